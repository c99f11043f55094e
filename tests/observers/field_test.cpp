// The adaptive observer field against its uniform dense twin on the same lattice.
#include "observers/field.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "pipeline/scene.h"
#include "pipeline/target_builder.h"

namespace glint {
namespace {

struct Case {
  std::string name;
  std::string json;
};

// A scene with an observer box; `material` and `objects` JSON spliced in.
std::string sceneJson(const std::string& beam, const std::string& material,
                      const std::string& objects, const std::string& observers) {
  return R"({"laser": {"position": [-100, 0, 0], "direction": [1, 0, 0], "power_w": 1000.0,
             "wavelength_nm": 1064, "beam": )" +
         beam + R"(}, "materials": {"m": )" + material + R"(}, "objects": [)" + objects +
         R"(], "observers": )" + observers + "}";
}

struct Comparison {
  double max_error_w_m2 = 0.0;
  double peak_w_m2 = 0.0;
  std::int64_t bright_skipped = 0;  // dense > 10 × floor but skipped in the adaptive field
  std::int64_t adaptive_evaluations = 0, dense_evaluations = 0;
  std::array<double, 3> volume_ratio{};  // adaptive / dense above 1 %, 10 %, 50 % of the peak
  double coarse_sample_max_w_m2 = 0.0;   // dense at the coarsest blocks' sample points
  FieldStats adaptive, dense;
};

Comparison compare(const std::string& json) {
  const Scene scene = parseScene(json, "test.json");
  const FieldSpec spec = fieldSpec(scene);
  const FacetIntegrator integrator(buildTarget(scene), beamOf(scene),
                                   fieldIntegratorOptions(scene, spec));
  const ExcludedFn excluded = excludedRegion(scene, 0.5 * spec.voxel_m);
  const ObserverField a = computeField(integrator, spec, excluded);
  const ObserverField d = computeDenseField(integrator, spec, excluded);
  Comparison c;
  c.adaptive = a.stats();
  c.dense = d.stats();
  c.peak_w_m2 = d.stats().peak_w_m2;
  const auto n = spec.nodes();
  for (int i = 0; i < n[0]; ++i)
    for (int j = 0; j < n[1]; ++j)
      for (int k = 0; k < n[2]; ++k) {
        if (d.status(i, j, k) != VoxelStatus::Evaluated) continue;
        const double e = d.irradiance(i, j, k);
        c.max_error_w_m2 = std::max(c.max_error_w_m2, std::abs(a.irradiance(i, j, k) - e));
        const int half = spec.block_voxels / 2;
        if (i % half == 0 && j % half == 0 && k % half == 0) {
          c.coarse_sample_max_w_m2 = std::max(c.coarse_sample_max_w_m2, e);
        }
        if (e > 10.0 * spec.floor_w_m2 && a.status(i, j, k) == VoxelStatus::BelowFloor) {
          ++c.bright_skipped;
        }
      }
  const std::array<double, 3> levels = {0.01, 0.1, 0.5};
  for (std::size_t l = 0; l < 3; ++l) {
    const double t = levels[l] * c.peak_w_m2;
    c.volume_ratio[l] = a.volumeAbove(t) / d.volumeAbove(t);
  }
  return c;
}

// The properties the issue asks of every scene: the error within the field's accuracy, the
// volumes above 1 %, 10 % and 50 % of the peak within 1 % of dense, and no voxel that dense
// finds above 10 × floor left uncomputed.
void expectMatchesDense(const Comparison& c, const FieldSpec& spec, const std::string& name) {
  ASSERT_GT(c.peak_w_m2, 100.0 * spec.floor_w_m2) << name << ": the scene must show a glint";
  EXPECT_LE(c.max_error_w_m2, spec.tolerance * c.peak_w_m2 + spec.floor_w_m2)
      << name << ": peak " << c.peak_w_m2;
  for (std::size_t l = 0; l < 3; ++l) {
    EXPECT_NEAR(c.volume_ratio[l], 1.0, 0.01) << name << ": volume above threshold " << l;
  }
  EXPECT_EQ(c.bright_skipped, 0) << name << ": voxels above 10 × floor proven negligible";
  // Pruned candidate lists may not make the integration fail where the full list succeeds.
  EXPECT_LE(c.adaptive.unconverged_points, c.dense.unconverged_points) << name;
}

FieldSpec specOf(const std::string& json) { return fieldSpec(parseScene(json, "test.json")); }

TEST(ObserverField, NarrowGlintBetweenCoarseSamplesIsFoundAsInDense) {
  // A 5 cm mirror at 45° sends a σ = 0.001 pencil along +y, 0.3 m off every coarse sample
  // plane (samples every 0.5 m): only the bound can tell the coarse blocks it is there.
  const std::string json = sceneJson(
      R"({"profile": "flat_top", "radius_m": 0.5})",
      R"({"specular_reflectance": 0.9, "sigma": 0.001})",
      R"({"shape": "disk", "center": [0.3, 0, 0.3], "normal": [-1, 1, 0], "radius": 0.05, "material": "m", "segments": 8})",
      R"({"min": [-1, 0.5, -1], "max": [1, 4.5, 1], "voxel_m": 0.0625, "block_m": 1.0,
          "tolerance": 0.01, "floor_w_m2": 1e-3})");
  const FieldSpec spec = specOf(json);
  const Comparison c = compare(json);
  expectMatchesDense(c, spec, "narrow glint");
  EXPECT_NEAR(c.adaptive.peak_w_m2, c.peak_w_m2, 1e-9 * c.peak_w_m2) << "the same peak point";
  // The premise: no sample of a coarse block (every 8th lattice point) sees the pencil.
  EXPECT_LT(c.coarse_sample_max_w_m2, spec.floor_w_m2) << "the glint must pass between samples";
  EXPECT_GT(c.adaptive.blocks_skipped, 0) << "most of the box is proven dark";
  EXPECT_LT(c.adaptive.evaluated_points, c.dense.evaluated_points / 4) << "and not computed";
}

// A 1 m cylinder lit across its axis, in a box around it, at lobe width σ.
std::string cylinderScene(double sigma) {
  return sceneJson(
      R"({"profile": "flat_top", "radius_m": 2.0})",
      R"({"specular_reflectance": 0.9, "sigma": )" + std::to_string(sigma) + "}",
      R"({"shape": "cylinder", "center": [0, 0, 0], "axis": [0, 0, 1], "radius": 0.5, "length": 1.0, "material": "m", "segments": 12})",
      R"({"min": [-3, -3, -1.5], "max": [3, 3, 1.5], "voxel_m": 0.25, "block_m": 1.0,
          "tolerance": 0.01, "floor_w_m2": 1e-2})");
}

TEST(ObserverField, CylinderNarrowLobeMatchesDense) {
  const std::string json = cylinderScene(0.003);
  expectMatchesDense(compare(json), specOf(json), "cylinder σ = 0.003");
}

TEST(ObserverField, CylinderBroadLobeMatchesDense) {
  const std::string json = cylinderScene(0.03);
  expectMatchesDense(compare(json), specOf(json), "cylinder σ = 0.03");
}

}  // namespace
}  // namespace glint
