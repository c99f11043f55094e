// The OpenEXR map writer, read back with OpenEXR itself.
#include "export/exr_map.h"

#include <ImfChannelList.h>
#include <ImfDoubleAttribute.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfStringAttribute.h>
#include <ImfVecAttribute.h>
#include <gtest/gtest.h>

#include <cstring>
#include <sstream>

namespace glint {
namespace {

// Reads an EXR from memory.
class MemoryIStream final : public Imf::IStream {
 public:
  explicit MemoryIStream(std::string bytes) : Imf::IStream("memory"), bytes_(std::move(bytes)) {}
  bool read(char c[], int n) override {
    if (pos_ + static_cast<std::size_t>(n) > bytes_.size()) throw std::runtime_error("past end");
    std::memcpy(c, bytes_.data() + pos_, static_cast<std::size_t>(n));
    pos_ += static_cast<std::size_t>(n);
    return pos_ < bytes_.size();
  }
  uint64_t tellg() override { return pos_; }
  void seekg(uint64_t pos) override { pos_ = pos; }

 private:
  std::string bytes_;
  std::size_t pos_ = 0;
};

TEST(ExrMap, ChannelsAreFloatAndKeepValuesBeyondHalfRange) {
  PlaneMap map;
  map.width = 3;
  map.height = 2;
  map.origin_m = Vec3(1.0, 2.0, 1.7);
  map.u_axis = Vec3(1.0, 0.0, 0.0);
  map.v_axis = Vec3(0.0, 0.6, 0.8);
  map.pixel_m = 0.25;
  // 1.5e6 W/m² and 3e-9: far outside HALF (max 65504, smallest normal 6.1e-5).
  map.irradiance_w_m2 = {1.5e6f, 2.0f, 3e-9f, 4.0f, 70000.0f, 6.0f};
  for (float e : map.irradiance_w_m2) map.hazard_ratio.push_back(e / 25.0f);
  map.level = {0, 1, 2, 3, 4, 5};
  map.status = {1, 2, 3, 1, 1, 5};
  std::ostringstream out;
  writeExr(out, map, {"glint test", 532.0, 25.0, "ANSI Z136.1-2014 Table 5a: test row"});

  MemoryIStream in(out.str());
  Imf::InputFile file(in);
  const Imf::Header& h = file.header();
  const Imath::Box2i window = h.dataWindow();
  ASSERT_EQ(window.max.x - window.min.x + 1, 3);
  ASSERT_EQ(window.max.y - window.min.y + 1, 2);
  for (const char* name : {"irradiance_w_m2", "hazard_ratio", "level", "status"}) {
    const Imf::Channel* c = h.channels().findChannel(name);
    ASSERT_NE(c, nullptr) << name;
    EXPECT_EQ(c->type, Imf::FLOAT) << name << ": never HALF";
  }
  std::vector<float> irradiance(6), ratio(6), level(6), status(6);
  Imf::FrameBuffer frame;
  frame.insert("irradiance_w_m2", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(irradiance.data()),
                                             sizeof(float), 3 * sizeof(float)));
  frame.insert("hazard_ratio", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(ratio.data()),
                                          sizeof(float), 3 * sizeof(float)));
  frame.insert("level", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(level.data()), sizeof(float),
                                   3 * sizeof(float)));
  frame.insert("status", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(status.data()),
                                    sizeof(float), 3 * sizeof(float)));
  file.setFrameBuffer(frame);
  file.readPixels(window.min.y, window.max.y);
  // The top image row is the plane's highest v (lattice row 1).
  for (int y = 0; y < 2; ++y)
    for (int i = 0; i < 3; ++i) {
      const std::size_t image = static_cast<std::size_t>(3 * y + i);
      const std::size_t lattice = static_cast<std::size_t>(3 * (1 - y) + i);
      EXPECT_EQ(irradiance[image], map.irradiance_w_m2[lattice])
          << "bit for bit, " << i << "," << y;
      EXPECT_EQ(ratio[image], map.hazard_ratio[lattice]) << i << "," << y;
      EXPECT_EQ(level[image], map.level[lattice]) << i << "," << y;
      EXPECT_EQ(status[image], map.status[lattice]) << i << "," << y;
    }
  const auto* origin = h.findTypedAttribute<Imf::V3dAttribute>("glint_origin_m");
  ASSERT_NE(origin, nullptr);
  EXPECT_EQ(origin->value(), Imath::V3d(1.0, 2.0, 1.7));
  const auto* v = h.findTypedAttribute<Imf::V3dAttribute>("glint_v_axis");
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(v->value(), Imath::V3d(0.0, 0.6, 0.8));
  const auto* pixel = h.findTypedAttribute<Imf::DoubleAttribute>("glint_pixel_m");
  ASSERT_NE(pixel, nullptr);
  EXPECT_EQ(pixel->value(), 0.25);
  const auto* mpe = h.findTypedAttribute<Imf::DoubleAttribute>("glint_mpe_w_m2");
  ASSERT_NE(mpe, nullptr);
  EXPECT_EQ(mpe->value(), 25.0);
  const auto* program = h.findTypedAttribute<Imf::StringAttribute>("glint_program");
  ASSERT_NE(program, nullptr);
  EXPECT_EQ(program->value(), "glint test");
}

TEST(ExrMap, RefusesChannelsOfTheWrongSize) {
  PlaneMap map;
  map.width = 2;
  map.height = 2;
  map.irradiance_w_m2 = {1, 2, 3};
  map.hazard_ratio = {1, 2, 3, 4};
  map.level = {1, 2, 3, 4};
  map.status = {1, 1, 1, 1};
  std::ostringstream out;
  EXPECT_THROW(writeExr(out, map, {}), std::invalid_argument) << "3 irradiance values for 4 points";
}

}  // namespace
}  // namespace glint
