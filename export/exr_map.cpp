#include "export/exr_map.h"

#include <ImathVec.h>
#include <ImfAttribute.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfOutputFile.h>
#include <ImfStandardAttributes.h>
#include <ImfStringAttribute.h>
#include <ImfVecAttribute.h>
#include <ImfDoubleAttribute.h>

#include <algorithm>
#include <stdexcept>

#include "export/atomic_file.h"

namespace glint {
namespace {

// OpenEXR writes through its own stream class: this one forwards to a std::ostream (the
// AtomicFile's), so an EXR appears whole or not at all like every other output.
class StdOStream final : public Imf::OStream {
 public:
  explicit StdOStream(std::ostream& out) : Imf::OStream("glint map"), out_(out) {}
  void write(const char c[], int n) override {
    out_.write(c, n);
    if (!out_) throw OutputError("writing the OpenEXR map failed");
  }
  uint64_t tellp() override { return static_cast<uint64_t>(out_.tellp()); }
  void seekp(uint64_t pos) override { out_.seekp(static_cast<std::streamoff>(pos)); }

 private:
  std::ostream& out_;
};

Imath::V3d v3d(const Vec3& v) { return {v.x, v.y, v.z}; }

}  // namespace

void writeExr(std::ostream& out, const PlaneMap& map, const ExrInfo& info) {
  const auto n = static_cast<std::size_t>(map.width) * static_cast<std::size_t>(map.height);
  if (map.width <= 0 || map.height <= 0 || map.irradiance_w_m2.size() != n ||
      map.hazard_ratio.size() != n || map.level.size() != n || map.status.size() != n) {
    throw std::invalid_argument("writeExr: every channel must hold width × height values");
  }
  Imf::Header header(map.width, map.height);
  header.compression() = Imf::ZIP_COMPRESSION;
  const char* names[] = {"irradiance_w_m2", "hazard_ratio", "level", "status"};
  for (const char* name : names) header.channels().insert(name, Imf::Channel(Imf::FLOAT));
  header.insert("glint_origin_m", Imf::V3dAttribute(v3d(map.origin_m)));
  header.insert("glint_u_axis", Imf::V3dAttribute(v3d(map.u_axis)));
  header.insert("glint_v_axis", Imf::V3dAttribute(v3d(map.v_axis)));
  header.insert("glint_pixel_m", Imf::DoubleAttribute(map.pixel_m));
  header.insert("glint_wavelength_nm", Imf::DoubleAttribute(info.wavelength_nm));
  header.insert("glint_mpe_w_m2", Imf::DoubleAttribute(info.mpe_w_m2));
  header.insert("glint_program", Imf::StringAttribute(info.program_version));

  // Image row y holds lattice row j = height − 1 − y.
  const std::vector<float>* channels[] = {&map.irradiance_w_m2, &map.hazard_ratio, &map.level,
                                          &map.status};
  std::vector<std::vector<float>> rows_down(4, std::vector<float>(n));
  Imf::FrameBuffer frame;
  const auto w = static_cast<std::size_t>(map.width);
  for (std::size_t c = 0; c < 4; ++c) {
    for (std::size_t y = 0; y < static_cast<std::size_t>(map.height); ++y) {
      const std::size_t j = static_cast<std::size_t>(map.height) - 1 - y;
      std::copy_n(channels[c]->begin() + static_cast<std::ptrdiff_t>(j * w), w,
                  rows_down[c].begin() + static_cast<std::ptrdiff_t>(y * w));
    }
    frame.insert(names[c], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(rows_down[c].data()),
                                      sizeof(float), sizeof(float) * w));
  }
  StdOStream stream(out);
  Imf::OutputFile file(stream, header);
  file.setFrameBuffer(frame);
  file.writePixels(map.height);
}

}  // namespace glint
