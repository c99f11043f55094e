#include "export/exr_map.h"

#include <IexBaseExc.h>
#include <ImathVec.h>
#include <ImfAttribute.h>
#include <ImfChannelList.h>
#include <ImfDoubleAttribute.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStandardAttributes.h>
#include <ImfStringAttribute.h>
#include <ImfVecAttribute.h>

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

namespace {

// Writes @p channels (width × height values each, row j = 0 at the bottom) into a scanline
// EXR whose header already holds glint's attributes.
void writeChannels(std::ostream& out, Imf::Header& header, int width, int height,
                   const std::vector<ExrChannel>& channels, const ExrInfo& info) {
  const auto n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (width <= 0 || height <= 0 || channels.empty()) {
    throw std::invalid_argument("writeExr: an empty map");
  }
  for (const ExrChannel& c : channels) {
    if (c.values == nullptr || c.values->size() != n)
      throw std::invalid_argument("writeExr: channel " + c.name +
                                  " must hold width × height values");
  }
  header.compression() = Imf::ZIP_COMPRESSION;
  for (const ExrChannel& c : channels) header.channels().insert(c.name, Imf::Channel(Imf::FLOAT));
  header.insert("glint_wavelength_nm", Imf::DoubleAttribute(info.wavelength_nm));
  header.insert("glint_mpe_w_m2", Imf::DoubleAttribute(info.mpe_w_m2));
  header.insert("glint_program", Imf::StringAttribute(info.program_version));
  if (!info.mpe_rule.empty()) header.insert("glint_mpe_rule", Imf::StringAttribute(info.mpe_rule));

  // Image row y holds lattice row j = height − 1 − y.
  std::vector<std::vector<float>> rows_down(channels.size(), std::vector<float>(n));
  Imf::FrameBuffer frame;
  const auto w = static_cast<std::size_t>(width);
  for (std::size_t c = 0; c < channels.size(); ++c) {
    for (std::size_t y = 0; y < static_cast<std::size_t>(height); ++y) {
      const std::size_t j = static_cast<std::size_t>(height) - 1 - y;
      std::copy_n(channels[c].values->begin() + static_cast<std::ptrdiff_t>(j * w), w,
                  rows_down[c].begin() + static_cast<std::ptrdiff_t>(y * w));
    }
    frame.insert(channels[c].name,
                 Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(rows_down[c].data()), sizeof(float),
                            sizeof(float) * w));
  }
  StdOStream stream(out);
  Imf::OutputFile file(stream, header);
  file.setFrameBuffer(frame);
  file.writePixels(height);
}

}  // namespace

void writeExr(std::ostream& out, const PlaneGrid& grid, const std::vector<ExrChannel>& channels,
              const ExrInfo& info) {
  Imf::Header header(std::max(grid.width, 1), std::max(grid.height, 1));
  header.insert("glint_origin_m", Imf::V3dAttribute(v3d(grid.origin_m)));
  header.insert("glint_u_axis", Imf::V3dAttribute(v3d(grid.u_axis)));
  header.insert("glint_v_axis", Imf::V3dAttribute(v3d(grid.v_axis)));
  header.insert("glint_pixel_m", Imf::DoubleAttribute(grid.pixel_m));
  writeChannels(out, header, grid.width, grid.height, channels, info);
}

void writeLatLongExr(std::ostream& out, const LatLongGrid& grid,
                     const std::vector<ExrChannel>& channels, const ExrInfo& info) {
  Imf::Header header(std::max(grid.width, 1), std::max(grid.height, 1));
  header.insert("glint_projection",
                Imf::StringAttribute("lat-long: column i at azimuth -180 + (i + 0.5) 360 / width "
                                     "degrees from +x toward +y; row j from the bottom at "
                                     "elevation -90 + (j + 0.5) 180 / height degrees toward +z"));
  header.insert("glint_centre_m", Imf::V3dAttribute(v3d(grid.centre_m)));
  header.insert("glint_far_radius_m", Imf::DoubleAttribute(grid.far_radius_m));
  writeChannels(out, header, grid.width, grid.height, channels, info);
}

void writeExr(std::ostream& out, const PlaneMap& map, const ExrInfo& info) {
  std::vector<ExrChannel> channels = {{"irradiance_w_m2", &map.irradiance_w_m2},
                                      {"hazard_ratio", &map.hazard_ratio}};
  if (!map.aided_hazard_ratio.empty()) {
    channels.push_back({"aided_hazard_ratio", &map.aided_hazard_ratio});
  }
  for (const auto& [name, values] : map.level_ratios) channels.push_back({name, &values});
  if (!map.irradiance_upper_w_m2.empty())
    channels.push_back({"irradiance_upper_w_m2", &map.irradiance_upper_w_m2});
  channels.push_back({"level", &map.level});
  channels.push_back({"status", &map.status});
  if (!map.observer_z_m.empty()) channels.push_back({"observer_z_m", &map.observer_z_m});
  writeExr(out, static_cast<const PlaneGrid&>(map), channels, info);
}

std::vector<float> readExrChannel(const std::string& path, const std::string& name, int& width,
                                  int& height) {
  try {
    Imf::InputFile file(path.c_str());
    const Imath::Box2i window = file.header().dataWindow();
    width = window.max.x - window.min.x + 1;
    height = window.max.y - window.min.y + 1;
    const Imf::Channel* channel = file.header().channels().findChannel(name);
    if (channel == nullptr || channel->type != Imf::FLOAT || width <= 0 || height <= 0)
      throw std::runtime_error(path + ": no FLOAT channel " + name);
    const auto w = static_cast<std::size_t>(width);
    std::vector<float> rows_down(w * static_cast<std::size_t>(height));
    Imf::FrameBuffer frame;
    // The slice's base is offset so that data-window pixel (min.x, min.y) lands at index 0.
    char* base = reinterpret_cast<char*>(rows_down.data()) -
                 (static_cast<std::ptrdiff_t>(window.min.x) +
                  static_cast<std::ptrdiff_t>(window.min.y) * static_cast<std::ptrdiff_t>(w)) *
                     static_cast<std::ptrdiff_t>(sizeof(float));
    frame.insert(name, Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * w));
    file.setFrameBuffer(frame);
    file.readPixels(window.min.y, window.max.y);
    std::vector<float> out(rows_down.size());
    for (std::size_t y = 0; y < static_cast<std::size_t>(height); ++y) {
      const std::size_t j = static_cast<std::size_t>(height) - 1 - y;
      std::copy_n(rows_down.begin() + static_cast<std::ptrdiff_t>(y * w), w,
                  out.begin() + static_cast<std::ptrdiff_t>(j * w));
    }
    return out;
  } catch (const Iex::BaseExc& e) {
    throw std::runtime_error(path + ": cannot read the OpenEXR map: " + e.what());
  }
}

}  // namespace glint
