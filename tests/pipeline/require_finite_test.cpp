// The last check before `glint run` and `glint batch` write: a field with a non-finite value
// or statistic is refused, so no infinity can reach an output or read as "no hazard".
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include "observers/field.h"
#include "observers/field_grids.h"
#include "pipeline/setup/scene_regions.h"

namespace glint {
namespace {

ObserverField fieldWith(const FieldStats& stats) {
  FieldSpec spec;
  spec.max_m = Vec3(1.0);
  spec.voxel_m = 0.5;
  spec.block_voxels = 2;
  auto grids = std::make_unique<FieldGrids>();
  grids->irradiance = openvdb::FloatGrid::create(0.0f);
  grids->level = openvdb::FloatGrid::create(-1.0f);
  grids->status = openvdb::FloatGrid::create(0.0f);
  grids->upper = openvdb::FloatGrid::create(0.0f);
  return ObserverField(spec, stats, std::move(grids), {});
}

std::string refusalOf(const FieldStats& stats) {
  try {
    requireFinite(fieldWith(stats), "the observer box");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(RequireFinite, AFiniteFieldPasses) {
  FieldStats s;
  s.peak_w_m2 = 1e30;
  s.unconverged_max_upper_w_m2 = std::numeric_limits<double>::infinity();  // "unbounded" is honest
  EXPECT_EQ(refusalOf(s), "") << "a finite peak with an unbounded unconverged error is reportable";
}

TEST(RequireFinite, NonFinitePointsAreRefusedNamingOne) {
  FieldStats s;
  s.non_finite_points = 3;
  s.non_finite_at_m = Vec3(0.5, 0.0, 1.0);
  EXPECT_EQ(refusalOf(s),
            "the observer box: 3 points have a non-finite irradiance, one at (0.5, 0, 1); "
            "nothing was written");
}

TEST(RequireFinite, ANonFiniteOrNegativePeakIsRefused) {
  for (const double peak :
       {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN(), -1.0}) {
    FieldStats s;
    s.peak_w_m2 = peak;
    EXPECT_NE(refusalOf(s), "") << "peak " << peak << " was accepted";
  }
  FieldStats s;
  s.unconverged_max_upper_w_m2 = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(refusalOf(s), "") << "a NaN unconverged bound was accepted";
}

}  // namespace
}  // namespace glint
