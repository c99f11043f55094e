#include "export/field_files.h"

#include <openvdb/io/Archive.h>
#include <openvdb/io/GridDescriptor.h>
#include <openvdb/io/io.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "observers/field_grids.h"

namespace glint {
namespace {

// Standard base64 (RFC 4648) of @p n bytes at @p data, appended to @p out.
void appendBase64(const char* data, std::size_t n, std::string& out) {
  static constexpr char kDigits[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* b = reinterpret_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < n; i += 3) {
    const std::size_t left = n - i;
    const unsigned v = (static_cast<unsigned>(b[i]) << 16) |
                       (left > 1 ? static_cast<unsigned>(b[i + 1]) << 8 : 0u) |
                       (left > 2 ? static_cast<unsigned>(b[i + 2]) : 0u);
    out += kDigits[(v >> 18) & 63];
    out += kDigits[(v >> 12) & 63];
    out += left > 1 ? kDigits[(v >> 6) & 63] : '=';
    out += left > 2 ? kDigits[v & 63] : '=';
  }
}

// A <DataArray> of VTK XML in the inline binary format (header_type UInt64): the array's byte
// count and bytes as one base64 stream inside the element. Appended data would be smaller, but
// since expat 2.6 (and Debian 12's security update 2.5.0-1+deb12u5) VTK's XML reader fails on
// any <AppendedData> section, raw or base64 ("not well-formed (invalid token)", "junk after
// document element"; VTK issue 19258): ParaView 5.11 on an up-to-date Debian 12 could not open
// such files. Inline base64 is plain XML character data and reads everywhere.
template <class T>
std::string dataArray(const std::string& name, const char* vtk_type, int components,
                      const std::vector<T>& values) {
  const std::uint64_t bytes = values.size() * sizeof(T);
  std::string block(sizeof bytes + bytes, '\0');
  std::memcpy(block.data(), &bytes, sizeof bytes);
  if (bytes > 0) std::memcpy(block.data() + sizeof bytes, values.data(), bytes);
  std::string xml = "<DataArray type=\"" + std::string(vtk_type) + "\" Name=\"" + name +
                    "\" NumberOfComponents=\"" + std::to_string(components) +
                    "\" format=\"binary\">\n";
  xml.reserve(xml.size() + 4 * ((block.size() + 2) / 3) + 16);
  appendBase64(block.data(), block.size(), xml);
  xml += "\n</DataArray>\n";
  return xml;
}

const char* kHeader =
    "<?xml version=\"1.0\"?>\n<VTKFile type=\"%s\" version=\"1.0\" byte_order=\"LittleEndian\" "
    "header_type=\"UInt64\">\n";

std::string header(const char* type) {
  char buf[256];
  std::snprintf(buf, sizeof buf, kHeader, type);
  return buf;
}

// OpenVDB's Stream::write takes every grid of a file at once, so each must exist whole at
// the same time; this writes the same bytes one grid at a time (io::Archive's own steps, for
// grids that share no tree and have distinct names), so a grid can be freed or reused as the
// next one once written.
class GridByGridWriter : private openvdb::io::Archive {
 public:
  GridByGridWriter(std::ostream& out, const openvdb::MetaMap& meta, std::int32_t grids)
      : out_(out), left_(grids), stream_meta_(openvdb::io::getStreamMetadataPtr(out)) {
    if (!stream_meta_) {
      // The stream keeps only a raw pointer to it: ours to keep alive until the last grid.
      stream_meta_ = std::make_shared<openvdb::io::StreamMetadata>();
      openvdb::io::setStreamMetadataPtr(out, stream_meta_, /*transfer=*/false);
      owns_stream_meta_ = true;
    }
    openvdb::io::setDataCompression(out, compression());
    openvdb::io::setWriteGridStatsMetadata(out, isGridStatsMetadataEnabled());
    writeHeader(out, /*seekable=*/false);
    meta.writeMeta(out);
    out.write(reinterpret_cast<const char*>(&grids), sizeof grids);
  }

  void write(const openvdb::GridBase::ConstPtr& grid) {
    if (left_-- <= 0) throw std::logic_error("GridByGridWriter: more grids than announced");
    openvdb::io::GridDescriptor descriptor(grid->getName(), grid->type(), grid->saveFloatAsHalf());
    writeGrid(descriptor, grid, out_, /*seekable=*/false);
    openvdb::io::setDataCompression(out_, compression());  // as Archive: some flags are per grid
  }

  void finish() const {
    if (left_ != 0) throw std::logic_error("GridByGridWriter: fewer grids than announced");
  }

  ~GridByGridWriter() override {
    if (owns_stream_meta_) openvdb::io::clearStreamMetadataPtr(out_);
  }
  GridByGridWriter(const GridByGridWriter&) = delete;
  GridByGridWriter& operator=(const GridByGridWriter&) = delete;

 private:
  std::ostream& out_;
  std::int32_t left_;
  openvdb::io::StreamMetadata::Ptr stream_meta_;
  bool owns_stream_meta_ = false;
};

}  // namespace

std::vector<float> hazardRatio(const std::vector<float>& irradiance_w_m2, double mpe_w_m2) {
  std::vector<float> ratio(irradiance_w_m2.size());
  for (std::size_t i = 0; i < ratio.size(); ++i) {
    ratio[i] = static_cast<float>(static_cast<double>(irradiance_w_m2[i]) / mpe_w_m2);
  }
  return ratio;
}

void writeVdb(std::ostream& out, ObserverField field, const RunInfo& info) {
  const FieldSpec& spec = field.spec();
  const FieldStats& stats = field.stats();
  openvdb::MetaMap meta;
  meta.insertMeta("program", openvdb::StringMetadata(info.program_version));
  meta.insertMeta("scene_file", openvdb::StringMetadata(info.scene_file));
  meta.insertMeta("scene_fnv1a64", openvdb::StringMetadata(info.scene_fnv1a64));
  meta.insertMeta("scheme", openvdb::StringMetadata(info.scheme));
  meta.insertMeta("length_unit", openvdb::StringMetadata("m"));
  meta.insertMeta("irradiance_unit", openvdb::StringMetadata("W/m^2"));
  meta.insertMeta("wavelength_nm", openvdb::DoubleMetadata(info.wavelength_nm));
  meta.insertMeta("power_w", openvdb::DoubleMetadata(info.power_w));
  const bool hazard = info.mpe_w_m2 > 0.0;
  const bool aided = hazard && info.aid_gain > 0.0;
  if (aided) meta.insertMeta("optical_aid_gain", openvdb::DoubleMetadata(info.aid_gain));
  if (hazard) {
    meta.insertMeta("exposure_s", openvdb::DoubleMetadata(info.exposure_s));
    meta.insertMeta("mpe_w_m2", openvdb::DoubleMetadata(info.mpe_w_m2));
    meta.insertMeta("mpe_rule", openvdb::StringMetadata(info.mpe_rule));
  }
  meta.insertMeta("tolerance", openvdb::DoubleMetadata(spec.tolerance));
  meta.insertMeta("floor_w_m2", openvdb::DoubleMetadata(spec.floor_w_m2));
  meta.insertMeta("voxel_m", openvdb::DoubleMetadata(spec.voxel_m));
  meta.insertMeta("evaluations", openvdb::Int64Metadata(stats.evaluations));
  meta.insertMeta("evaluated_points", openvdb::Int64Metadata(stats.evaluated_points));
  meta.insertMeta("peak_irradiance_w_m2", openvdb::DoubleMetadata(stats.peak_w_m2));

  FieldGrids& g = field.grids();
  GridByGridWriter file(out, meta, 3 + (hazard ? 1 : 0) + (aided ? 1 : 0));
  // A shallow copy (the same tree) carries the irradiance's metadata: the grid itself goes on
  // to become the hazard ratio.
  {
    auto irradiance = g.irradiance->copyGrid();
    irradiance->insertMeta("units", openvdb::StringMetadata("W/m^2"));
    file.write(irradiance);
  }
  if (hazard) {
    openvdb::FloatGrid::Ptr ratio = std::move(g.irradiance);
    for (auto it = ratio->beginValueOn(); it; ++it) {
      it.setValue(static_cast<float>(static_cast<double>(*it) / info.mpe_w_m2));
    }
    ratio->setName("hazard_ratio");
    ratio->insertMeta("units", openvdb::StringMetadata("1 (irradiance / MPE)"));
    file.write(ratio);
    if (aided) {  // once written, the ratio grid goes on to become the aided one
      auto aided_ratio = ratio->copyGrid();
      for (auto it = ratio->beginValueOn(); it; ++it) {
        it.setValue(static_cast<float>(static_cast<double>(*it) * info.aid_gain));
      }
      aided_ratio->setName("aided_hazard_ratio");
      aided_ratio->insertMeta("units",
                              openvdb::StringMetadata("1 (irradiance x optical aid gain / MPE)"));
      file.write(aided_ratio);
    }
  }
  g.irradiance.reset();
  {
    openvdb::FloatGrid::Ptr level = std::move(g.level);
    level->insertMeta("meaning", openvdb::StringMetadata("refinement level, 0 = coarsest block"));
    file.write(level);
  }
  openvdb::FloatGrid::Ptr status = std::move(g.status);
  status->insertMeta("meaning",
                     openvdb::StringMetadata(
                         "0 outside the box, 1 evaluated, 2 interpolated, 3 proven "
                         "below floor_w_m2 (not computed), 4 inside or on the target, 5 evaluated "
                         "but unconverged (integrator limit reached)"));
  file.write(status);
  file.finish();
}

void writeVti(std::ostream& out, const ObserverField& field, int stride, double mpe_w_m2) {
  const FieldSpec& spec = field.spec();
  const auto n = spec.nodes();
  std::array<int, 3> m{};
  for (int a = 0; a < 3; ++a) m[a] = (n[a] - 1) / stride + 1;
  const std::size_t count = static_cast<std::size_t>(m[0]) * m[1] * m[2];
  std::vector<float> irradiance(count);
  std::vector<std::int32_t> level(count), status(count);
  const auto& g = field.grids();
  auto ia = g.irradiance->getConstAccessor();
  auto la = g.level->getConstAccessor();
  auto sa = g.status->getConstAccessor();
  std::size_t p = 0;
  for (int k = 0; k < m[2]; ++k)
    for (int j = 0; j < m[1]; ++j)
      for (int i = 0; i < m[0]; ++i, ++p) {
        const openvdb::Coord c(i * stride, j * stride, k * stride);
        irradiance[p] = ia.isValueOn(c) ? ia.getValue(c) : 0.0f;
        level[p] = static_cast<std::int32_t>(std::lround(la.getValue(c)));
        status[p] = static_cast<std::int32_t>(std::lround(sa.getValue(c)));
      }
  out << header("ImageData");
  const double h = spec.voxel_m * stride;
  out << "<ImageData WholeExtent=\"0 " << m[0] - 1 << " 0 " << m[1] - 1 << " 0 " << m[2] - 1
      << "\" Origin=\"" << spec.min_m.x << " " << spec.min_m.y << " " << spec.min_m.z
      << "\" Spacing=\"" << h << " " << h << " " << h << "\">\n";
  out << "<Piece Extent=\"0 " << m[0] - 1 << " 0 " << m[1] - 1 << " 0 " << m[2] - 1 << "\">\n";
  out << "<PointData Scalars=\"irradiance_w_m2\">\n";
  out << dataArray("irradiance_w_m2", "Float32", 1, irradiance);
  if (mpe_w_m2 > 0.0) out << dataArray("hazard_ratio", "Float32", 1, hazardRatio(irradiance, mpe_w_m2));
  out << dataArray("refinement_level", "Int32", 1, level);
  out << dataArray("status", "Int32", 1, status);
  out << "</PointData>\n</Piece>\n</ImageData>\n";
  out << "</VTKFile>\n";
}

void writeBlocksVtu(std::ostream& out, const ObserverField& field, double mpe_w_m2) {
  const FieldSpec& spec = field.spec();
  const auto& blocks = field.blocks();
  auto ia = field.grids().irradiance->getConstAccessor();
  std::vector<double> points;
  std::vector<float> irradiance;
  std::vector<std::int64_t> connectivity, offsets;
  std::vector<std::uint8_t> types;
  std::vector<std::int32_t> level, status;
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
    types.push_back(12);  // VTK_HEXAHEDRON
    level.push_back(b.level);
    status.push_back(static_cast<std::int32_t>(b.status));
  };
  for (const FieldBlock& b : blocks) {
    if (b.status != VoxelStatus::Evaluated || b.size != std::array<int, 3>{2, 2, 2}) {
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
  out << header("UnstructuredGrid") << "<UnstructuredGrid>\n";
  out << "<Piece NumberOfPoints=\"" << points.size() / 3 << "\" NumberOfCells=\"" << types.size()
      << "\">\n<Points>\n"
      << dataArray("Points", "Float64", 3, points) << "</Points>\n<Cells>\n"
      << dataArray("connectivity", "Int64", 1, connectivity)
      << dataArray("offsets", "Int64", 1, offsets) << dataArray("types", "UInt8", 1, types)
      << "</Cells>\n<PointData Scalars=\"irradiance_w_m2\">\n"
      << dataArray("irradiance_w_m2", "Float32", 1, irradiance)
      << (mpe_w_m2 > 0.0 ? dataArray("hazard_ratio", "Float32", 1, hazardRatio(irradiance, mpe_w_m2))
                         : std::string())
      << "</PointData>\n<CellData>\n"
      << dataArray("refinement_level", "Int32", 1, level)
      << dataArray("status", "Int32", 1, status) << "</CellData>\n</Piece>\n</UnstructuredGrid>\n";
  out << "</VTKFile>\n";
}

void writeTargetVtp(std::ostream& out, const FacetIntegrator& integrator, int level) {
  const Target& target = integrator.target();
  const Beam& beam = integrator.beam();
  const NormalModel normals = integrator.options().normals;
  std::vector<double> points;
  std::vector<std::int64_t> connectivity, offsets;
  std::vector<double> power;
  std::vector<std::int32_t> coarse;
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
      coarse.push_back(static_cast<std::int32_t>(f));
      for (const Vec3& corner : s.corner_m) {
        const Vec3 x = corner + origin;
        connectivity.push_back(static_cast<std::int64_t>(points.size() / 3));
        points.insert(points.end(), {x.x, x.y, x.z});
      }
      offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
    }
  }
  out << header("PolyData") << "<PolyData>\n";
  out << "<Piece NumberOfPoints=\"" << points.size() / 3 << "\" NumberOfPolys=\"" << power.size()
      << "\">\n<Points>\n"
      << dataArray("Points", "Float64", 3, points) << "</Points>\n<Polys>\n"
      << dataArray("connectivity", "Int64", 1, connectivity)
      << dataArray("offsets", "Int64", 1, offsets)
      << "</Polys>\n<CellData Scalars=\"incident_power_w\">\n"
      << dataArray("incident_power_w", "Float64", 1, power)
      << dataArray("coarse_facet", "Int32", 1, coarse) << "</CellData>\n</Piece>\n</PolyData>\n";
  out << "</VTKFile>\n";
}

void writeHazardSurfaceVtp(std::ostream& out, const HazardSurface& surface) {
  std::vector<double> points;
  points.reserve(3 * surface.points_m.size());
  for (const Vec3& p : surface.points_m) points.insert(points.end(), {p.x, p.y, p.z});
  std::vector<std::int64_t> connectivity, offsets;
  connectivity.reserve(4 * surface.quads.size());
  for (const auto& q : surface.quads) {
    connectivity.insert(connectivity.end(), q.begin(), q.end());
    offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
  }
  out << header("PolyData") << "<PolyData>\n";
  out << "<Piece NumberOfPoints=\"" << surface.points_m.size() << "\" NumberOfPolys=\""
      << surface.quads.size() << "\">\n<Points>\n"
      << dataArray("Points", "Float64", 3, points) << "</Points>\n<Polys>\n"
      << dataArray("connectivity", "Int64", 1, connectivity)
      << dataArray("offsets", "Int64", 1, offsets) << "</Polys>\n<PointData Scalars=\"nohd_m\">\n"
      << dataArray("nohd_m", "Float32", 1, surface.nohd_m)
      << dataArray("intensity_w_sr", "Float32", 1, surface.intensity_w_sr)
      << dataArray("beyond_far_radius", "UInt8", 1, surface.beyond_far_radius)
      << "</PointData>\n</Piece>\n</PolyData>\n";
  out << "</VTKFile>\n";
}

}  // namespace glint
