// The adaptive observer field against its uniform dense twin on the same lattice.
#include "observers/field.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "hazard/hazard.h"
#include "observers/detail/field_common.h"
#include "observers/far_field.h"
#include "observers/field_compare.h"
#include "pipeline/input/scene.h"
#include "pipeline/setup/target_builder.h"

namespace glint {
namespace {

struct Case {
  std::string name;
  std::string json;
};

// A scene whose observers are `observers_key`: `observers`; beam, material and objects JSON
// spliced in.
std::string sceneWith(const std::string& beam, const std::string& material,
                      const std::string& objects, const std::string& observers_key,
                      const std::string& observers) {
  return R"({"laser": {"position": [-100, 0, 0], "direction": [1, 0, 0], "power_w": 1000.0,
             "wavelength_nm": 1064, "beam": )" +
         beam + R"(}, "materials": {"m": )" + material + R"(}, "objects": [)" + objects +
         R"(], ")" + observers_key + R"(": )" + observers + "}";
}

// A scene with an observer box.
std::string sceneJson(const std::string& beam, const std::string& material,
                      const std::string& objects, const std::string& observers) {
  return sceneWith(beam, material, objects, "observers", observers);
}

struct Comparison {
  FieldComparison fields;
  double coarse_sample_max_w_m2 = 0.0;  // dense at the coarsest blocks' sample points
  FieldStats adaptive, dense;
};

// The adaptive field and its dense twin over `spec` (the scene's box or one of its planes).
Comparison compare(const Scene& scene, const FieldSpec& spec) {
  const FieldProblem p = fieldProblem(scene, spec);
  const ObserverField a = computeField(p.integrator, spec, p.excluded);
  const ObserverField d = computeDenseField(p.integrator, spec, p.excluded);
  Comparison c;
  c.fields = compareFields(a, d);
  c.adaptive = a.stats();
  c.dense = d.stats();
  const auto n = spec.nodes();
  const int half = spec.block_voxels / 2;
  for (int i = 0; i < n[0]; i += half)
    for (int j = 0; j < n[1]; j += half)
      for (int k = 0; k < n[2]; k += half) {
        c.coarse_sample_max_w_m2 = std::max(c.coarse_sample_max_w_m2, d.irradiance(i, j, k));
      }
  return c;
}

Comparison compare(const std::string& json) {
  const Scene scene = parseScene(json, "test.json");
  return compare(scene, fieldSpec(scene));
}

// The properties the issue asks of every scene: the error within the field's accuracy, the
// volumes above 1 %, 10 % and 50 % of the peak within 1 % of dense, and no voxel that dense
// finds above 10 × floor left uncomputed.
void expectMatchesDense(const Comparison& c, const FieldSpec& spec, const std::string& name) {
  const FieldComparison& f = c.fields;
  ASSERT_GT(f.peak_w_m2, 100.0 * spec.floor_w_m2) << name << ": the scene must show a glint";
  EXPECT_LE(f.max_error_w_m2, f.allowed_error_w_m2)
      << name << ": peak " << f.peak_w_m2 << ", worst at (" << f.max_error_at_m.x << ", "
      << f.max_error_at_m.y << ", " << f.max_error_at_m.z << ")";
  for (std::size_t t = 0; t < f.threshold_shares.size(); ++t) {
    EXPECT_NEAR(f.volumeRatio(t), 1.0, 0.01)
        << name << ": volume above " << f.threshold_shares[t] << " of the peak";
  }
  EXPECT_EQ(f.bright_skipped, 0) << name << ": voxels above 10 × floor proven negligible";
  EXPECT_TRUE(f.withinAccuracy()) << name;
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
  EXPECT_NEAR(c.adaptive.peak_w_m2, c.fields.peak_w_m2, 1e-9 * c.fields.peak_w_m2)
      << "the same peak point";
  // The premise: no sample of a coarse block (every 8th lattice point) sees the pencil.
  EXPECT_LT(c.coarse_sample_max_w_m2, spec.floor_w_m2) << "the glint must pass between samples";
  EXPECT_GT(c.adaptive.blocks_skipped, 0) << "most of the box is proven dark";
  EXPECT_LT(c.adaptive.evaluated_points, c.dense.evaluated_points / 4) << "and not computed";
}

// A one-sided mirror of R 0.125 m and σ = 0.001 under a 2.5 W Gaussian beam (w 0.1 m) at
// 532 nm sends a pencil about 0.25 m wide up and across a box of 0.1 m voxels. The mirror sits
// inside the first coarse block of 1.6 m, between its samples; the pencil crosses the block
// for about 1.1 m before it meets any. The block's ball reaches the mirror, so its bound is
// +∞: once summed with compensation as ∞ − ∞ = NaN, which neither the skip test nor the
// narrow-glint guard could see, and the block was interpolated from samples that all read 0.
std::string mirrorInBlockScene(const std::string& observers_key, const std::string& observers) {
  return R"({"laser": {"position": [-100, 0.6, 0.6], "direction": [1, 0, 0], "power_w": 2.5,
             "wavelength_nm": 532, "exposure_s": 0.25,
             "beam": {"profile": "gaussian", "w_m": 0.1}},
    "materials": {"mirror": {"specular_reflectance": 0.9, "sigma": 0.001}},
    "objects": [{"shape": "disk", "center": [0.6, 0.6, 0.6], "normal": [-1, 1, 0.5],
                 "radius": 0.125, "material": "mirror"}], ")" +
         observers_key + R"(": )" + observers + "}";
}

// Hazard points of the dense field (ratio ≥ 1.05) that the adaptive field reads below the MPE,
// and the counts of points at ratio ≥ 1 in each.
struct HazardAgreement {
  std::int64_t missed = 0, adaptive_hazardous = 0, dense_hazardous = 0;
};
HazardAgreement hazardAgreement(const ObserverField& adaptive, const ObserverField& dense,
                                double mpe_w_m2) {
  HazardAgreement h;
  const auto n = dense.spec().nodes();
  for (int i = 0; i < n[0]; ++i)
    for (int j = 0; j < n[1]; ++j)
      for (int k = 0; k < n[2]; ++k) {
        const double d = dense.irradiance(i, j, k) / mpe_w_m2;
        const double a = adaptive.irradiance(i, j, k) / mpe_w_m2;
        h.dense_hazardous += d >= 1.0 ? 1 : 0;
        h.adaptive_hazardous += a >= 1.0 ? 1 : 0;
        h.missed += d >= 1.05 && !(a >= 1.0) ? 1 : 0;
      }
  return h;
}

TEST(ObserverField, MirrorInsideACoarseBlockIsRefinedNotInterpolatedAway) {
  const std::string json = mirrorInBlockScene(
      "observers", R"({"min": [0, 0, 0], "max": [3.2, 3.2, 3.2], "voxel_m": 0.1, "block_m": 1.6})");
  const Scene scene = parseScene(json, "test.json");
  const FieldSpec spec = fieldSpec(scene);
  ASSERT_EQ(spec.block_voxels, 16);
  const FieldProblem p = fieldProblem(scene, spec);
  const ObserverField a = computeField(p.integrator, spec, p.excluded);
  const ObserverField d = computeDenseField(p.integrator, spec, p.excluded);
  const double mpe = scene.hazard.mpe_w_m2;
  ASSERT_NEAR(mpe, 25.46, 0.01) << "532 nm for 0.25 s";
  const HazardAgreement h = hazardAgreement(a, d, mpe);
  // The premise: a hazardous pencil, and the block that holds the mirror sees none of it at
  // its samples (lattice points 0, 8, 16 per axis and the octant centres 4, 12).
  ASSERT_GT(d.stats().peak_w_m2, 5.0 * mpe) << "peak hazard ratio about 5.6";
  ASSERT_GT(h.dense_hazardous, 50);
  double block_samples_max = 0.0;
  for (int i = 0; i <= 16; i += 4)
    for (int j = 0; j <= 16; j += 4)
      for (int k = 0; k <= 16; k += 4) {
        const bool octant_centre = i % 8 == 4 && j % 8 == 4 && k % 8 == 4;
        const bool lattice = i % 8 == 0 && j % 8 == 0 && k % 8 == 0;
        if (octant_centre || lattice) {
          block_samples_max = std::max(block_samples_max, d.irradiance(i, j, k));
        }
      }
  EXPECT_LT(block_samples_max, spec.floor_w_m2) << "the pencil passes between the samples";

  EXPECT_EQ(h.missed, 0) << "dense points at hazard ratio ≥ 1.05 read below 1: dense "
                         << h.dense_hazardous << " hazardous points, adaptive "
                         << h.adaptive_hazardous;
  EXPECT_EQ(h.adaptive_hazardous, h.dense_hazardous);
  EXPECT_NEAR(a.stats().peak_w_m2, d.stats().peak_w_m2, 1e-9 * d.stats().peak_w_m2)
      << "the true peak, near the mirror, is in the adaptive grid";
  Comparison c;
  c.fields = compareFields(a, d);
  c.adaptive = a.stats();
  c.dense = d.stats();
  expectMatchesDense(c, spec, "mirror inside a coarse block");
  EXPECT_LT(c.adaptive.evaluated_points, c.dense.evaluated_points / 4) << "still adaptive";
}

TEST(ObserverPlane, PlaneThroughASmallMirrorIsRefinedAroundIt) {
  // The same mirror, a ground plane at the mirror's height: the coarse square that holds the
  // mirror has a ball that reaches it, so it must be refined, never interpolated.
  const std::string json = mirrorInBlockScene(
      "planes", R"([{"name": "slice", "origin": [0, 0, 0.65], "u_axis": [1, 0, 0],
                     "v_axis": [0, 1, 0], "size_m": [3.2, 3.2], "pixel_m": 0.05,
                     "block_m": 1.6}])");
  const Scene scene = parseScene(json, "test.json");
  const FieldSpec spec = planeFieldSpec(scene, scene.planes.at(0));
  const FieldProblem p = fieldProblem(scene, spec);
  const ObserverField a = computeField(p.integrator, spec, p.excluded);
  const ObserverField d = computeDenseField(p.integrator, spec, p.excluded);
  const HazardAgreement h = hazardAgreement(a, d, scene.hazard.mpe_w_m2);
  ASSERT_GT(h.dense_hazardous, 10) << "the premise: the pencil crosses the slice";
  EXPECT_EQ(h.missed, 0) << "dense " << h.dense_hazardous << ", adaptive " << h.adaptive_hazardous;
  Comparison c;
  c.fields = compareFields(a, d);
  c.adaptive = a.stats();
  c.dense = d.stats();
  expectMatchesDense(c, spec, "slice through the mirror");
}

// A 1 m cylinder lit across its axis by a beam that covers it, at lobe width σ, seen from the
// box `observers`.
std::string cylinderSceneWith(double sigma, const std::string& observers) {
  return sceneJson(
      R"({"profile": "flat_top", "radius_m": 2.0})",
      R"({"specular_reflectance": 0.9, "sigma": )" + std::to_string(sigma) + "}",
      R"({"shape": "cylinder", "center": [0, 0, 0], "axis": [0, 0, 1], "radius": 0.5, "length": 1.0, "material": "m", "segments": 12})",
      observers);
}

// The same in a box around it.
std::string cylinderScene(double sigma) {
  return cylinderSceneWith(sigma, R"({"min": [-3, -3, -1.5], "max": [3, 3, 1.5], "voxel_m": 0.25,
                                      "block_m": 1.0, "tolerance": 0.01, "floor_w_m2": 1e-2})");
}

TEST(ObserverField, CylinderNarrowLobeMatchesDense) {
  const std::string json = cylinderScene(0.003);
  expectMatchesDense(compare(json), specOf(json), "cylinder σ = 0.003");
}

TEST(ObserverField, CylinderBroadLobeMatchesDense) {
  const std::string json = cylinderScene(0.03);
  expectMatchesDense(compare(json), specOf(json), "cylinder σ = 0.03");
}

TEST(ObserverField, RimStepIsResolvedAcrossItselfAndInterpolatedAlongIt) {
  // The σ = 0.003 sheet of a 1 m cylinder ends at its rims, z = ±0.5, within a centimetre: a
  // step across z that is level along x and y. Halving only the axes whose samples bend
  // resolves it in blocks thin across the step and whole along it; the first versions' octree
  // halved every axis down to single voxels there. Both must match dense; the anisotropic
  // field must do it with fewer points, and no more points than the octree anywhere.
  const std::string json =
      cylinderSceneWith(0.003, R"({"min": [-6, -2, 0], "max": [-2, 2, 1], "voxel_m": 0.125,
                                   "block_m": 1.0, "tolerance": 0.01, "floor_w_m2": 1e-2})");
  const Scene scene = parseScene(json, "test.json");
  FieldSpec spec = fieldSpec(scene);
  ASSERT_TRUE(spec.anisotropic) << "the default";
  const Comparison anisotropic = compare(scene, spec);
  expectMatchesDense(anisotropic, spec, "anisotropic");
  spec.anisotropic = false;
  const Comparison octree = compare(scene, spec);
  expectMatchesDense(octree, spec, "octree");
  EXPECT_LT(2 * anisotropic.adaptive.evaluated_points, octree.adaptive.evaluated_points)
      << "anisotropic " << anisotropic.adaptive.evaluated_points << " points, octree "
      << octree.adaptive.evaluated_points;
  std::printf("rim step: %lld points evaluated (octree %lld, dense %lld)\n",
              static_cast<long long>(anisotropic.adaptive.evaluated_points),
              static_cast<long long>(octree.adaptive.evaluated_points),
              static_cast<long long>(anisotropic.dense.evaluated_points));
}

TEST(ObserverField, LobeEdgeOnAMiddleSamplePlaneIsResolved) {
  // The σ = 0.003 fan of a 1 m cylinder stops at z = ±0.5 within a centimetre: a step. Blocks
  // of 1 m from z = −1 put it exactly on their middle sample plane, where the sample is half
  // the step and corners, mid-samples and all look linear. Only the octant centres see it
  // (without them: error 1.06 W/m² against 0.11 allowed, volume above 1 % 14 % too large).
  const std::string json =
      cylinderSceneWith(0.003, R"({"min": [-6, -2, -1], "max": [-2, 2, 1], "voxel_m": 0.25,
                                   "block_m": 1.0, "tolerance": 0.01, "floor_w_m2": 1e-2})");
  const FieldSpec spec = specOf(json);
  ASSERT_EQ(spec.block_voxels, 4);
  ASSERT_DOUBLE_EQ(spec.position(0, 0, spec.block_voxels / 2).z, -0.5) << "the premise";
  expectMatchesDense(compare(json), spec, "lobe edge on a sample plane");
}

TEST(ObserverField, RegionAboveAThresholdIsEveryLatticePointReachingIt) {
  // The nominal hazard zone is exceedance(MPE): checked here against a plain scan of every
  // lattice point through the public accessors, at a threshold of a fifth of the peak.
  const std::string json = cylinderScene(0.03);
  const Scene scene = parseScene(json, "test.json");
  const FieldSpec spec = fieldSpec(scene);
  const FieldProblem p = fieldProblem(scene, spec);
  const ObserverField field = computeField(p.integrator, spec, p.excluded);
  const double threshold = 0.2 * field.stats().peak_w_m2;
  const Vec3 from(0.25, -0.5, 0.1);
  std::int64_t points = 0;
  double farthest = 0.0;
  Vec3 lo(1e300), hi(-1e300);
  const auto n = spec.nodes();
  for (int i = 0; i < n[0]; ++i)
    for (int j = 0; j < n[1]; ++j)
      for (int k = 0; k < n[2]; ++k) {
        if (!(field.irradiance(i, j, k) >= threshold)) continue;
        ++points;
        const Vec3 x = spec.position(i, j, k);
        lo = glm::min(lo, x);
        hi = glm::max(hi, x);
        farthest = std::max(farthest, glm::length(x - from));
      }
  ASSERT_GT(points, 10) << "the premise: a bright region";
  const ObserverField::Exceedance r = field.exceedance(threshold, from);
  EXPECT_EQ(r.points, points);
  EXPECT_NEAR(r.volume_m3, static_cast<double>(points) * std::pow(spec.voxel_m, 3), 1e-12);
  EXPECT_NEAR(r.farthest_m, farthest, 1e-12) << "the same lattice point";
  EXPECT_NEAR(glm::length(r.farthest_at_m - from), farthest, 1e-12);
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(r.min_m[a], lo[a], 1e-12) << "axis " << a;
    EXPECT_NEAR(r.max_m[a], hi[a], 1e-12) << "axis " << a;
  }
  const ObserverField::Exceedance none = field.exceedance(2.0 * field.stats().peak_w_m2, from);
  EXPECT_EQ(none.points, 0) << "nothing above twice the peak";
  EXPECT_EQ(none.volume_m3, 0.0);
}

// An observer whose integration stopped at accuracy.max_evaluations is an estimate: the zone
// must count it where its value plus error reaches the threshold, so that a point hazardous in
// the converged field is never outside the cut-short field's zone (issue 64: a plane of such
// points read "hazardous area 0 m²"). Both fields dense, so that they share every point.
TEST(ObserverField, AnUnconvergedPointCountsInTheZoneByItsValuePlusError) {
  const std::string converged_json = cylinderScene(0.003);
  std::string cut_json = converged_json;
  cut_json.insert(cut_json.rfind('}'), R"(, "accuracy": {"max_evaluations": 16})");
  const auto dense = [](const std::string& json) {
    const Scene scene = parseScene(json, "test.json");
    const FieldSpec spec = fieldSpec(scene);
    const FieldProblem p = fieldProblem(scene, spec);
    return computeDenseField(p.integrator, spec, p.excluded);
  };
  const ObserverField truth = dense(converged_json);
  const ObserverField cut = dense(cut_json);
  ASSERT_GT(cut.stats().unconverged_points, 0) << "the premise: points cut short";
  const double threshold = 0.2 * truth.stats().peak_w_m2;
  const auto n = truth.spec().nodes();
  std::int64_t counted = 0, missed_by_value = 0, missed = 0;
  for (int i = 0; i < n[0]; ++i)
    for (int j = 0; j < n[1]; ++j)
      for (int k = 0; k < n[2]; ++k) {
        const bool in_cut =
            cut.irradiance(i, j, k) >= threshold || cut.unconvergedUpper(i, j, k) >= threshold;
        counted += in_cut ? 1 : 0;
        if (!(truth.irradiance(i, j, k) >= threshold)) continue;
        missed_by_value += cut.irradiance(i, j, k) >= threshold ? 0 : 1;
        missed += in_cut ? 0 : 1;
      }
  ASSERT_GT(missed_by_value, 0) << "the premise: values alone leave hazardous points out";
  EXPECT_EQ(missed, 0) << "of " << missed_by_value
                       << " hazardous points whose cut-short value is below the threshold";
  const ObserverField::Exceedance zone = cut.exceedance(threshold, Vec3(0.0));
  EXPECT_EQ(zone.points, counted) << "the zone is every point whose value or bound reaches it";
  EXPECT_GE(zone.by_error_points, missed_by_value) << "counted by their value plus error";
  EXPECT_GE(zone.points, truth.exceedance(threshold, Vec3(0.0)).points)
      << "the cut-short zone is never smaller than the converged one";

  // The outputs' irradiance_upper_w_m2 (upperLattice()) says the same point by point: it reaches
  // the threshold exactly where the zone counts a point, and never lies below the value.
  const std::vector<float> upper = cut.upperLattice();
  const std::vector<float> value = cut.irradianceLattice();
  ASSERT_EQ(upper.size(), value.size());
  std::int64_t upper_counted = 0, below_value = 0;
  for (std::size_t p = 0; p < upper.size(); ++p) {
    upper_counted += static_cast<double>(upper[p]) >= threshold ? 1 : 0;
    below_value += upper[p] < value[p] ? 1 : 0;
  }
  EXPECT_EQ(upper_counted, counted) << "the upper channel marks the zone's points, no more";
  EXPECT_EQ(below_value, 0) << "the most a point may receive is never below its value";
  // Resampled every other point, as the .vti is: the same values at the points kept.
  const std::vector<float> coarse = cut.upperLattice(2);
  std::array<int, 3> m{};
  for (int a = 0; a < 3; ++a) m[a] = (n[a] - 1) / 2 + 1;
  ASSERT_EQ(coarse.size(), static_cast<std::size_t>(m[0]) * m[1] * m[2]);
  for (int k = 0; k < m[2]; ++k)
    for (int j = 0; j < m[1]; ++j)
      for (int i = 0; i < m[0]; ++i) {
        const std::size_t at = (static_cast<std::size_t>(k) * m[1] + j) * m[0] + i;
        const std::size_t fine = (static_cast<std::size_t>(2 * k) * n[1] + 2 * j) * n[0] +
                                 static_cast<std::size_t>(2 * i);
        ASSERT_EQ(coarse[at], upper[fine]) << "point " << i << ", " << j << ", " << k;
      }
}

// A far field sums its faces' work as any fields' (operator+=), but not what belongs to a face's
// own positions and units: countsOnly() keeps the counts and drops the boxes, peak and bounds.
TEST(FieldStats, CountsOnlyKeepTheWorkAndDropWhatBelongsToTheFieldsPositions) {
  FieldStats s;
  s.evaluated_points = 7;
  s.unconverged_points = 2;
  s.unconverged_max_upper_w_m2 = 3.0;
  s.unconverged_min_m = Vec3(-1.0);
  s.unconverged_max_m = Vec3(1.0);
  s.unresolved_blocks = 4;
  s.unresolved_max_bound_w_m2 = 9.0;
  s.unresolved_min_m = Vec3(-2.0);
  s.peak_w_m2 = 5.0;
  s.peak_at_m = Vec3(0.5);
  s.evaluations = 100;
  s.seconds = 0.25;
  FieldStats sum;
  sum += s.countsOnly();
  sum += s.countsOnly();
  EXPECT_EQ(sum.evaluated_points, 14);
  EXPECT_EQ(sum.unconverged_points, 4);
  EXPECT_EQ(sum.unresolved_blocks, 8);
  EXPECT_EQ(sum.evaluations, 200);
  EXPECT_DOUBLE_EQ(sum.seconds, 0.5);
  EXPECT_DOUBLE_EQ(sum.unconverged_max_upper_w_m2, 3.0) << "a maximum, kept";
  const FieldStats none;
  EXPECT_EQ(sum.peak_w_m2, none.peak_w_m2) << "a face's irradiance is not an intensity";
  EXPECT_EQ(sum.unresolved_max_bound_w_m2, none.unresolved_max_bound_w_m2);
  EXPECT_TRUE(std::isinf(sum.unconverged_min_m.x) && std::isinf(sum.unresolved_min_m.x))
      << "no box of positions on a face";
}

// A bound kept in a float grid (the unresolved blocks', the unconverged points') must stay a
// bound and must be finite: it is written into the outputs.
TEST(BoundAsFloat, IsTheLeastFloatNotBelowAndNeverInfinite) {
  EXPECT_EQ(field::boundAsFloat(1.0), 1.0f) << "a float stays itself";
  const float tenth = field::boundAsFloat(0.1);
  EXPECT_GE(static_cast<double>(tenth), 0.1);
  EXPECT_LT(static_cast<double>(std::nextafter(tenth, 0.0f)), 0.1) << "the least such float";
  const float largest = std::numeric_limits<float>::max();
  EXPECT_EQ(field::boundAsFloat(std::numeric_limits<double>::infinity()), largest);
  EXPECT_EQ(field::boundAsFloat(std::numeric_limits<double>::quiet_NaN()), largest)
      << "a NaN bound says nothing, so it bounds nothing below the largest float";
  EXPECT_EQ(field::boundAsFloat(1e300), largest);
}

// A scene with one plane instead of an observer box.
std::string planeScene(const std::string& beam, const std::string& material,
                       const std::string& objects, const std::string& plane) {
  return sceneWith(beam, material, objects, "planes", "[" + plane + "]");
}

TEST(ObserverPlane, TiltedWallFindsTheNarrowGlintAsDense) {
  // The σ = 0.001 pencil of the 5 cm mirror (along +y at x = z = 0.3) crosses a wall tilted
  // 53° from vertical; coarse squares of 8 px have no sample on the 1-2 px spot.
  const std::string json = planeScene(
      R"({"profile": "flat_top", "radius_m": 0.5})",
      R"({"specular_reflectance": 0.9, "sigma": 0.001})",
      R"({"shape": "disk", "center": [0.3, 0, 0.3], "normal": [-1, 1, 0], "radius": 0.05, "material": "m", "segments": 8})",
      R"({"name": "wall", "origin": [-1, 1.7, -0.6], "u_axis": [1, 0, 0], "v_axis": [0, 0.6, 0.8],
          "size_m": [2, 2], "pixel_m": 0.0625, "block_m": 0.5, "tolerance": 0.01,
          "floor_w_m2": 1e-3})");
  const Scene scene = parseScene(json, "test.json");
  const FieldSpec spec = planeFieldSpec(scene, scene.planes.at(0));
  ASSERT_EQ(spec.nodes(), (std::array<int, 3>{33, 33, 1})) << "one layer of 33 × 33";
  const Comparison c = compare(scene, spec);
  expectMatchesDense(c, spec, "tilted wall");
  // The premise: the pencil hits the wall (x = 0.3 → i = 20.8, z = 0.3 → j = 18).
  EXPECT_GT(c.fields.peak_w_m2, 100.0) << "the pencil reaches the wall";
  EXPECT_LT(c.adaptive.evaluated_points, c.dense.evaluated_points / 4)
      << "most of the wall is proven dark";
  const Vec3 peak = c.adaptive.peak_at_m;
  EXPECT_NEAR(peak.x, 0.3, 2 * spec.voxel_m) << "the spot lies on the pencil";
  EXPECT_NEAR(peak.z, 0.3, 2 * spec.voxel_m);
  EXPECT_NEAR(glm::dot(peak - spec.min_m, spec.axes[2]), 0.0, 1e-12) << "on the plane";
}

TEST(ObserverPlane, HorizontalSliceAgreesWithTheBoxAtTheSameHeight) {
  // A plane z = 0.25 (in the lit band) through the lattice of a box around the σ = 0.03 cylinder:
  // the quadtree's points and the octree's at that height must agree within both fields' accuracy.
  const std::string box_json = sceneJson(
      R"({"profile": "flat_top", "radius_m": 2.0})",
      R"({"specular_reflectance": 0.9, "sigma": 0.03})",
      R"({"shape": "cylinder", "center": [0, 0, 0], "axis": [0, 0, 1], "radius": 0.5, "length": 1.0, "material": "m", "segments": 12})",
      R"({"min": [-3, -3, 0], "max": [3, 3, 1], "voxel_m": 0.25, "block_m": 1.0,
          "tolerance": 0.01, "floor_w_m2": 1e-2})");
  const Scene box_scene = parseScene(box_json, "test.json");
  const FieldSpec box_spec = fieldSpec(box_scene);
  const FieldProblem bp = fieldProblem(box_scene, box_spec);
  const ObserverField box = computeField(bp.integrator, box_spec, bp.excluded);

  PlaneSpec plane;
  plane.name = "slice";
  plane.origin_m = Vec3(-3.0, -3.0, 0.25);
  plane.width_m = 6.0;
  plane.height_m = 6.0;
  plane.pixel_m = 0.25;
  plane.block_m = 1.0;
  plane.tolerance = 0.01;
  plane.floor_w_m2 = 1e-2;
  const FieldSpec spec = planeFieldSpec(box_scene, plane);
  const FieldProblem pp = fieldProblem(box_scene, spec);
  const ObserverField slice = computeField(pp.integrator, spec, pp.excluded);

  const int k = 1;  // z = 0 + 1 × 0.25
  ASSERT_DOUBLE_EQ(box_spec.position(0, 0, k).z, 0.25);
  const auto n = spec.nodes();
  const double allowed =
      2.0 * (0.01 * std::max(box.stats().peak_w_m2, slice.stats().peak_w_m2) + 1e-2);
  double worst = 0.0;
  int compared = 0;
  for (int i = 0; i < n[0]; ++i)
    for (int j = 0; j < n[1]; ++j) {
      ASSERT_EQ(spec.position(i, j, 0), box_spec.position(i, j, k)) << "the same lattice point";
      if (box.status(i, j, k) == VoxelStatus::Excluded) continue;
      worst = std::max(worst, std::abs(slice.irradiance(i, j, 0) - box.irradiance(i, j, k)));
      ++compared;
    }
  EXPECT_GT(slice.stats().peak_w_m2, 1.0) << "the slice crosses the glint fan";
  EXPECT_LE(worst, allowed) << compared << " points compared";
}

// A mirror ball half a metre across, lit whole, and a box of observers in front of it.
std::string mirrorBallScene() {
  return sceneJson(R"({"profile": "flat_top", "radius_m": 1.0})",
                   R"({"specular_reflectance": 0.6, "sigma": 0.01})",
                   R"({"shape": "sphere", "center": [0, 0, 0], "radius": 0.5, "material": "m"})",
                   R"({"min": [-4.4, -1.6, -1.6], "max": [-1.2, 1.6, 1.6], "voxel_m": 0.2,
                       "block_m": 1.6, "tolerance": 0.01, "floor_w_m2": 1e-2})");
}

TEST(ObserverField, SphereFarFieldIsInterpolatedAlongItsFallOff) {
  // A mirror ball's glint fills the half-space in front of it and falls off as about 1/r².
  // Trilinear interpolation of 1/r² errs by about 0.75 (h/r)², more than 1 % for blocks
  // wider than a tenth of their distance; interpolating E·r², which is nearly constant, lets
  // large blocks through. They must still match dense to the same accuracy.
  const std::string json = mirrorBallScene();
  const FieldSpec spec = specOf(json);
  const Comparison c = compare(json);
  expectMatchesDense(c, spec, "mirror sphere, far field");
  EXPECT_GT(c.adaptive.blocks_accepted_spread, 0) << "the 1/r² fall-off must be followed";
  EXPECT_LT(c.adaptive.evaluated_points, c.dense.evaluated_points / 2)
      << "a smooth field in front of the ball needs few integrated points";
}

TEST(ObserverField, AGlintBetweenTheLatticePointsIsMarkedWithItsBoundAtEveryVoxelSize) {
  // Issue 34: a 5 cm mirror (σ = 0.001) sends a pencil about 9 times the MPE along +y through
  // a 10 m box, 0.3 m off the lattice planes x = 0 and z = 0 (tests/data/subvoxel_pencil.json).
  // At 0.0625 m the lattice meets it; from 0.125 m to 1 m the pencil passes between the
  // lattice points and only the finest blocks' bounds know it is there. Wherever it is
  // hazardous, a corner of the lattice cell holding it must be above the MPE or marked status
  // 6, and the largest bound reported must cover what the pencil truly carries.
  Scene scene = loadScene(std::string(GLINT_TEST_DATA_DIR) + "/subvoxel_pencil.json");
  const double mpe = scene.hazard.mpe_w_m2;
  // The pencil's own irradiance on its axis (the disk's centre reflected along +y), integrated
  // directly at the field's accuracy.
  FieldProblem reference = fieldProblem(scene, fieldSpec(scene));
  IntegratorWorkspace ws;
  std::vector<std::pair<Vec3, double>> axis;
  double pencil_max = 0.0;
  for (double y = 2.5; y <= 12.0; y += 0.5) {
    const Vec3 x(0.3, y, 0.3);
    const double e = reference.integrator.adaptive(x, ws).irradiance_w_m2;
    axis.emplace_back(x, e);
    pencil_max = std::max(pencil_max, e);
  }
  ASSERT_GT(pencil_max, 5.0 * mpe) << "the premise: the pencil is hazardous about 9 times over";
  const auto fieldAt = [&](double voxel) {
    scene.observers->voxel_m = voxel;
    scene.observers->block_m = 16.0 * voxel;
    const FieldSpec spec = fieldSpec(scene);
    const FieldProblem p = fieldProblem(scene, spec);
    return computeField(p.integrator, spec, p.excluded);
  };
  double resolving_m = std::numeric_limits<double>::infinity();
  for (const double voxel : {0.0625, 0.125, 0.25, 0.5, 1.0}) {
    const ObserverField field = fieldAt(voxel);
    const FieldSpec& spec = field.spec();
    const FieldStats& s = field.stats();
    resolving_m = std::min(resolving_m, s.unresolved_resolving_voxel_m);
    EXPECT_GT(s.unresolved_points, 0) << voxel << " m";
    EXPECT_GE(s.unresolved_max_bound_w_m2, pencil_max)
        << voxel << " m: the bound reported must hold the pencil's largest irradiance";
    EXPECT_GT(s.unresolved_resolving_voxel_m, 0.0) << voxel << " m";
    EXPECT_LT(s.unresolved_resolving_voxel_m, voxel)
        << voxel << " m: a finer lattice is what would resolve it";
    for (const auto& [x, e] : axis) {
      if (e < mpe) continue;
      // The lattice cell that holds x: one of its corners must see the hazard or say that it
      // may pass.
      const Vec3 at = (x - spec.min_m) / spec.voxel_m;
      const int i = static_cast<int>(at.x), j = static_cast<int>(at.y), k = static_cast<int>(at.z);
      bool seen = false;
      for (int c = 0; c < 8; ++c) {
        const int a = i + (c >> 2), b = j + ((c >> 1) & 1), d = k + (c & 1);
        seen = seen || field.status(a, b, d) == VoxelStatus::Unresolved ||
               field.irradiance(a, b, d) >= mpe;
      }
      EXPECT_TRUE(seen) << voxel << " m: the pencil at y = " << x.y << " (ratio " << e / mpe
                        << ") passes through the cell at (" << i << ", " << j << ", " << k
                        << "), none of whose corners reaches the MPE or has status 6";
    }
    const HazardZone zone = hazardZone(field, scene.hazard, Vec3(0.3, 0.0, 0.3));
    EXPECT_TRUE(zone.narrow_glint_may_be_hazardous) << voxel << " m";
    EXPECT_GE(zone.narrow_glint_ratio_bound, pencil_max / mpe) << voxel << " m";
    if (voxel >= 0.125) {
      EXPECT_EQ(zone.above_mpe.points, 0) << voxel << " m: the premise, no lattice point sees it";
    }
    std::printf(
        "[ pencil ] voxel %g m: lattice peak ratio %.3g, %lld points status 6, bound "
        "ratio %.4g (pencil %.3g), resolving voxel %.4g m\n",
        voxel, s.peak_w_m2 / mpe, static_cast<long long>(s.unresolved_points),
        zone.narrow_glint_ratio_bound, pencil_max / mpe, s.unresolved_resolving_voxel_m);
  }
  // At the voxel the runs suggest, the lattice meets the pencil and no bound is left above it.
  const ObserverField resolved = fieldAt(resolving_m);
  EXPECT_EQ(resolved.stats().unresolved_points, 0) << "at " << resolving_m << " m";
  EXPECT_GE(resolved.stats().peak_w_m2, mpe) << "at " << resolving_m << " m";
}

}  // namespace
}  // namespace glint

namespace glint {
namespace {

// The lattice of directions × distances (RadialLattice) is computed by the same block check:
// toward a mirror ball's lit side, from twice its radius out to 40 radii, rays from its centre
// every 1/8 of a face's half-width and layers 10 % apart. Its blocks grow with the distance,
// their balls hold their frusta, and the field must match its dense twin to the same accuracy
// as the box does, following the 1/r² fall-off along the rays.
TEST(ObserverField, ARadialLatticeMatchesDenseFromNearTheTargetOut) {
  const std::string json = mirrorBallScene();
  const Scene scene = parseScene(json, "test.json");
  FieldSpec spec = fieldSpec(scene);
  spec.block_voxels = 8;
  spec.axes = {Vec3(0.0, -1.0, 0.0), Vec3(0.0, 0.0, 1.0), Vec3(-1.0, 0.0, 0.0)};
  // About the lit facets' centre, where the field weighs E by r^p.
  const FieldProblem problem = fieldProblem(scene, spec);
  spec.radial = RadialLattice{litBall(problem.integrator).centre_m, 16, 1.0, 1.1, 32};
  const std::array<int, 3> n = spec.nodes();
  ASSERT_EQ(n[0], 17);
  ASSERT_EQ(n[2], 33);
  const Vec3 c = spec.radial->centre_m;
  EXPECT_NEAR(glm::length(spec.position(8, 8, 32) - c), std::pow(1.1, 32), 1e-9)
      << "the face's centre ray";
  EXPECT_NEAR(glm::length(spec.position(0, 0, 0) - c), std::sqrt(3.0), 1e-12) << "a corner ray";
  const Comparison r = compare(scene, spec);
  expectMatchesDense(r, spec, "mirror sphere, radial lattice");
  EXPECT_GT(r.adaptive.blocks_accepted_spread, 0) << "the 1/r² fall-off along the rays";
  EXPECT_LT(r.adaptive.evaluated_points, r.dense.evaluated_points / 2)
      << "a smooth field in front of the ball needs few integrated points";
  std::printf("[ radial ] %lld of %lld points evaluated, %lld blocks accepted (%lld as E r^p)\n",
              static_cast<long long>(r.adaptive.evaluated_points),
              static_cast<long long>(r.dense.evaluated_points),
              static_cast<long long>(r.adaptive.blocks_accepted),
              static_cast<long long>(r.adaptive.blocks_accepted_spread));
}

}  // namespace
}  // namespace glint
