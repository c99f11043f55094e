#include "export/vtk_files.h"

#include <unistd.h>
#include <vtkAMRBox.h>
#include <vtkAMRUtilities.h>
#include <vtkCallbackCommand.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkCommand.h>
#include <vtkDoubleArray.h>
#include <vtkErrorCode.h>
#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkOverlappingAMR.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkTypeInt64Array.h>
#include <vtkUniformGrid.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLImageDataWriter.h>
#include <vtkXMLPolyDataWriter.h>
#include <vtkXMLUniformGridAMRWriter.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <string>
#include <system_error>
#include <vector>

#include "export/atomic_file.h"
#include "observers/field_grids.h"

namespace glint {
namespace {

// The .vti's budget (pipeline/commands/run_command.cpp, vtiStride): the AMR keeps to it too.
constexpr double kAmrPointBudget = 16.7e6;
// Each AMR block is a file: a folder of many thousands is slow to open and to copy.
constexpr std::size_t kAmrFileBudget = 10000;

// ZLib-compressed arrays, inline (see the header: appended data is unreadable under expat 2.6),
// with 64-bit headers so an array may pass 4 GB.
void configure(vtkXMLWriter& writer) {
  writer.SetDataModeToBinary();
  writer.SetCompressorTypeToZLib();
  writer.SetHeaderTypeToUInt64();
}

// Runs @p writer. Write()'s result alone does not tell a failure: vtkXMLUniformGridAMRWriter
// returns 1 when it could not make its block folder, and only its ErrorEvent says so. An
// observer also keeps VTK from printing the message itself: it becomes the exception's.
void runWriter(vtkXMLWriter& writer, const std::string& what) {
  std::string errors;
  vtkNew<vtkCallbackCommand> observer;
  observer->SetClientData(&errors);
  observer->SetCallback([](vtkObject*, unsigned long, void* client, void* call) {
    auto& log = *static_cast<std::string*>(client);
    log += log.empty() ? "" : "; ";
    log += call != nullptr ? static_cast<const char*>(call) : "unknown error";
  });
  writer.AddObserver(vtkCommand::ErrorEvent, observer);
  const int ok = writer.Write();
  writer.RemoveObserver(observer);
  const unsigned long code = writer.GetErrorCode();
  if (ok != 1 || code != vtkErrorCode::NoError || !errors.empty()) {
    // The reason in the words the other writers use (a full disk reads as strerror says it);
    // VTK's own messages, where it gave any, after it.
    std::string reason =
        code == vtkErrorCode::OutOfDiskSpaceError ? std::generic_category().message(ENOSPC)
        : code != vtkErrorCode::NoError ? std::string(vtkErrorCode::GetStringFromErrorCode(code))
                                        : std::string();
    if (!errors.empty()) reason += (reason.empty() ? "" : "; ") + errors;
    throw OutputError(what + ": VTK's XML writer failed: " +
                      (reason.empty() ? std::string("it gave no reason") : reason));
  }
}

// Writes @p data with @p writer into @p out, whole: VTK makes the file in memory first.
void writeTo(std::ostream& out, vtkXMLWriter& writer, vtkDataObject* data, const char* what) {
  configure(writer);
  writer.SetInputData(data);
  writer.WriteToOutputStringOn();
  runWriter(writer, what);
  const std::string text = writer.GetOutputString();
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
}

template <class Array>
vtkNew<Array> namedArray(const char* name, vtkIdType tuples, int components = 1) {
  vtkNew<Array> a;
  a->SetName(name);
  a->SetNumberOfComponents(components);
  a->SetNumberOfTuples(tuples);
  return a;
}

// Adds each of @p scaled beside the @p n irradiance values @p e: irradiance × per_w_m2, formed
// in double, stored as float (the VDB's and the EXR's values).
void addScaledArrays(vtkPointData& data, const float* e, vtkIdType n,
                     const std::vector<ScaledArray>& scaled) {
  for (const ScaledArray& s : scaled) {
    auto array = namedArray<vtkFloatArray>(s.name.c_str(), n);
    float* out = array->GetPointer(0);
    for (vtkIdType q = 0; q < n; ++q) {
      out[q] = static_cast<float>(static_cast<double>(e[q]) * s.per_w_m2);
    }
    data.AddArray(array);
  }
}

// Cells from offsets (starting at 0, one past each cell) and connectivity, 64-bit.
vtkNew<vtkCellArray> cellArray(const std::vector<std::int64_t>& offsets,
                               const std::vector<std::int64_t>& connectivity) {
  vtkNew<vtkTypeInt64Array> o, c;
  o->SetNumberOfTuples(static_cast<vtkIdType>(offsets.size()));
  std::copy(offsets.begin(), offsets.end(), o->GetPointer(0));
  c->SetNumberOfTuples(static_cast<vtkIdType>(connectivity.size()));
  std::copy(connectivity.begin(), connectivity.end(), c->GetPointer(0));
  vtkNew<vtkCellArray> cells;
  cells->SetData(o, c);
  return cells;
}

vtkNew<vtkPoints> pointsOf(const std::vector<double>& xyz) {
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(static_cast<vtkIdType>(xyz.size() / 3));
  std::copy(xyz.begin(), xyz.end(), static_cast<double*>(points->GetData()->GetVoidPointer(0)));
  return points;
}

// --- The AMR's blocks: boxes of lattice points, in voxels.
struct LatticeBox {
  std::array<int, 3> lo{};  // first lattice point
  std::array<int, 3> hi{};  // last lattice point
};

int log2Of(int power_of_two) {
  int l = 0;
  while ((1 << (l + 1)) <= power_of_two) ++l;
  return l;
}

// The AMR's levels for a field: level l samples every step(l) voxels.
struct AmrLayout {
  int block_voxels = 1;
  int finest = 0;  // the field's finest resolution level
  [[nodiscard]] int step(int l) const { return std::max(1, block_voxels >> (l + 1)); }
  // The level at which a block's shortest edge is 2 steps.
  [[nodiscard]] int levelOf(const FieldBlock& b) const {
    const int shortest = std::max(1, std::min({b.size[0], b.size[1], b.size[2]}));
    return std::clamp(log2Of(block_voxels / shortest), 0, finest);
  }
  // Level l's blocks (l ≥ 1): per coarse block, the box around the level-l cubes (edge
  // block_voxels / 2^l) that meet a final block of level ≥ l. A level-l cube lies in a
  // level-(l-1) cube that meets the same final block, so each box lies in its coarse block's
  // box of the level below.
  [[nodiscard]] std::vector<LatticeBox> boxes(const std::vector<FieldBlock>& blocks, int l,
                                              const std::array<int, 3>& coarse_count) const {
    const int cube = std::max(1, block_voxels >> l);
    std::map<std::int64_t, LatticeBox> by_coarse;  // ordered: the same files for any run
    for (const FieldBlock& b : blocks) {
      if (levelOf(b) < l) continue;
      std::array<int, 3> c{};
      LatticeBox box;
      for (int a = 0; a < 3; ++a) {
        c[a] = b.origin[a] / block_voxels;
        box.lo[a] = b.origin[a] / cube * cube;
        box.hi[a] = (b.origin[a] + b.size[a] + cube - 1) / cube * cube;
      }
      const std::int64_t key =
          (static_cast<std::int64_t>(c[2]) * coarse_count[1] + c[1]) * coarse_count[0] + c[0];
      auto [it, fresh] = by_coarse.try_emplace(key, box);
      if (!fresh) {
        for (int a = 0; a < 3; ++a) {
          it->second.lo[a] = std::min(it->second.lo[a], box.lo[a]);
          it->second.hi[a] = std::max(it->second.hi[a], box.hi[a]);
        }
      }
    }
    std::vector<LatticeBox> out;
    out.reserve(by_coarse.size());
    for (const auto& kv : by_coarse) out.push_back(kv.second);
    return out;
  }
};

AmrLayout amrLayout(const ObserverField& field) {
  AmrLayout layout;
  layout.block_voxels = std::max(1, field.spec().block_voxels);
  layout.finest = std::max(0, log2Of(layout.block_voxels) - 1);
  int finest = 0;
  for (const FieldBlock& b : field.blocks()) finest = std::max(finest, layout.levelOf(b));
  layout.finest = finest;
  return layout;
}

double pointsOf(const LatticeBox& box, int step) {
  double p = 1.0;
  for (int a = 0; a < 3; ++a) p *= (box.hi[a] - box.lo[a]) / step + 1;
  return p;
}

// Level 0 (the whole box) and the finer levels that keep within the budget.
std::vector<std::vector<LatticeBox>> amrBoxes(const ObserverField& field) {
  const AmrLayout layout = amrLayout(field);
  const auto n = field.spec().nodes();
  std::array<int, 3> coarse_count{};
  LatticeBox whole;
  for (int a = 0; a < 3; ++a) {
    whole.hi[a] = n[a] - 1;
    coarse_count[a] = std::max(1, (n[a] - 1 + layout.block_voxels - 1) / layout.block_voxels);
  }
  std::vector<std::vector<LatticeBox>> levels{{whole}};
  double points = pointsOf(whole, layout.step(0));
  std::size_t files = 1;
  for (int l = 1; l <= layout.finest; ++l) {
    std::vector<LatticeBox> boxes = layout.boxes(field.blocks(), l, coarse_count);
    for (const LatticeBox& b : boxes) points += pointsOf(b, layout.step(l));
    files += boxes.size();
    if (boxes.empty() || points > kAmrPointBudget || files > kAmrFileBudget) break;
    levels.push_back(std::move(boxes));
  }
  return levels;
}

// A random name for a staging folder: `.<name>.glint-<pid>-<8 characters>`, the pattern of
// AtomicFile's temporaries, so removeStaleTemporaries() knows it.
std::filesystem::path stagingName(const std::filesystem::path& target) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789";
  thread_local std::mt19937_64 rng{std::random_device{}()};
  std::string name =
      "." + target.filename().string() + ".glint-" + std::to_string(::getpid()) + "-";
  for (int i = 0; i < 8; ++i) name += kAlphabet[rng() % (sizeof kAlphabet - 1)];
  std::filesystem::path folder = target.parent_path();
  return (folder.empty() ? std::filesystem::path(".") : folder) / name;
}

}  // namespace

void writeVti(std::ostream& out, const ObserverField& field, int stride,
              const std::vector<ScaledArray>& scaled) {
  const FieldSpec& spec = field.spec();
  const auto n = spec.nodes();
  std::array<int, 3> m{};
  for (int a = 0; a < 3; ++a) m[a] = (n[a] - 1) / stride + 1;
  const auto count = static_cast<vtkIdType>(m[0]) * m[1] * m[2];
  auto irradiance = namedArray<vtkFloatArray>("irradiance_w_m2", count);
  auto level = namedArray<vtkIntArray>("refinement_level", count);
  auto status = namedArray<vtkIntArray>("status", count);
  float* e = irradiance->GetPointer(0);
  int* lv = level->GetPointer(0);
  int* st = status->GetPointer(0);
  const auto& g = field.grids();
  auto ia = g.irradiance->getConstAccessor();
  auto la = g.level->getConstAccessor();
  auto sa = g.status->getConstAccessor();
  vtkIdType p = 0;
  for (int k = 0; k < m[2]; ++k)
    for (int j = 0; j < m[1]; ++j)
      for (int i = 0; i < m[0]; ++i, ++p) {
        const openvdb::Coord c(i * stride, j * stride, k * stride);
        e[p] = ia.isValueOn(c) ? ia.getValue(c) : 0.0f;
        lv[p] = static_cast<int>(std::lround(la.getValue(c)));
        st[p] = static_cast<int>(std::lround(sa.getValue(c)));
      }
  vtkNew<vtkImageData> image;
  image->SetDimensions(m[0], m[1], m[2]);
  image->SetOrigin(spec.min_m.x, spec.min_m.y, spec.min_m.z);
  const double h = spec.voxel_m * stride;
  image->SetSpacing(h, h, h);
  vtkPointData* data = image->GetPointData();
  data->AddArray(irradiance);
  addScaledArrays(*data, e, count, scaled);
  {
    const std::vector<float> most = field.upperLattice(stride);
    auto upper = namedArray<vtkFloatArray>("irradiance_upper_w_m2", count);
    std::copy(most.begin(), most.end(), upper->GetPointer(0));
    data->AddArray(upper);
  }
  data->AddArray(level);
  data->AddArray(status);
  data->SetActiveScalars("irradiance_w_m2");
  vtkNew<vtkXMLImageDataWriter> writer;
  writeTo(out, *writer, image, "the box's ImageData (.vti)");
}

void writeBlocksVtu(std::ostream& out, const ObserverField& field,
                    const std::vector<ScaledArray>& scaled) {
  const FieldSpec& spec = field.spec();
  auto ia = field.grids().irradiance->getConstAccessor();
  std::vector<double> points;
  std::vector<float> irradiance;
  std::vector<std::int64_t> connectivity, offsets{0};
  std::vector<int> level, status;
  // VTK_HEXAHEDRON corner order.
  constexpr int kCorner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                 {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  auto cell = [&](const FieldBlock& b) {
    for (const auto& c : kCorner) {
      const int i = b.origin[0] + c[0] * b.size[0], j = b.origin[1] + c[1] * b.size[1],
                k = b.origin[2] + c[2] * b.size[2];
      const Vec3 x = spec.position(i, j, k);
      points.insert(points.end(), {x.x, x.y, x.z});
      const openvdb::Coord q(i, j, k);
      irradiance.push_back(ia.isValueOn(q) ? ia.getValue(q) : 0.0f);
      connectivity.push_back(static_cast<std::int64_t>(connectivity.size()));
    }
    offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
    level.push_back(b.level);
    status.push_back(static_cast<int>(b.status));
  };
  for (const FieldBlock& b : field.blocks()) {
    if (!integratedHere(b.status) || b.size != std::array<int, 3>{2, 2, 2}) {
      cell(b);
      continue;
    }
    // A finest block (every lattice point evaluated) shows them all: one cell per voxel.
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j)
        for (int k = 0; k < 2; ++k) {
          cell({{b.origin[0] + i, b.origin[1] + j, b.origin[2] + k}, {1, 1, 1}, b.level, b.status});
        }
  }
  vtkNew<vtkUnstructuredGrid> grid;
  grid->SetPoints(pointsOf(points));
  grid->SetCells(VTK_HEXAHEDRON, cellArray(offsets, connectivity));
  const auto n_points = static_cast<vtkIdType>(irradiance.size());
  auto e = namedArray<vtkFloatArray>("irradiance_w_m2", n_points);
  std::copy(irradiance.begin(), irradiance.end(), e->GetPointer(0));
  grid->GetPointData()->AddArray(e);
  addScaledArrays(*grid->GetPointData(), irradiance.data(), n_points, scaled);
  grid->GetPointData()->SetActiveScalars("irradiance_w_m2");
  const auto n_cells = static_cast<vtkIdType>(level.size());
  auto lv = namedArray<vtkIntArray>("refinement_level", n_cells);
  auto st = namedArray<vtkIntArray>("status", n_cells);
  std::copy(level.begin(), level.end(), lv->GetPointer(0));
  std::copy(status.begin(), status.end(), st->GetPointer(0));
  grid->GetCellData()->AddArray(lv);
  grid->GetCellData()->AddArray(st);
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  writeTo(out, *writer, grid, "the final blocks' UnstructuredGrid (.vtu)");
}

void writeTargetVtp(std::ostream& out, const FacetIntegrator& integrator, int level) {
  const Target& target = integrator.target();
  const Beam& beam = integrator.beam();
  const NormalModel normals = integrator.options().normals;
  std::vector<double> points;
  std::vector<std::int64_t> connectivity, offsets{0};
  std::vector<double> power;
  std::vector<int> coarse;
  std::vector<SubFacet> pieces;
  for (std::uint32_t f = 0; f < target.facetCount(); ++f) {
    const Vec3 origin = target.objects[target.object[f]].origin_m;
    subFacetsAtDepth(target, f, level, pieces);
    for (const SubFacet& s : pieces) {
      const PatchGeometry g = patchGeometry(target, s, normals);
      const Vec3 centre = g.centre_m + origin;
      const Beam::Sample at = beam.at(centre);
      power.push_back(at.irradiance_w_m2 * g.area_m2 *
                      std::max(0.0, glm::dot(g.normal, at.toward_laser)));
      coarse.push_back(static_cast<int>(f));
      for (const Vec3& corner : s.corner_m) {
        const Vec3 x = corner + origin;
        connectivity.push_back(static_cast<std::int64_t>(points.size() / 3));
        points.insert(points.end(), {x.x, x.y, x.z});
      }
      offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
    }
  }
  vtkNew<vtkPolyData> poly;
  poly->SetPoints(pointsOf(points));
  poly->SetPolys(cellArray(offsets, connectivity));
  const auto n_cells = static_cast<vtkIdType>(power.size());
  auto p = namedArray<vtkDoubleArray>("incident_power_w", n_cells);
  std::copy(power.begin(), power.end(), p->GetPointer(0));
  auto c = namedArray<vtkIntArray>("coarse_facet", n_cells);
  std::copy(coarse.begin(), coarse.end(), c->GetPointer(0));
  poly->GetCellData()->AddArray(p);
  poly->GetCellData()->AddArray(c);
  poly->GetCellData()->SetActiveScalars("incident_power_w");
  vtkNew<vtkXMLPolyDataWriter> writer;
  writeTo(out, *writer, poly, "the target's PolyData (.vtp)");
}

namespace {

// A surface of quads over @p points_m, to which the caller adds its point data.
vtkSmartPointer<vtkPolyData> quadSurface(const std::vector<Vec3>& points_m,
                                         const std::vector<std::array<std::int64_t, 4>>& quads) {
  std::vector<double> points;
  points.reserve(3 * points_m.size());
  for (const Vec3& p : points_m) points.insert(points.end(), {p.x, p.y, p.z});
  std::vector<std::int64_t> connectivity, offsets{0};
  connectivity.reserve(4 * quads.size());
  for (const auto& q : quads) {
    connectivity.insert(connectivity.end(), q.begin(), q.end());
    offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
  }
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  poly->SetPoints(pointsOf(points));
  poly->SetPolys(cellArray(offsets, connectivity));
  return poly;
}

}  // namespace

void writeHazardSurfaceVtp(std::ostream& out, const HazardSurface& surface) {
  const vtkSmartPointer<vtkPolyData> poly = quadSurface(surface.points_m, surface.quads);
  const auto n = static_cast<vtkIdType>(surface.points_m.size());
  auto nohd = namedArray<vtkFloatArray>("nohd_m", n);
  auto intensity = namedArray<vtkFloatArray>("intensity_w_sr", n);
  auto beyond = namedArray<vtkUnsignedCharArray>("beyond_far_radius", n);
  std::copy(surface.nohd_m.begin(), surface.nohd_m.end(), nohd->GetPointer(0));
  std::copy(surface.intensity_w_sr.begin(), surface.intensity_w_sr.end(), intensity->GetPointer(0));
  std::copy(surface.beyond_far_radius.begin(), surface.beyond_far_radius.end(),
            beyond->GetPointer(0));
  poly->GetPointData()->AddArray(nohd);
  poly->GetPointData()->AddArray(intensity);
  poly->GetPointData()->AddArray(beyond);
  poly->GetPointData()->SetActiveScalars("nohd_m");
  vtkNew<vtkXMLPolyDataWriter> writer;
  writeTo(out, *writer, poly, "the far field's hazard surface (.vtp)");
}

void writeReachVtp(std::ostream& out, const ReachSurface& surface) {
  const vtkSmartPointer<vtkPolyData> poly = quadSurface(surface.points_m, surface.quads);
  const auto n = static_cast<vtkIdType>(surface.points_m.size());
  auto distance = namedArray<vtkFloatArray>("distance_m", n);
  auto ratio = namedArray<vtkFloatArray>("hazard_ratio", n);
  std::copy(surface.distance_m.begin(), surface.distance_m.end(), distance->GetPointer(0));
  std::copy(surface.hazard_ratio.begin(), surface.hazard_ratio.end(), ratio->GetPointer(0));
  poly->GetPointData()->AddArray(distance);
  poly->GetPointData()->AddArray(ratio);
  poly->GetPointData()->SetActiveScalars("distance_m");
  vtkNew<vtkXMLPolyDataWriter> writer;
  writeTo(out, *writer, poly, "the hazard reach's surface (.vtp)");
}

// --- The AMR data set.

StagedAmr::StagedAmr(std::filesystem::path staging, std::filesystem::path vthb_path)
    : staging_(std::move(staging)),
      target_(std::move(vthb_path)),
      interrupt_slot_(removeOnInterrupt(staging_, InterruptCleanup::RemoveTree)) {}

StagedAmr::StagedAmr(StagedAmr&& other) noexcept
    : staging_(std::move(other.staging_)),
      target_(std::move(other.target_)),
      interrupt_slot_(other.interrupt_slot_) {
  other.staging_.clear();
  other.interrupt_slot_ = -1;
}

StagedAmr::~StagedAmr() {
  if (staging_.empty()) return;  // moved from
  // Whatever is left: the uncommitted data set, or the earlier one it replaced.
  std::error_code ignored;
  std::filesystem::remove_all(staging_, ignored);
  forgetOnInterrupt(interrupt_slot_);
}

void StagedAmr::addTo(OutputSet& outputs) const {
  // VTK names the block folder after the .vthb's stem.
  const std::filesystem::path folder = std::filesystem::path(target_).replace_extension();
  outputs.addStaged(staging_ / folder.filename(), folder, staging_);
  outputs.addStaged(staging_ / target_.filename(), target_, staging_);
}

void StagedAmr::commit() const {
  OutputSet alone;
  addTo(alone);
  alone.commit();
}

StagedAmr writeAmr(const std::filesystem::path& vthb_path, const ObserverField& field,
                   const std::vector<ScaledArray>& scaled) {
  const FieldSpec& spec = field.spec();
  if (spec.plane) throw std::invalid_argument("writeAmr: a box's field, not a plane's");
  const AmrLayout layout = amrLayout(field);
  const std::vector<std::vector<LatticeBox>> levels = amrBoxes(field);

  vtkNew<vtkOverlappingAMR> amr;
  std::vector<int> per_level;
  for (const auto& boxes : levels) per_level.push_back(static_cast<int>(boxes.size()));
  amr->Initialize(static_cast<int>(levels.size()), per_level.data());
  const double origin[3] = {spec.min_m.x, spec.min_m.y, spec.min_m.z};
  amr->SetOrigin(origin);
  auto ia = field.grids().irradiance->getConstAccessor();
  for (std::size_t l = 0; l < levels.size(); ++l) {
    const int step = layout.step(static_cast<int>(l));
    const double h = spec.voxel_m * step;
    const double spacing[3] = {h, h, h};
    amr->SetSpacing(static_cast<unsigned>(l), spacing);
    for (std::size_t b = 0; b < levels[l].size(); ++b) {
      const LatticeBox& box = levels[l][b];
      std::array<int, 3> cells{}, lo{}, hi{};
      for (int a = 0; a < 3; ++a) {
        cells[a] = (box.hi[a] - box.lo[a]) / step;
        lo[a] = box.lo[a] / step;  // in the level's own cells
        hi[a] = lo[a] + cells[a] - 1;
      }
      amr->SetAMRBox(static_cast<unsigned>(l), static_cast<unsigned>(b),
                     vtkAMRBox(lo.data(), hi.data()));
      vtkNew<vtkUniformGrid> grid;
      const Vec3 corner = spec.position(box.lo[0], box.lo[1], box.lo[2]);
      grid->SetOrigin(corner.x, corner.y, corner.z);
      grid->SetSpacing(h, h, h);
      grid->SetDimensions(cells[0] + 1, cells[1] + 1, cells[2] + 1);
      const vtkIdType count = grid->GetNumberOfPoints();
      auto e = namedArray<vtkFloatArray>("irradiance_w_m2", count);
      float* v = e->GetPointer(0);
      vtkIdType p = 0;
      for (int k = box.lo[2]; k <= box.hi[2]; k += step)
        for (int j = box.lo[1]; j <= box.hi[1]; j += step)
          for (int i = box.lo[0]; i <= box.hi[0]; i += step, ++p) {
            const openvdb::Coord c(i, j, k);
            v[p] = ia.isValueOn(c) ? ia.getValue(c) : 0.0f;
          }
      grid->GetPointData()->AddArray(e);
      addScaledArrays(*grid->GetPointData(), v, count, scaled);
      grid->GetPointData()->SetActiveScalars("irradiance_w_m2");
      amr->SetDataSet(static_cast<unsigned>(l), static_cast<unsigned>(b), grid);
    }
  }
  // The refinement ratios, parents and children, and the coarse cells a finer level covers
  // marked hidden (vtkGhostType), so that ParaView shows each place once, at its finest.
  vtkAMRUtilities::BlankCells(amr);

  // Staged whole in a folder of its own beside the target (the same file system, so the
  // commit is renames only).
  std::filesystem::path staging;
  std::error_code ec;
  bool made = false;
  for (int attempt = 0; attempt < 100 && !made && !ec; ++attempt) {
    staging = stagingName(vthb_path);
    made = std::filesystem::create_directory(staging, ec);  // false: the name was taken
  }
  if (!made) {
    throw OutputError("cannot create " + vthb_path.string() +
                      " (is the folder there and writable?): " + ec.message());
  }
  StagedAmr staged(staging, vthb_path);
  vtkNew<vtkXMLUniformGridAMRWriter> writer;
  configure(*writer);
  writer->SetInputData(amr);
  writer->SetFileName((staging / vthb_path.filename()).c_str());
  runWriter(*writer, vthb_path.string());
  return staged;
}

int amrLevels(const ObserverField& field) { return static_cast<int>(amrBoxes(field).size()); }

}  // namespace glint
