#include "pipeline/run_outputs.h"

#include <algorithm>

#include "export/atomic_file.h"
#include "export/vtk_files.h"
#include "facets/integrator.h"
#include "pipeline/hazard_report.h"
#include "pipeline/input_files.h"
#include "pipeline/output_names.h"
#include "pipeline/scene.h"

namespace glint {
namespace {

// The largest power-of-two stride that keeps the .vti resample under 16.7 M points.
int vtiStride(const FieldSpec& spec) {
  const auto n = spec.nodes();
  int stride = 1;
  auto points = [&](int s) {
    double p = 1.0;
    for (int a = 0; a < 3; ++a) p *= (n[a] - 1) / s + 1;
    return p;
  };
  while (points(stride) > 16.7e6 && stride < spec.block_voxels) stride *= 2;
  return stride;
}

// The far field's hazard surface: at most 128² directions a face.
int surfacePixels(const FarField& far) { return std::min(far.spec().face_pixels, 128); }

void writeFarExr(std::ostream& out, const FarResults& r) {
  const HazardSpec& h = r.hazard;
  const double mpe = r.info.mpe_w_m2;
  const LatLongMap map = latLongMap(r.far, farMapHeight(r.far.spec().face_pixels), mpe,
                                    h.atmosphere.extinction_per_m, h.aid ? h.aidedMpeW_m2() : 0.0);
  std::vector<ExrChannel> channels = {{"intensity_w_sr", &map.intensity_w_sr},
                                      {"nohd_m", &map.nohd_m}};
  if (h.aid) channels.push_back({"aided_nohd_m", &map.aided_nohd_m});
  writeLatLongExr(out, {map.width, map.height, r.far.ball().centre_m, r.far.spec().far_radius_m},
                  channels, exrInfo(r.info));
}

void writeFarVtp(std::ostream& out, const FarResults& r, double threshold_w_m2) {
  writeHazardSurfaceVtp(out, hazardSurface(r.far, surfacePixels(r.far), threshold_w_m2,
                                           r.hazard.atmosphere.extinction_per_m));
}

}  // namespace

// Every output of glint run but the planes' maps (one per plane, after these): its name, the
// region it is written from and its writer. A region's files are written in this order, but
// for the one that takes the field's grids, written last.
struct RunOutputs::Declared {
  enum class Region { Run, Box, Far };
  const char* name;
  Region region;
  void (*box)(std::ostream&, BoxResults&) = nullptr;
  void (*far)(std::ostream&, const FarResults&) = nullptr;
  bool takes_field = false;    // the box's VDB moves the grids out of the field
  bool staged_folder = false;  // the AMR data set: a folder staged beside its .vthb
  bool aided_only = false;     // written with an optical aid only

  [[nodiscard]] bool wanted(const Scene& s) const {
    switch (region) {
      case Region::Run:
        return true;
      case Region::Box:
        return s.observers.has_value();
      case Region::Far:
        return s.far_field.enabled && (!aided_only || s.hazard.aid.has_value());
    }
    return false;
  }
};

namespace {

using Region = RunOutputs::Declared::Region;

constexpr RunOutputs::Declared kOutputs[] = {
    {.name = output_names::kSummary, .region = Region::Run},
    {.name = output_names::kIrradianceVdb,
     .region = Region::Box,
     .box = [](std::ostream& out, BoxResults& b) { writeVdb(out, std::move(b.field), b.info); },
     .takes_field = true},
    {.name = output_names::kIrradianceVti,
     .region = Region::Box,
     .box =
         [](std::ostream& out, BoxResults& b) {
           writeVti(out, b.field, vtiStride(b.field.spec()), b.info.scaled);
         }},
    {.name = output_names::kBlocksVtu,
     .region = Region::Box,
     .box = [](std::ostream& out, BoxResults& b) { writeBlocksVtu(out, b.field, b.info.scaled); }},
    {.name = output_names::kTargetVtp,
     .region = Region::Box,
     .box = [](std::ostream& out, BoxResults& b) { writeTargetVtp(out, b.integrator, 2); }},
    {.name = output_names::kIrradianceAmr, .region = Region::Box, .staged_folder = true},
    {.name = output_names::kFarFieldExr, .region = Region::Far, .far = writeFarExr},
    {.name = output_names::kFarFieldVtp,
     .region = Region::Far,
     .far = [](std::ostream& out, const FarResults& f) { writeFarVtp(out, f, f.info.mpe_w_m2); }},
    {.name = output_names::kFarFieldAidedVtp,
     .region = Region::Far,
     .far = [](std::ostream& out,
               const FarResults& f) { writeFarVtp(out, f, f.hazard.aidedMpeW_m2()); },
     .aided_only = true},
};

}  // namespace

RunOutputs::RunOutputs(const Scene& scene, const std::filesystem::path& dir,
                       const InputFiles& inputs, bool writer)
    : dir_(dir), writer_(writer), scene_(scene) {
  auto declare = [&](const std::string& name, const Declared* d) {
    names_.push_back(name);
    declared_.push_back(d);
    const bool folder = d != nullptr && d->staged_folder;
    if (!writer_ || folder) {
      files_.push_back(nullptr);
      return;
    }
    inputs.requireNotAnInput(dir_ / name);  // a hard link to an input, named otherwise
    files_.push_back(std::make_unique<AtomicFile>(dir_ / name));
  };
  for (const Declared& d : kOutputs) {
    if (!d.wanted(scene)) continue;
    declare(d.name, &d);
    if (d.region == Region::Far) far_names_.emplace_back(d.name);
  }
  for (const PlaneSpec& plane : scene.planes) declare(output_names::planeExr(plane.name), nullptr);
}

RunOutputs::~RunOutputs() = default;

std::ostream* RunOutputs::summary() {
  return writer_ && files_.at(0) ? &files_[0]->stream() : nullptr;
}

void RunOutputs::writeBox(BoxResults& box) {
  if (!writer_) return;
  std::optional<std::size_t> last;
  for (std::size_t i = 0; i < names_.size(); ++i) {
    const Declared* d = declared_[i];
    if (d == nullptr || d->region != Region::Box) continue;
    if (d->staged_folder) {
      amr_ = std::make_unique<StagedAmr>(writeAmr(dir_ / names_[i], box.field, box.info.scaled));
    } else if (d->takes_field) {
      last = i;
    } else {
      d->box(files_[i]->stream(), box);
    }
  }
  if (last) declared_[*last]->box(files_[*last]->stream(), box);
}

void RunOutputs::writePlane(std::size_t index, const PlaneResults& plane) {
  if (!writer_) return;
  // The planes' maps follow the declared outputs, in the scene's order.
  const std::size_t i = names_.size() - scene_.planes.size() + index;
  writePlaneExr(files_.at(i)->stream(), plane.field, plane.hazard, plane.info);
}

void RunOutputs::writeFar(const FarResults& far) {
  if (!writer_) return;
  for (std::size_t i = 0; i < names_.size(); ++i) {
    const Declared* d = declared_[i];
    if (d != nullptr && d->region == Region::Far) d->far(files_[i]->stream(), far);
  }
}

void RunOutputs::commit() {
  for (const auto& f : files_) {
    if (f) f->commit();
  }
  if (amr_) amr_->commit();
}

ExrInfo exrInfo(const RunInfo& info) {
  return {info.program_version, info.wavelength_nm, info.mpe_w_m2};
}

PlaneMap writePlaneExr(std::ostream& out, const ObserverField& field, const HazardSpec& hazard,
                       const RunInfo& info) {
  PlaneMap map = planeMap(field, hazard);
  writeExr(out, map, exrInfo(info));
  return map;
}

}  // namespace glint
