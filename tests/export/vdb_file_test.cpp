// irradiance.vdb is written one grid at a time (the field's grids freed as they go, the hazard
// ratio made in place of the irradiance): the file must still be exactly what OpenVDB's own
// writer makes of the same grids, and the hazard ratio the irradiance divided by the MPE.
#include <gtest/gtest.h>
#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>

#include <memory>
#include <sstream>
#include <string>

#include "export/field_files.h"
#include "observers/detail/field_common.h"
#include "observers/field.h"
#include "observers/field_grids.h"

namespace glint {
namespace {

// A small field with voxels, a tile (a uniform 8³ leaf's worth) and values of both signs of
// the MPE's ratio, so the in-place division meets leaves and tiles.
ObserverField sampleField() {
  openvdb::initialize();
  FieldSpec spec;
  spec.max_m = Vec3(4.0);
  spec.voxel_m = 0.25;
  spec.block_voxels = 8;
  std::unique_ptr<FieldGrids> g = field::makeGrids(spec);  // as the field builder makes them
  g->irradiance->tree().fill(openvdb::CoordBBox({0, 0, 0}, {7, 7, 7}), 37.5f, true);
  auto e = g->irradiance->getAccessor();
  for (int i = 8; i < 16; ++i) e.setValue({i, 3, 5}, 1.0f / static_cast<float>(i));
  e.setValue({9, 9, 9}, 3.0e7f);
  g->level->tree().fill(openvdb::CoordBBox({0, 0, 0}, {15, 15, 15}), 2.0f, true);
  g->status->tree().fill(openvdb::CoordBBox({0, 0, 0}, {15, 15, 15}), 2.0f, true);
  g->status->getAccessor().setValue({9, 9, 9}, 1.0f);
  FieldStats stats;
  stats.evaluations = 1234;
  stats.peak_w_m2 = 3.0e7;
  return ObserverField(spec, stats, std::move(g), {});
}

RunInfo sampleInfo() {
  RunInfo info;
  info.program_version = "glint test";
  info.scene_file = "scene.json";
  info.scene_fnv1a64 = "0123456789abcdef";
  info.scheme = "adaptive";
  info.wavelength_nm = 1064.0;
  info.power_w = 5.0e4;
  info.exposure_s = 10.0;
  info.mpe_w_m2 = 50.0;
  info.mpe_rule = "test";
  info.scaled = {{"hazard_ratio", "1 (irradiance / MPE)", 1.0 / 50.0}};
  return info;
}

// The header's UUID (bytes 21 .. 56: magic, versions and the offsets flag before it) is new
// in every file.
std::string withoutUuid(const std::string& vdb) {
  constexpr std::size_t kUuidAt = 21, kUuidChars = 36;
  return vdb.substr(0, kUuidAt) + vdb.substr(kUuidAt + kUuidChars);
}

// The grids writeVdb() writes of sampleField() with @p info, read back by OpenVDB.
openvdb::GridPtrVecPtr writtenGrids(const RunInfo& info) {
  std::ostringstream out;
  writeVdb(out, sampleField(), info);
  std::istringstream in(out.str());
  return openvdb::io::Stream(in).getGrids();
}

TEST(VdbFile, GridByGridIsByteForByteWhatOpenVdbWritesOfTheSameGrids) {
  std::ostringstream ours;
  writeVdb(ours, sampleField(), sampleInfo());

  std::istringstream in(ours.str());
  openvdb::io::Stream reader(in);
  const openvdb::GridPtrVecPtr grids = reader.getGrids();
  const openvdb::MetaMap::Ptr meta = reader.getMetadata();
  ASSERT_EQ(grids->size(), 5u) << "irradiance, hazard ratio, level, status and upper bound";

  std::ostringstream theirs;
  openvdb::io::Stream(theirs).write(*grids, *meta);
  EXPECT_EQ(ours.str().size(), theirs.str().size());
  EXPECT_TRUE(withoutUuid(ours.str()) == withoutUuid(theirs.str()))
      << "the grid-by-grid file differs from io::Stream's beyond the header's UUID";
}

TEST(VdbFile, HazardRatioIsTheIrradianceOverTheMpeAndTheOtherGridsAreKept) {
  const ObserverField reference = sampleField();
  const RunInfo info = sampleInfo();
  const openvdb::GridPtrVecPtr grids = writtenGrids(info);
  ASSERT_EQ(grids->size(), 5u);
  auto grid = [&](const std::string& name) {
    const openvdb::GridBase::Ptr g = openvdb::findGridByName(*grids, name);
    EXPECT_TRUE(g) << name << " is missing";
    return openvdb::gridPtrCast<openvdb::FloatGrid>(g);
  };
  const auto irradiance = grid("irradiance_w_m2");
  const auto ratio = grid("hazard_ratio");
  const auto level = grid("refinement_level");
  const auto status = grid("status");
  ASSERT_TRUE(irradiance && ratio && level && status);
  const FieldGrids& want = reference.grids();
  EXPECT_EQ(irradiance->activeVoxelCount(), want.irradiance->activeVoxelCount());
  EXPECT_EQ(ratio->activeVoxelCount(), want.irradiance->activeVoxelCount());
  for (auto it = want.irradiance->cbeginValueOn(); it; ++it) {
    const openvdb::Coord c = it.getCoord();
    EXPECT_EQ(irradiance->tree().getValue(c), *it) << "irradiance at " << c;
    // Computed in double and stored as float, as the VTK files do.
    EXPECT_EQ(ratio->tree().getValue(c),
              static_cast<float>(static_cast<double>(*it) * info.scaled[0].per_w_m2))
        << "hazard ratio at " << c;
  }
  for (const openvdb::Coord c : {openvdb::Coord(3, 3, 3), openvdb::Coord(9, 9, 9),
                                 openvdb::Coord(12, 3, 5), openvdb::Coord(40, 40, 40)}) {
    EXPECT_EQ(level->tree().getValue(c), want.level->tree().getValue(c)) << "level at " << c;
    EXPECT_EQ(status->tree().getValue(c), want.status->tree().getValue(c)) << "status at " << c;
  }
}

TEST(VdbFile, WithoutScaledArraysOnlyTheFieldsGridsAreWritten) {
  RunInfo info = sampleInfo();
  info.mpe_w_m2 = 0.0;
  info.scaled.clear();
  const openvdb::GridPtrVecPtr grids = writtenGrids(info);
  EXPECT_EQ(grids->size(), 4u) << "irradiance, level, status and upper bound";
  EXPECT_FALSE(openvdb::findGridByName(*grids, "hazard_ratio")) << "written without an MPE";
}

TEST(VdbFile, EachScaledGridIsTheIrradianceTimesItsFactorWithinTwoFloatRoundings) {
  // The aided ratio is the hazard ratio's grid rescaled in place (gain 34.3): two roundings to
  // float, each within 2^-24 relative.
  RunInfo info = sampleInfo();
  info.scaled.push_back({"aided_hazard_ratio", "1 (aided)", 34.3 / 50.0});
  const ObserverField reference = sampleField();
  const openvdb::GridPtrVecPtr grids = writtenGrids(info);
  ASSERT_EQ(grids->size(), 6u) << "irradiance, two scaled grids, level, status and upper bound";
  const auto aided = openvdb::gridPtrCast<openvdb::FloatGrid>(
      openvdb::findGridByName(*grids, "aided_hazard_ratio"));
  ASSERT_TRUE(aided);
  EXPECT_EQ(aided->metaValue<std::string>("units"), "1 (aided)");
  int compared = 0;
  for (auto it = reference.grids().irradiance->cbeginValueOn(); it; ++it) {
    const double want = static_cast<double>(*it) * 34.3 / 50.0;
    EXPECT_NEAR(aided->tree().getValue(it.getCoord()), want,
                2.0 * 0x1p-24 * std::abs(want) + 1e-300)
        << "aided ratio at " << it.getCoord();
    ++compared;
  }
  EXPECT_GT(compared, 0);
}

}  // namespace
}  // namespace glint
