// The VTK files go through VTK's own writers: VTK's readers must give back exactly the values
// the field holds (float for float), and the AMR must appear whole on commit or not at all.
#include "export/vtk_files.h"

#include <gtest/gtest.h>
#include <unistd.h>
#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkOverlappingAMR.h>
#include <vtkPointData.h>
#include <vtkUniformGrid.h>
#include <vtkXMLImageDataReader.h>
#include <vtkXMLUniformGridAMRReader.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "export/atomic_file.h"
#include "observers/detail/field_common.h"
#include "observers/field.h"
#include "observers/field_grids.h"
#include "support/small_disk.h"

namespace glint {
namespace {

namespace fs = std::filesystem;

constexpr double kMpe = 50.0;
constexpr double kAidGain = 34.3;
// What pipeline/hazard gives the writers for an MPE of 50 W/m² and a 7×50 binocular.
const std::vector<ScaledArray> kRatios = {{"hazard_ratio", "", 1.0 / kMpe},
                                          {"aided_hazard_ratio", "", kAidGain / kMpe}};

// A scaled array's value: irradiance × per_w_m2 in double, stored as float.
float scaled(float e_w_m2, const ScaledArray& a) {
  return static_cast<float>(static_cast<double>(e_w_m2) * a.per_w_m2);
}

// A 16-voxel box of two coarse blocks of 8 a side along x (17 × 9 × 9 lattice points):
// the first refined to level 1 (blocks of 4), one of those to level 2 (blocks of 2); the
// second accepted at level 0. Values of both signs of the MPE's ratio, a tile, inactive voxels.
ObserverField sampleField() {
  openvdb::initialize();
  FieldSpec spec;
  spec.min_m = Vec3(-1.0, 0.5, 2.0);
  spec.max_m = spec.min_m + Vec3(4.0, 2.0, 2.0);
  spec.voxel_m = 0.25;
  spec.block_voxels = 8;
  std::unique_ptr<FieldGrids> g = field::makeGrids(spec);  // as the field builder makes them
  g->irradiance->tree().fill(openvdb::CoordBBox({8, 0, 0}, {16, 8, 8}), 37.5f, true);
  auto e = g->irradiance->getAccessor();
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 9; ++j)
      e.setValue({i, j, (i + j) % 9}, 1.0f / static_cast<float>(i + j + 1));
  e.setValue({2, 2, 2}, 3.0e7f);
  g->level->tree().fill(openvdb::CoordBBox({0, 0, 0}, {16, 8, 8}), 1.0f, true);
  g->status->tree().fill(openvdb::CoordBBox({0, 0, 0}, {16, 8, 8}), 2.0f, true);
  g->status->getAccessor().setValue({2, 2, 2}, 1.0f);
  std::vector<FieldBlock> blocks;
  for (int c = 0; c < 8; ++c) {
    const std::array<int, 3> o{4 * (c >> 2), 4 * ((c >> 1) & 1), 4 * (c & 1)};
    if (c != 0) {
      blocks.push_back({o, {4, 4, 4}, 1, VoxelStatus::Interpolated});
      continue;
    }
    for (int d = 0; d < 8; ++d) {
      blocks.push_back(
          {{2 * (d >> 2), 2 * ((d >> 1) & 1), 2 * (d & 1)}, {2, 2, 2}, 2, VoxelStatus::Evaluated});
    }
  }
  blocks.push_back({{8, 0, 0}, {8, 8, 8}, 0, VoxelStatus::Interpolated});
  return ObserverField(spec, FieldStats{}, std::move(g), std::move(blocks));
}

// The lattice's irradiance as the files hold it: the stored float, 0 where not computed.
float latticeValue(const ObserverField& field, int i, int j, int k) {
  auto a = field.grids().irradiance->getConstAccessor();
  const openvdb::Coord c(i, j, k);
  return a.isValueOn(c) ? a.getValue(c) : 0.0f;
}

// A fresh, empty folder under the system's temporary folder.
fs::path freshFolder(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / (name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

TEST(VtkFiles, VtiReadsBackWithVtkAsTheFieldsValuesExactly) {
  const ObserverField field = sampleField();
  std::ostringstream out;
  writeVti(out, field, 1, kRatios);
  ASSERT_EQ(out.str().find("<AppendedData"), std::string::npos)
      << "appended data is unreadable under expat 2.6 (VTK issue 19258)";

  vtkNew<vtkXMLImageDataReader> reader;
  reader->ReadFromInputStringOn();
  reader->SetInputString(out.str());
  reader->Update();
  vtkImageData* image = reader->GetOutput();
  ASSERT_NE(image, nullptr);
  int dims[3];
  image->GetDimensions(dims);
  const auto n = field.spec().nodes();
  ASSERT_EQ(dims[0], n[0]);
  ASSERT_EQ(dims[1], n[1]);
  ASSERT_EQ(dims[2], n[2]);
  EXPECT_EQ(image->GetOrigin()[0], -1.0);
  EXPECT_EQ(image->GetOrigin()[1], 0.5);
  EXPECT_EQ(image->GetOrigin()[2], 2.0);
  EXPECT_EQ(image->GetSpacing()[0], 0.25);

  auto* e = vtkFloatArray::SafeDownCast(image->GetPointData()->GetArray("irradiance_w_m2"));
  auto* r = vtkFloatArray::SafeDownCast(image->GetPointData()->GetArray("hazard_ratio"));
  auto* aided = vtkFloatArray::SafeDownCast(image->GetPointData()->GetArray("aided_hazard_ratio"));
  auto* level = vtkIntArray::SafeDownCast(image->GetPointData()->GetArray("refinement_level"));
  auto* status = vtkIntArray::SafeDownCast(image->GetPointData()->GetArray("status"));
  ASSERT_TRUE(e && r && aided && level && status)
      << "Float32 irradiance and both ratios, Int32 level, status";
  int nonzero = 0;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        const vtkIdType p = i + n[0] * (j + static_cast<vtkIdType>(n[1]) * k);
        const float want = latticeValue(field, i, j, k);
        nonzero += want != 0.0f;
        ASSERT_EQ(e->GetValue(p), want) << "irradiance at (" << i << ", " << j << ", " << k << ")";
        ASSERT_EQ(r->GetValue(p), scaled(want, kRatios[0]))
            << "hazard ratio at (" << i << ", " << j << ", " << k << ")";
        ASSERT_EQ(aided->GetValue(p), scaled(want, kRatios[1]))
            << "aided hazard ratio at (" << i << ", " << j << ", " << k << ")";
        ASSERT_EQ(status->GetValue(p), field.status(i, j, k) == VoxelStatus::Evaluated ? 1 : 2)
            << "status at (" << i << ", " << j << ", " << k << ")";
        ASSERT_EQ(level->GetValue(p), 1);
      }
  EXPECT_GT(nonzero, 100) << "premise: the field has values to compare";
  EXPECT_EQ(e->GetValue(2 + n[0] * (2 + n[1] * 2)), 3.0e7f) << "the peak";
}

TEST(VtkFiles, AmrHasOneLevelPerBlockResolutionEachHoldingTheLatticeValues) {
  const ObserverField field = sampleField();
  const fs::path dir = freshFolder("glint-vtk-amr");
  writeAmr(dir / "irradiance.vthb", field, kRatios).commit();
  ASSERT_TRUE(fs::is_regular_file(dir / "irradiance.vthb"));
  ASSERT_TRUE(fs::is_directory(dir / "irradiance"));

  vtkNew<vtkXMLUniformGridAMRReader> reader;
  reader->SetFileName((dir / "irradiance.vthb").c_str());
  reader->SetMaximumLevelsToReadByDefault(0);  // every level
  reader->Update();
  auto* amr = vtkOverlappingAMR::SafeDownCast(reader->GetOutputDataObject(0));
  ASSERT_NE(amr, nullptr);
  ASSERT_EQ(amr->GetNumberOfLevels(), 3u) << "coarse blocks of 8, refined to 4 and to 2";
  EXPECT_EQ(amrLevels(field), 3);
  EXPECT_EQ(amr->GetNumberOfDataSets(0), 1u) << "level 0: the whole box";
  EXPECT_EQ(amr->GetNumberOfDataSets(1), 1u) << "level 1: one coarse block holds finer blocks";
  EXPECT_EQ(amr->GetNumberOfDataSets(2), 1u);
  int compared = 0;
  for (unsigned l = 0; l < amr->GetNumberOfLevels(); ++l) {
    const int step = 4 >> l;  // block_voxels / 2^(l+1)
    for (unsigned b = 0; b < amr->GetNumberOfDataSets(l); ++b) {
      vtkUniformGrid* grid = amr->GetDataSet(l, b);
      ASSERT_NE(grid, nullptr);
      EXPECT_DOUBLE_EQ(grid->GetSpacing()[0], 0.25 * step) << "level " << l;
      auto* e = vtkFloatArray::SafeDownCast(grid->GetPointData()->GetArray("irradiance_w_m2"));
      auto* r = vtkFloatArray::SafeDownCast(grid->GetPointData()->GetArray("hazard_ratio"));
      auto* aided =
          vtkFloatArray::SafeDownCast(grid->GetPointData()->GetArray("aided_hazard_ratio"));
      ASSERT_TRUE(e && r && aided) << "level " << l;
      for (vtkIdType p = 0; p < grid->GetNumberOfPoints(); ++p) {
        double x[3];
        grid->GetPoint(p, x);
        const int i = static_cast<int>(std::lround((x[0] + 1.0) / 0.25));
        const int j = static_cast<int>(std::lround((x[1] - 0.5) / 0.25));
        const int k = static_cast<int>(std::lround((x[2] - 2.0) / 0.25));
        const float want = latticeValue(field, i, j, k);
        ASSERT_EQ(e->GetValue(p), want)
            << "level " << l << " at (" << i << ", " << j << ", " << k << ")";
        ASSERT_EQ(r->GetValue(p), scaled(want, kRatios[0]));
        ASSERT_EQ(aided->GetValue(p), scaled(want, kRatios[1]));
        ++compared;
      }
    }
  }
  EXPECT_EQ(compared, 5 * 3 * 3 + 5 * 5 * 5 + 5 * 5 * 5)
      << "level 0: every 4th point; 1: the first coarse block every 2nd; 2: its finest corner";
  fs::remove_all(dir);
}

TEST(VtkFiles, AmrLeavesNothingUntilCommittedAndReplacesThePreviousWhole) {
  const ObserverField field = sampleField();
  const fs::path dir = freshFolder("glint-vtk-staged");
  { const StagedAmr dropped = writeAmr(dir / "irradiance.vthb", field, kRatios); }
  EXPECT_TRUE(fs::is_empty(dir)) << "an AMR dropped uncommitted leaves no file or folder";

  fs::create_directories(dir / "irradiance");
  { std::ofstream(dir / "irradiance" / "stale.vti") << "old"; }
  writeAmr(dir / "irradiance.vthb", field, kRatios).commit();
  EXPECT_FALSE(fs::exists(dir / "irradiance" / "stale.vti")) << "the previous folder is replaced";
  int entries = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    ++entries;
    EXPECT_NE(entry.path().filename().string().front(), '.')
        << "staging left behind: " << entry.path();
  }
  EXPECT_EQ(entries, 2) << "irradiance.vthb and irradiance/";
  fs::remove_all(dir);
}

TEST(VtkFiles, AmrIntoAMissingFolderThrowsOutputError) {
  const ObserverField field = sampleField();
  const fs::path dir = freshFolder("glint-vtk-missing") / "not-there";
  EXPECT_THROW((void)writeAmr(dir / "irradiance.vthb", field, kRatios), OutputError);
  fs::remove_all(dir.parent_path());
}

// A full disk under the AMR's block files reads as the other writers' full disks do, with its
// reason, not as "VTK's XML writer failed" alone (issue 64). The disk is a tmpfs of the test's
// own, one page: room for the first block, not for the rest.
TEST(VtkFiles, AmrOnAFullDiskSaysTheDiskIsFull) {
  const ObserverField field = sampleField();
  const fs::path dir = freshFolder("glint-vtk-full");
  {
    test::SmallDisk disk(dir / "disk", 1);
    ASSERT_TRUE(disk.mounted()) << "cannot mount a tmpfs here (" << disk.why()
                                << "): the full-disk tests need root and CAP_SYS_ADMIN";
    std::string message;
    try {
      writeAmr(dir / "disk" / "irradiance.vthb", field, kRatios).commit();
    } catch (const OutputError& e) {
      message = e.what();
    }
    EXPECT_NE(message.find("No space left on device"), std::string::npos) << message;
    EXPECT_TRUE(fs::is_empty(dir / "disk")) << "no staging folder left: " << message;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace glint
