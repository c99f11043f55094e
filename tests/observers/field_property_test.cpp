// A randomized property of the adaptive observer field: whatever the scene, it never misses
// what its dense twin finds. Small mirrors, spheres and cylinders are placed anywhere in or
// near the coarse blocks of a small box, under narrow Gaussian and wide flat-top beams from
// any direction, with lobes from σ = 0.001 to 0.03. Seeds are fixed, so a failure names a
// scene that can be rerun; the generator is a hand-written SplitMix64, whose sequence (unlike
// the standard library's distributions) is the same everywhere.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>

#include "observers/field.h"
#include "observers/field_compare.h"
#include "pipeline/input/scene.h"
#include "pipeline/setup/target_builder.h"

namespace glint {
namespace {

class SplitMix64 {
 public:
  explicit SplitMix64(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  double uniform(double lo, double hi) {
    return lo + (hi - lo) * static_cast<double>(next() >> 11) * 0x1.0p-53;
  }
  double logUniform(double lo, double hi) { return std::exp(uniform(std::log(lo), std::log(hi))); }
  Vec3 direction() {  // uniform on the sphere
    const double z = uniform(-1.0, 1.0), phi = uniform(0.0, 2.0 * kPi);
    const double s = std::sqrt(1.0 - z * z);
    return {s * std::cos(phi), s * std::sin(phi), z};
  }

 private:
  std::uint64_t state_;
};

std::string vec(const Vec3& v) {
  std::ostringstream s;
  s.precision(17);
  s << "[" << v.x << ", " << v.y << ", " << v.z << "]";
  return s.str();
}

// The box: one coarse block of 1.6 m at 0.2 m voxels (9³ lattice points, samples every 0.8 m
// and the octant centres between): coarse, so that 36 scenes and their dense twins run in
// seconds, and every object and pencil is small against the block. (At 0.8 m blocks every
// scene passed even before the fix of issue 14: their samples were too close to miss.)
constexpr double kBoxM = 1.6;

struct RandomScene {
  std::string json;
  std::string about;  // for failure messages
};

RandomScene randomScene(std::uint64_t seed) {
  SplitMix64 rng(seed);
  std::ostringstream about, objects;
  about.precision(3);
  objects.precision(17);
  // Anywhere in the box or up to 0.2 m outside it.
  const Vec3 centre(rng.uniform(-0.2, kBoxM + 0.2), rng.uniform(-0.2, kBoxM + 0.2),
                    rng.uniform(-0.2, kBoxM + 0.2));
  const Vec3 dir = rng.direction();
  const double sigma = rng.logUniform(0.001, 0.03);
  switch (seed % 3) {
    case 0: {  // a small one-sided mirror facing the laser at up to ~78°
      const double radius = rng.uniform(0.03, 0.15);
      Vec3 n = rng.direction();
      if (glm::dot(n, -dir) < 0.0) n = -n;
      n = glm::normalize(n - dir * 0.2);
      objects << R"({"shape": "disk", "center": )" << vec(centre) << R"(, "normal": )" << vec(n)
              << R"(, "radius": )" << radius << R"(, "material": "m"})";
      about << "disk R " << radius;
      break;
    }
    case 1: {
      const double radius = rng.uniform(0.05, 0.3);
      objects << R"({"shape": "sphere", "center": )" << vec(centre) << R"(, "radius": )" << radius
              << R"(, "material": "m"})";
      about << "sphere R " << radius;
      break;
    }
    default: {
      const double radius = rng.uniform(0.03, 0.2), length = rng.uniform(0.1, 0.8);
      objects << R"({"shape": "cylinder", "center": )" << vec(centre) << R"(, "axis": )"
              << vec(rng.direction()) << R"(, "radius": )" << radius << R"(, "length": )" << length
              << R"(, "material": "m"})";
      about << "cylinder R " << radius << " L " << length;
      break;
    }
  }
  // Narrow Gaussian beams (the mirror's pencil, a spot on a curved target) and wide flat-tops
  // (the whole target lit, beam edges beyond it), aimed within half a radius of the centre.
  const bool narrow = (seed / 3) % 2 == 0;
  const double beam_radius = narrow ? rng.uniform(0.05, 0.15) : rng.uniform(0.5, 2.0);
  Vec3 side = glm::cross(dir, rng.direction());
  side = glm::length(side) > 1e-6 ? glm::normalize(side) : Vec3(0.0);
  const Vec3 laser = centre - 100.0 * dir + 0.5 * beam_radius * rng.uniform(0.0, 1.0) * side;
  // Peak beam irradiance 1e4 W/m²: the glints stand well above the floor (1e-3 × MPE).
  const double power = 1e4 * kPi * beam_radius * beam_radius / (narrow ? 2.0 : 1.0);
  std::ostringstream json;
  json.precision(17);
  json << R"({"laser": {"position": )" << vec(laser) << R"(, "direction": )" << vec(dir)
       << R"(, "power_w": )" << power << R"(, "wavelength_nm": 1064, "exposure_s": 0.25,
       "beam": {"profile": ")"
       << (narrow ? "gaussian\", \"w_m\": " : "flat_top\", \"radius_m\": ") << beam_radius
       << R"(}}, "materials": {"m": {"specular_reflectance": 0.9, "sigma": )" << sigma
       << R"(}}, "objects": [)" << objects.str() << R"(],
       "observers": {"min": [0, 0, 0], "max": [1.6, 1.6, 1.6], "voxel_m": 0.2, "block_m": 1.6}})";
  about << " at " << vec(centre) << ", σ " << sigma << ", "
        << (narrow ? "Gaussian w " : "flat top r ") << beam_radius;
  return {json.str(), about.str()};
}

// What the adaptive field got wrong against dense, point by point.
struct Misses {
  std::int64_t bright_below_floor = 0;  // dense > 10 × floor, adaptive status 3
  std::int64_t interpolated_off = 0;    // interpolated beyond tolerance × peak + floor
  double worst_w_m2 = 0.0;
  Vec3 worst_at_m{0.0};
};

Misses missesOf(const ObserverField& adaptive, const ObserverField& dense) {
  const FieldSpec& spec = dense.spec();
  const double allowed = spec.tolerance * dense.stats().peak_w_m2 + spec.floor_w_m2;
  Misses m;
  const auto n = spec.nodes();
  for (int i = 0; i < n[0]; ++i)
    for (int j = 0; j < n[1]; ++j)
      for (int k = 0; k < n[2]; ++k) {
        if (!integratedHere(dense.status(i, j, k))) continue;
        const double d = dense.irradiance(i, j, k);
        const VoxelStatus s = adaptive.status(i, j, k);
        if (d > 10.0 * spec.floor_w_m2 && s == VoxelStatus::BelowFloor) ++m.bright_below_floor;
        const double error = std::abs(adaptive.irradiance(i, j, k) - d);
        if (s == VoxelStatus::Interpolated && !(error <= allowed)) ++m.interpolated_off;
        if (error > m.worst_w_m2) {
          m.worst_w_m2 = error;
          m.worst_at_m = spec.position(i, j, k);
        }
      }
  return m;
}

constexpr std::uint64_t kScenes = 36;

TEST(ObserverFieldProperty, AdaptiveNeverMissesWhatDenseFinds) {
  int with_glint = 0;
  for (std::uint64_t seed = 0; seed < kScenes; ++seed) {
    const RandomScene rs = randomScene(seed);
    const Scene scene = parseScene(rs.json, "random.json");
    const FieldSpec spec = fieldSpec(scene);
    const FieldProblem p = fieldProblem(scene, spec);
    const ObserverField a = computeField(p.integrator, spec, p.excluded);
    const ObserverField d = computeDenseField(p.integrator, spec, p.excluded);
    const FieldComparison c = compareFields(a, d);
    const Misses m = missesOf(a, d);
    const std::string name = "seed " + std::to_string(seed) + ": " + rs.about;
    with_glint += c.peak_w_m2 > 100.0 * spec.floor_w_m2 ? 1 : 0;
    EXPECT_EQ(m.bright_below_floor, 0) << name << ": points above 10 × floor proven dark";
    EXPECT_EQ(m.interpolated_off, 0) << name << ": interpolated beyond tolerance × peak + floor";
    EXPECT_LE(c.max_error_w_m2, c.allowed_error_w_m2)
        << name << ": peak " << c.peak_w_m2 << " W/m², worst " << m.worst_w_m2 << " at "
        << vec(m.worst_at_m);
  }
  // The premise: most scenes send a glint through the box (the others check that darkness is
  // proven, not assumed, which matters as much).
  EXPECT_GE(with_glint, static_cast<int>(kScenes) / 2) << "scenes with a glint in the box";
}

}  // namespace
}  // namespace glint
