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

  void append(const openvdb::GridBase::ConstPtr& grid) {
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
  if (info.optical_aid_gain > 0.0) {
    meta.insertMeta("optical_aid_gain", openvdb::DoubleMetadata(info.optical_aid_gain));
  }
  if (info.mpe_w_m2 > 0.0) {
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
  GridByGridWriter file(out, meta, 4 + static_cast<int>(info.scaled.size()));
  // A shallow copy (the same tree) carries the irradiance's metadata: the grid itself goes on
  // to become each scaled grid in turn.
  {
    auto irradiance = g.irradiance->copyGrid();
    irradiance->insertMeta("units", openvdb::StringMetadata("W/m^2"));
    file.append(irradiance);
  }
  double scale = 1.0;  // what the grid's values are, per W/m² of irradiance
  for (const ScaledArray& a : info.scaled) {
    const double factor = a.per_w_m2 / scale;
    for (auto it = g.irradiance->beginValueOn(); it; ++it) {
      it.setValue(static_cast<float>(static_cast<double>(*it) * factor));
    }
    scale = a.per_w_m2;
    auto grid = g.irradiance->copyGrid();
    grid->setName(a.name);
    grid->insertMeta("units", openvdb::StringMetadata(a.units));
    file.append(grid);
  }
  g.irradiance.reset();
  {
    openvdb::FloatGrid::Ptr level = std::move(g.level);
    level->insertMeta("meaning", openvdb::StringMetadata("refinement level, 0 = coarsest block"));
    file.append(level);
  }
  openvdb::FloatGrid::Ptr status = std::move(g.status);
  status->insertMeta("meaning", openvdb::StringMetadata(voxelStatusMeanings()));
  file.append(status);
  {
    openvdb::FloatGrid::Ptr upper = std::move(g.upper);
    upper->insertMeta("units", openvdb::StringMetadata("W/m^2"));
    upper->insertMeta("meaning", openvdb::StringMetadata(
                                     "at unconverged points (status 5) only: irradiance plus "
                                     "its error estimate, by which the hazard zones count them"));
    file.append(upper);
  }
  file.finish();
}

}  // namespace glint
