#include "pipeline/report/run_outputs.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <optional>
#include <utility>

#include "export/atomic_file.h"
#include "export/geo_files.h"
#include "export/vtk_files.h"
#include "facets/integrator.h"
#include "geo/backend.h"
#include "pipeline/base/memory_model.h"
#include "pipeline/base/number_format.h"
#include "pipeline/base/output_names.h"
#include "pipeline/input/input_files.h"
#include "pipeline/input/scene.h"
#include "pipeline/input/scene_memory.h"
#include "pipeline/report/hazard_report.h"
#include "pipeline/setup/target_builder.h"

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

// The reach per direction on the far field's lat-long map, or finer where the lattice's rays
// are closer than its pixels.
void writeReachExr(std::ostream& out, const ReachResults& r) {
  const double mu = r.hazard.atmosphere.extinction_per_m;
  const int height = std::max(farMapHeight(r.far.spec().face_pixels), 2 * r.near.spec.face_cells);
  const HazardSpec& h = r.hazard;
  std::vector<std::string> names = {"reach_m"};
  if (h.aid) names.emplace_back("aided_reach_m");
  for (const ExposureLevel& l : h.levels) names.push_back(output_names::levelReach(l.name));
  // The far field's pixels found once for every threshold, and let go before the file is made.
  const std::vector<std::vector<float>> maps = [&] {
    const LatLongIntensity beyond = latLongIntensity(r.far, height);
    std::vector<std::vector<float>> all;
    for (std::size_t t = 0; t < names.size(); ++t)
      all.push_back(reachLatLong(r.near, r.far, beyond, t, mu));
    return all;
  }();
  std::vector<ExrChannel> channels;
  for (std::size_t t = 0; t < names.size(); ++t) channels.push_back({names[t], &maps[t]});
  writeLatLongExr(out, {2 * height, height, r.near.spec.centre_m, r.far.spec().far_radius_m},
                  channels, exrInfo(r.info));
}

void writePlaneExr(std::ostream& out, const PlaneResults& r) {
  writeExr(out, planeMap(r.field, r.hazard), exrInfo(r.info));
}

GeoInfo geoInfo(const PlaneResults& r) {
  return {r.info.program_version, r.plane_name, r.info.mpe_rule, r.info.wavelength_nm,
          r.info.mpe_w_m2};
}

// The plane's map on the site's map: the hazard ratio and the irradiance first, as GIS tools
// show the first band; then the aided ratio (with an aid) and the status codes.
void writePlaneGeoTiff(std::ostream& out, const PlaneResults& r) {
  const PlaneMap m = planeMap(r.field, r.hazard);
  std::vector<ExrChannel> channels = {{"hazard_ratio", &m.hazard_ratio},
                                      {"irradiance_w_m2", &m.irradiance_w_m2}};
  std::vector<std::string> units = {"1 (irradiance / MPE)", "W/m^2"};
  if (r.hazard.aid) {
    channels.push_back({"aided_hazard_ratio", &m.aided_hazard_ratio});
    units.emplace_back("1 (irradiance x optical aid gain / MPE)");
  }
  for (std::size_t k = 0; k < m.level_ratios.size(); ++k) {
    channels.push_back({m.level_ratios[k].first, &m.level_ratios[k].second});
    units.push_back("1 (irradiance / the " + r.hazard.levels[k].name + " level's threshold)");
  }
  channels.push_back({"irradiance_upper_w_m2", &m.irradiance_upper_w_m2});
  units.emplace_back(upperIrradianceMeaning());
  channels.push_back({"status", &m.status});
  units.emplace_back(voxelStatusMeanings());
  if (!m.observer_z_m.empty()) {
    channels.push_back({"observer_z_m", &m.observer_z_m});
    units.emplace_back("m (each observer's height in the site's local frame)");
  }
  writeGeoTiff(out, m, channels, units, *r.site, geoInfo(r));
}

// An engagement's plane on the site's map: every channel of its EXR, and where the worst
// window reaches the MPE (naked eye and aided) as polygons.
const std::vector<float>* channelNamed(const EngagementPlaneResults& r, const std::string& name) {
  for (const ExrChannel& c : r.channels) {
    if (c.name == name) return c.values;
  }
  return nullptr;
}

GeoInfo engagementGeoInfo(const EngagementPlaneResults& r) {
  return {r.info.program_version, r.plane_name, r.info.mpe_rule, r.info.wavelength_nm,
          r.info.mpe_w_m2};
}

void writeEngagementGeoTiff(std::ostream& out, const EngagementPlaneResults& r) {
  std::vector<std::string> units;
  for (const ExrChannel& c : r.channels) {
    const std::string& n = c.name;
    units.emplace_back(n.ends_with("_w_m2")   ? "W/m^2"
                       : n.ends_with("_j_m2") ? "J/m^2"
                       : n.ends_with("_s")    ? "s"
                                              : "1");
  }
  writeGeoTiff(out, r.grid, r.channels, units, *r.site, engagementGeoInfo(r));
}

void writeEngagementZones(std::ostream& out, const EngagementPlaneResults& r, VectorFormat format) {
  std::vector<ZoneMask> zones;
  const auto add = [&](const char* channel, const char* kind, const char* description) {
    const std::vector<float>* v = channelNamed(r, channel);
    if (v == nullptr) return;
    ZoneMask z{kind, description, std::vector<unsigned char>(v->size())};
    for (std::size_t i = 0; i < v->size(); ++i) z.inside[i] = (*v)[i] >= 1.0F ? 1 : 0;
    zones.push_back(std::move(z));
  };
  add("hazard_ratio", "hazardous",
      "the verdict reaches 1: the worst window, a pulse at its half peak or the pulse train");
  add("aided_hazard_ratio", "aided_hazardous", "through the optical aid");
  writeZones(out, format, r.grid, zones, *r.site, engagementGeoInfo(r));
}

// The reach's footprint: where it covers the ground (naked eye, and aided), and the height of
// each observer it was judged at.
GeoInfo footprintInfo(const ReachResults& r) {
  return {r.info.program_version, "reach_footprint", r.info.mpe_rule, r.info.wavelength_nm,
          r.info.mpe_w_m2};
}

// The footprint's masks, each with its name and what it means: per threshold at eye height,
// then the same at each flight altitude (`<name>_at_<altitude>m`).
struct FootprintMask {
  std::string name, meaning;
  const std::vector<unsigned char>* inside;
};

std::vector<FootprintMask> footprintMasks(const ReachResults& r) {
  const ReachFootprint& f = *r.footprint;
  const HazardSpec& h = r.hazard;
  std::vector<std::pair<std::string, std::string>> thresholds = {
      {"reach", "the naked eye's hazard reach"}};
  if (h.aid) thresholds.emplace_back("aided_reach", "the hazard reach through the optical aid");
  for (const ExposureLevel& l : h.levels)
    thresholds.emplace_back(output_names::levelFootprint(l.name),
                            "where the " + l.label + " is reached");
  std::vector<FootprintMask> masks;
  for (std::size_t t = 0; t < thresholds.size(); ++t) {
    masks.push_back({thresholds[t].first,
                     thresholds[t].second +
                         " on the ground, at eye height, where the ground does not hide the lit "
                         "centre",
                     &f.inside.at(t)});
  }
  const std::string reference =
      r.footprint_above_ellipsoid ? "above the ellipsoid" : "above the ground";
  for (const ReachFootprint::Altitude& a : f.altitudes) {
    const std::string at = formatNumber("%g", a.altitude_m);
    for (std::size_t t = 0; t < thresholds.size(); ++t) {
      masks.push_back({output_names::footprintAtAltitude(thresholds[t].first, at),
                       thresholds[t].second + " at " + at + " m " + reference, &a.inside.at(t)});
    }
  }
  return masks;
}

void writeFootprintTif(std::ostream& out, const ReachResults& r) {
  const ReachFootprint& f = *r.footprint;
  const std::vector<FootprintMask> masks = footprintMasks(r);
  std::vector<std::vector<float>> bands;
  for (const FootprintMask& m : masks) bands.emplace_back(m.inside->begin(), m.inside->end());
  std::vector<ExrChannel> channels;
  std::vector<std::string> units;
  for (std::size_t k = 0; k < masks.size(); ++k) {
    channels.push_back({masks[k].name, &bands[k]});
    units.push_back("1 where " + masks[k].meaning);
  }
  channels.push_back({"observer_z_m", &f.ground_z_m});
  units.emplace_back("m (each observer's height at eye height in the site's local frame)");
  writeGeoTiff(out, f.grid, channels, units, *r.site, footprintInfo(r));
}

void writeFootprintZones(std::ostream& out, const ReachResults& r, VectorFormat format) {
  std::vector<ZoneMask> zones;
  for (const FootprintMask& m : footprintMasks(r)) zones.push_back({m.name, m.meaning, *m.inside});
  writeZones(out, format, r.footprint->grid, zones, *r.site, footprintInfo(r));
}

// The plane's zones: where the ratio reaches 1, naked eye and aided, and where a glint narrower
// than the lattice may pass with a bound above the MPE (status 6), which a hazard map must not
// leave out.
void writePlaneZones(std::ostream& out, const PlaneResults& r, VectorFormat format) {
  const PlaneMap m = planeMap(r.field, r.hazard);
  const std::size_t n = m.hazard_ratio.size();
  ZoneMask hazardous{"hazardous", "hazard ratio >= 1: irradiance at or above the MPE", {}};
  // A level below the MPE lowers the threshold at which the lattice marks such points.
  ZoneMask unresolved{"may_be_hazardous",
                      r.hazard.levels.empty()
                          ? "a glint narrower than the lattice may pass here, and its bound "
                            "reaches the MPE (status 6)"
                          : "a glint narrower than the lattice may pass here, and its bound "
                            "reaches the lowest level judged (status 6)",
                      {}};
  hazardous.inside.resize(n);
  unresolved.inside.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    hazardous.inside[k] = m.hazard_ratio[k] >= 1.0F;
    unresolved.inside[k] = !hazardous.inside[k] && static_cast<int>(m.status[k]) ==
                                                       static_cast<int>(VoxelStatus::Unresolved);
  }
  std::vector<ZoneMask> zones{std::move(hazardous), std::move(unresolved)};
  if (r.hazard.aid) {
    ZoneMask aided{"aided_hazardous", "aided hazard ratio >= 1: through the optical aid", {}};
    aided.inside.resize(n);
    for (std::size_t k = 0; k < n; ++k) aided.inside[k] = m.aided_hazard_ratio[k] >= 1.0F;
    zones.push_back(std::move(aided));
  }
  for (std::size_t l = 0; l < m.level_ratios.size(); ++l) {
    const ExposureLevel& level = r.hazard.levels[l];
    ZoneMask z{level.name, "where the " + level.label + " is reached", {}};
    z.inside.resize(n);
    for (std::size_t k = 0; k < n; ++k) z.inside[k] = m.level_ratios[l].second[k] >= 1.0F;
    zones.push_back(std::move(z));
  }
  writeZones(out, format, m, zones, *r.site, geoInfo(r));
}

// The writers' scratch, declared beside each writer in kOutputs: floors in bytes, the arrays a
// writer makes by count. A map is written from its channels copied row by row, bottom up
// (writeExr(), writeGeoTiff()), so a file of c float channels makes c more per pixel.
constexpr double kFloat = sizeof(float);

double latticePoints(const FieldSpec& spec) {
  const std::array<int, 3> n = spec.nodes();
  return static_cast<double>(n[0]) * n[1] * n[2];
}

// The channels planeMap() makes of a plane: irradiance, ratio, upper irradiance, level and
// status, the aided ratio with an aid, a ratio per level, each observer's height over a surface.
double planeMapChannels(const Scene& scene, const FieldSpec& plane) {
  return 5.0 + (scene.hazard.aid ? 1.0 : 0.0) + static_cast<double>(scene.hazard.levels.size()) +
         (plane.surface ? 1.0 : 0.0);
}

// An engagement's maps are made before the writers run (EngagementMaps::channels(): ten, the
// aided ratio among them, and a time above each level).
double engagementChannels(const Scene& scene) {
  return 10.0 + static_cast<double>(scene.hazard.levels.size());
}

// A cube-sphere surface of c² quads a face: points (3 doubles and two floats) and quads.
double cubeSphereBytes(int cells) {
  const double c = cells;
  return 6.0 * ((c + 1.0) * (c + 1.0) * (3.0 * sizeof(double) + 2.0 * kFloat) +
                c * c * 4.0 * sizeof(std::int64_t));
}

// The reach's lat-long map (writeReachExr()): its height as the writer chooses it.
int reachMapHeight(const Scene& scene) {
  return std::max(farMapHeight(farFieldLattice(scene).face_pixels), 2 * scene.reach.face_cells);
}

// Eye height and each flight altitude.
double footprintHeights(const Scene& scene) {
  return 1.0 + static_cast<double>(scene.reach.footprint.value().flight_altitudes_m.size());
}

double footprintPixels(const Scene& scene) {
  const FootprintSpec& f = scene.reach.footprint.value();
  const double pixel = f.pixel_m > 0.0 ? f.pixel_m : 2.0 * f.radius_m / 512.0;
  const double n = 2.0 * std::ceil(f.radius_m / pixel) + 1.0;
  return n * n;
}

// The thresholds judged: the MPE, the aided MPE with an aid, each level.
double hazardThresholds(const Scene& scene) {
  return static_cast<double>(scene.hazard.thresholdsW_m2().size());
}

// target.vtp splits each coarse facet this deep (4^depth pieces): the target as integrated.
constexpr int kTargetVtpDepth = 2;

namespace scratch {

// Written from what the results hold, without a copy of their size: summary.json; the box's
// VDB, which takes the field's grids; blocks.vtu, whose cells fieldMemoryFloorBytes() counts
// per coarse block (finer ones grow with the work, which the memory watch covers).
std::uint64_t none(const Scene&, const FieldSpec*) { return 0; }

// The box resampled at vtiStride(): irradiance, its upper bound (made, then copied into its
// array), level, status and the hazard's scaled arrays.
std::uint64_t vti(const Scene& scene, const FieldSpec* box) {
  const std::array<int, 3> n = box->nodes();
  const int stride = vtiStride(*box);
  double points = 1.0;
  for (int a = 0; a < 3; ++a) points *= (n[a] - 1) / stride + 1;
  return memory_model::saturated(points * kFloat * (5.0 + hazardThresholds(scene)));
}

// The AMR levels copy the lattice at each level's spacing: the coarsest covers the whole box.
std::uint64_t amr(const Scene& scene, const FieldSpec* box) {
  const double coarse = latticePoints(*box) / std::pow(box->block_voxels, 3.0);
  return memory_model::saturated(coarse * kFloat * (3.0 + hazardThresholds(scene)));
}

// target.vtp: every coarse facet (lit or not) split to kTargetVtpDepth, each piece 3 corners
// of 3 doubles, their connectivity, an offset, its power and its facet.
std::uint64_t targetVtp(const Scene& scene, const FieldSpec*) {
  double facets = 0.0;
  for (const ObjectSpec& object : scene.objects)
    facets += static_cast<double>(coarseFacetCount(object));
  const double pieces = facets * std::pow(4.0, kTargetVtpDepth);
  return memory_model::saturated(
      pieces * (9.0 * sizeof(double) + 4.0 * sizeof(std::int64_t) + sizeof(double) + sizeof(int)));
}

// planeMap()'s channels, and as many again flipped for the file.
std::uint64_t planeExr(const Scene& scene, const FieldSpec* plane) {
  return memory_model::saturated(2.0 * planeMapChannels(scene, *plane) * kFloat *
                                 latticePoints(*plane));
}

// The map, and GDAL's bands copied from it (as many as the map's channels, at most).
std::uint64_t planeGeoTiff(const Scene& scene, const FieldSpec* plane) {
  return planeExr(scene, plane);
}

// The map, and a byte per pixel of each zone (hazardous, may be hazardous, aided, levels).
std::uint64_t planeZones(const Scene& scene, const FieldSpec* plane) {
  return memory_model::saturated((planeMapChannels(scene, *plane) * kFloat + 3.0 +
                                  static_cast<double>(scene.hazard.levels.size())) *
                                 latticePoints(*plane));
}

std::uint64_t engagementPlaneMap(const Scene& scene, const FieldSpec* plane) {
  return memory_model::saturated(engagementChannels(scene) * kFloat * latticePoints(*plane));
}

std::uint64_t engagementPlaneZones(const Scene&, const FieldSpec* plane) {
  return memory_model::saturated(2.0 * latticePoints(*plane));
}

// writeLatticeVdb() makes a float grid of each channel, a value per lattice point.
std::uint64_t engagementVdb(const Scene& scene, const FieldSpec* box) {
  return memory_model::saturated(engagementChannels(scene) * kFloat * latticePoints(*box));
}

// latLongMap() while it is made, then its two or three channels and their rows flipped.
std::uint64_t farExr(const Scene& scene, const FieldSpec*) {
  const int n = farFieldLattice(scene).face_pixels;
  const int h = farMapHeight(n);
  const double channels = 1.0 + (scene.hazard.aid ? 2.0 : 1.0);  // the levels have none
  return std::max(latLongMapBytes(h, n),
                  memory_model::saturated(2.0 * h * h * 2.0 * channels * kFloat));
}

std::uint64_t farVtp(const Scene& scene, const FieldSpec*) {
  return memory_model::saturated(
      cubeSphereBytes(std::min(farFieldLattice(scene).face_pixels, 128)));
}

// The far field's latLongIntensity() while it is made; then held (a double a pixel) while
// reachLatLong() makes each threshold's map (and one threshold's far-field distances); then
// the maps and their rows flipped.
std::uint64_t reachExr(const Scene& scene, const FieldSpec*) {
  const int h = reachMapHeight(scene);
  const double pixels = 2.0 * h * h, thresholds = hazardThresholds(scene);
  return std::max({latLongMapBytes(h, farFieldLattice(scene).face_pixels),
                   memory_model::saturated(pixels * (sizeof(double) + (thresholds + 1.0) * kFloat)),
                   memory_model::saturated(pixels * 2.0 * thresholds * kFloat)});
}

std::uint64_t reachVtp(const Scene& scene, const FieldSpec*) {
  return memory_model::saturated(cubeSphereBytes(scene.reach.face_cells));
}

// The footprint itself (ReachFootprint: a byte per pixel of each mask, the observers' heights
// as floats), made before its writers and held while each runs.
double footprintHeldBytes(const Scene& scene) {
  return (hazardThresholds(scene) * footprintHeights(scene) + kFloat) * footprintPixels(scene);
}

// The footprint's masks (per threshold, at eye height and each flight altitude) as float bands
// beside the ground's height, all of them with their rows flipped (writeGeoTiff()); GDAL's
// block cache; and the file as written, twice (GDAL's memory file and the bytes taken out of
// it). Compressed, a mask takes next to nothing there and the height about 70 % of its floats
// (measured: 182 MB for 64 M pixels): counted at its floats' size.
std::uint64_t footprintTif(const Scene& scene, const FieldSpec*) {
  const double masks = hazardThresholds(scene) * footprintHeights(scene);
  const double file = kFloat * footprintPixels(scene);
  return memory_model::saturated(footprintHeldBytes(scene) +
                                 (masks + (masks + 1.0)) * kFloat * footprintPixels(scene) +
                                 static_cast<double>(kGdalBlockCacheBytes) + 2.0 * file);
}

// A copy of each mask, and GDAL's in-memory raster of one, beside the footprint.
std::uint64_t footprintZones(const Scene& scene, const FieldSpec*) {
  return memory_model::saturated(footprintHeldBytes(scene) +
                                 (hazardThresholds(scene) * footprintHeights(scene) + 1.0) *
                                     footprintPixels(scene));
}

}  // namespace scratch

}  // namespace

// Every output of glint run: its name, the region it is written from, its writer and whether a
// study's scenario writes it too. A region's files are written in this order, but for the one
// that takes the field's grids, written last; summary.json lists them in this order, a plane's
// one a plane.
struct RunOutputs::Declared {
  using Region = OutputRegion;
  const char* name = nullptr;
  std::string (*plane_name)(const std::string&) = nullptr;  // instead of name, a plane's
  Region region = Region::Run;
  void (*box)(std::ostream&, BoxResults&) = nullptr;
  void (*plane)(std::ostream&, const PlaneResults&) = nullptr;
  void (*far)(std::ostream&, const FarResults&) = nullptr;
  void (*reach)(std::ostream&, const ReachResults&) = nullptr;
  void (*engagement_plane)(std::ostream&, const EngagementPlaneResults&) = nullptr;
  void (*engagement_box)(std::ostream&, const EngagementBoxResults&) = nullptr;
  // What its writer allocates besides the results (writerScratch()); the lattice is the
  // region's, null for the far field and the reach.
  std::uint64_t (*scratch_bytes)(const Scene&, const FieldSpec* lattice) = nullptr;
  // What lowers that scratch where it is not the region's size (the memory check's advice).
  const char* scratch_advice = nullptr;
  bool takes_field = false;    // the box's VDB moves the grids out of the field
  bool staged_folder = false;  // the AMR data set: a folder staged beside its .vthb
  bool aided_only = false;     // written with an optical aid only
  bool geo = false;            // with a site only, of planes flat enough for a map
  bool footprint = false;      // with reach.footprint only
  // A study's scenario writes it too, under the same name in its folder, so that a scenario's
  // map is what glint run writes of the scenario's scene (its result.json vouches for it).
  bool scenario = false;

  // Its name; a plane's of the plane named @p plane_of.
  [[nodiscard]] std::string fileName(const std::string& plane_of) const {
    return plane_name != nullptr ? plane_name(plane_of) : std::string(name);
  }

  [[nodiscard]] bool wanted(const Scene& s) const {
    if (geo && !s.site) return false;
    if (footprint && !s.reach.footprint) return false;
    // An engagement's run writes its planes' maps over time and its summary only: a box, the
    // far field and the reach judge one pose.
    const bool one_pose = !s.engagement.has_value();
    switch (region) {
      case Region::Run:
        return true;
      case Region::Box:
        return one_pose && s.observers.has_value();
      case Region::Plane:
        return one_pose && !s.planes.empty();
      case Region::Far:
        return one_pose && s.far_field.enabled && (!aided_only || s.hazard.aid.has_value());
      case Region::Reach:
        return one_pose && s.wantsReach();
      case Region::EngagementPlane:
        return !one_pose && !s.planes.empty();
      case Region::EngagementBox:
        return !one_pose && s.observers.has_value();
    }
    return false;
  }

  void write(std::ostream& out, BoxResults& r) const { box(out, r); }
  void write(std::ostream& out, const PlaneResults& r) const { plane(out, r); }
  void write(std::ostream& out, const FarResults& r) const { far(out, r); }
  void write(std::ostream& out, const ReachResults& r) const { reach(out, r); }
  void write(std::ostream& out, const EngagementPlaneResults& r) const { engagement_plane(out, r); }
  void write(std::ostream& out, const EngagementBoxResults& r) const { engagement_box(out, r); }
};

namespace {

using Declared = RunOutputs::Declared;
using Region = Declared::Region;

constexpr Declared kOutputs[] = {
    {.name = output_names::kSummary, .region = Region::Run, .scratch_bytes = scratch::none},
    {.name = output_names::kIrradianceVdb,
     .region = Region::Box,
     .box = [](std::ostream& out, BoxResults& b) { writeVdb(out, std::move(b.field), b.info); },
     .scratch_bytes = scratch::none,
     .takes_field = true,
     .scenario = true},
    {.name = output_names::kIrradianceVti,
     .region = Region::Box,
     .box = [](std::ostream& out,
               BoxResults& b) { writeVti(out, b.field, vtiStride(b.field.spec()), b.info.scaled); },
     .scratch_bytes = scratch::vti},
    {.name = output_names::kBlocksVtu,
     .region = Region::Box,
     .box = [](std::ostream& out, BoxResults& b) { writeBlocksVtu(out, b.field, b.info.scaled); },
     .scratch_bytes = scratch::none},
    {.name = output_names::kTargetVtp,
     .region = Region::Box,
     .box = [](std::ostream& out,
               BoxResults& b) { writeTargetVtp(out, b.integrator, kTargetVtpDepth); },
     .scratch_bytes = scratch::targetVtp,
     .scratch_advice = "lower the objects' segments or decimate the meshes (target.vtp holds 16 "
                       "pieces of every facet)"},
    {.name = output_names::kIrradianceAmr,
     .region = Region::Box,
     .scratch_bytes = scratch::amr,
     .staged_folder = true},
    {.name = output_names::kFarFieldExr,
     .region = Region::Far,
     .far = writeFarExr,
     .scratch_bytes = scratch::farExr},
    {.name = output_names::kFarFieldVtp,
     .region = Region::Far,
     .far = [](std::ostream& out, const FarResults& f) { writeFarVtp(out, f, f.info.mpe_w_m2); },
     .scratch_bytes = scratch::farVtp},
    {.name = output_names::kFarFieldAidedVtp,
     .region = Region::Far,
     .far = [](std::ostream& out,
               const FarResults& f) { writeFarVtp(out, f, f.hazard.aidedMpeW_m2()); },
     .scratch_bytes = scratch::farVtp,
     .aided_only = true},
    {.name = output_names::kReachExr,
     .region = Region::Reach,
     .reach = writeReachExr,
     .scratch_bytes = scratch::reachExr},
    {.name = output_names::kReachVtp,
     .region = Region::Reach,
     .reach =
         [](std::ostream& out, const ReachResults& r) {
           writeReachVtp(out, reachSurface(r.near, r.far, r.hazard.atmosphere.extinction_per_m));
         },
     .scratch_bytes = scratch::reachVtp},
    {.name = output_names::kReachFootprintTif,
     .region = Region::Reach,
     .reach = writeFootprintTif,
     .scratch_bytes = scratch::footprintTif,
     .geo = true,
     .footprint = true},
    {.name = output_names::kReachFootprintGeoJson,
     .region = Region::Reach,
     .reach = [](std::ostream& out,
                 const ReachResults& r) { writeFootprintZones(out, r, VectorFormat::GeoJson); },
     .scratch_bytes = scratch::footprintZones,
     .geo = true,
     .footprint = true},
    {.name = output_names::kReachFootprintKml,
     .region = Region::Reach,
     .reach = [](std::ostream& out,
                 const ReachResults& r) { writeFootprintZones(out, r, VectorFormat::Kml); },
     .scratch_bytes = scratch::footprintZones,
     .geo = true,
     .footprint = true},
    {.plane_name = output_names::planeExr,
     .region = Region::Plane,
     .plane = writePlaneExr,
     .scratch_bytes = scratch::planeExr,
     .scenario = true},
    {.plane_name = output_names::planeGeoTiff,
     .region = Region::Plane,
     .plane = writePlaneGeoTiff,
     .scratch_bytes = scratch::planeGeoTiff,
     .geo = true},
    {.plane_name = output_names::planeZonesGeoJson,
     .region = Region::Plane,
     .plane = [](std::ostream& out,
                 const PlaneResults& r) { writePlaneZones(out, r, VectorFormat::GeoJson); },
     .scratch_bytes = scratch::planeZones,
     .geo = true},
    {.plane_name = output_names::planeZonesKml,
     .region = Region::Plane,
     .plane = [](std::ostream& out,
                 const PlaneResults& r) { writePlaneZones(out, r, VectorFormat::Kml); },
     .scratch_bytes = scratch::planeZones,
     .geo = true},
    {.plane_name = output_names::planeExr,
     .region = Region::EngagementPlane,
     .engagement_plane =
         [](std::ostream& out, const EngagementPlaneResults& r) {
           writeExr(out, r.grid, r.channels, exrInfo(r.info));
         },
     .scratch_bytes = scratch::engagementPlaneMap,
     .scenario = true},
    {.plane_name = output_names::planeGeoTiff,
     .region = Region::EngagementPlane,
     .engagement_plane = writeEngagementGeoTiff,
     .scratch_bytes = scratch::engagementPlaneMap,
     .geo = true},
    {.plane_name = output_names::planeZonesGeoJson,
     .region = Region::EngagementPlane,
     .engagement_plane =
         [](std::ostream& out, const EngagementPlaneResults& r) {
           writeEngagementZones(out, r, VectorFormat::GeoJson);
         },
     .scratch_bytes = scratch::engagementPlaneZones,
     .geo = true},
    {.plane_name = output_names::planeZonesKml,
     .region = Region::EngagementPlane,
     .engagement_plane =
         [](std::ostream& out, const EngagementPlaneResults& r) {
           writeEngagementZones(out, r, VectorFormat::Kml);
         },
     .scratch_bytes = scratch::engagementPlaneZones,
     .geo = true},
    {.name = output_names::kEngagementVdb,
     .region = Region::EngagementBox,
     .engagement_box =
         [](std::ostream& out, const EngagementBoxResults& r) {
           LatticeMeta meta;
           meta.strings = {{"program", r.info.program_version},
                           {"scene_file", r.info.scene_file},
                           {"scene_fnv1a64", r.info.scene_fnv1a64},
                           {"length_unit", "m"},
                           {"mpe_rule", r.info.mpe_rule}};
           meta.numbers = {{"wavelength_nm", r.info.wavelength_nm},
                           {"power_w", r.info.power_w},
                           {"exposure_s", r.info.exposure_s},
                           {"mpe_w_m2", r.info.mpe_w_m2},
                           {"voxel_m", r.spec.voxel_m}};
           if (r.info.optical_aid_gain > 0.0)
             meta.numbers["optical_aid_gain"] = r.info.optical_aid_gain;
           writeLatticeVdb(out, r.spec, r.channels, meta);
         },
     .scratch_bytes = scratch::engagementVdb,
     .scenario = true},
};

// A scenario writes maps of its box and planes only (its far field is a figure of its
// result.json), and commits each as it is written: none is a folder to stage.
static_assert(std::all_of(std::begin(kOutputs), std::end(kOutputs), [](const Declared& d) {
  return !d.scenario ||
         ((d.region == Region::Box || d.region == Region::Plane ||
           d.region == Region::EngagementPlane || d.region == Region::EngagementBox) &&
          !d.staged_folder);
}));

// Every output says what its writer allocates: a new one without it does not compile.
static_assert(std::all_of(std::begin(kOutputs), std::end(kOutputs),
                          [](const Declared& d) { return d.scratch_bytes != nullptr; }));

// The outputs of @p region in the order they are written: the list's, but the one that takes
// the field's grids last.
std::vector<const Declared*> writingOrder(Region region) {
  std::vector<const Declared*> order;
  const Declared* last = nullptr;
  for (const Declared& d : kOutputs) {
    if (d.region != region) continue;
    if (d.takes_field) {
      last = &d;
    } else {
      order.push_back(&d);
    }
  }
  if (last != nullptr) order.push_back(last);
  return order;
}

}  // namespace

WriterScratch writerScratch(const Scene& scene, OutputRegion region, const FieldSpec* lattice,
                            const std::string& plane_name, bool scenario) {
  WriterScratch largest;
  for (const Declared& d : kOutputs) {
    if (d.region != region || !d.wanted(scene) || (scenario && !d.scenario)) continue;
    const std::uint64_t bytes = d.scratch_bytes(scene, lattice);
    if (largest.file.empty() || bytes > largest.bytes) {
      largest = {bytes, d.fileName(plane_name),
                 d.scratch_advice != nullptr ? d.scratch_advice : std::string()};
    }
  }
  return largest;
}

RunOutputs::RunOutputs(const Scene& scene, const std::filesystem::path& dir,
                       const InputFiles& inputs, bool writer)
    : dir_(dir), writer_(writer) {
  auto declare = [&](const Declared& d, std::size_t plane) {
    const bool of_plane = d.region == Region::Plane || d.region == Region::EngagementPlane;
    const std::string name = d.fileName(of_plane ? scene.planes[plane].name : "");
    names_.push_back(name);
    if (d.region == Region::Far) far_names_.push_back(name);
    declared_.push_back(&d);
    planes_.push_back(plane);
    if (!writer_ || d.staged_folder) {
      files_.push_back(nullptr);
      return;
    }
    inputs.requireNotAnInput(dir_ / name);  // a hard link to an input, named otherwise
    // summary.json, which says the run finished, appears after every other output.
    files_.push_back(&set_.open(dir_ / name, d.region == Region::Run));
  };
  for (const Declared& d : kOutputs) {
    if (!d.wanted(scene)) continue;
    if (d.region != Region::Plane && d.region != Region::EngagementPlane) {
      declare(d, 0);
      continue;
    }
    for (std::size_t p = 0; p < scene.planes.size(); ++p) {
      const PlaneSpec& plane = scene.planes[p];
      if (!d.geo || mappable(plane.u_axis, plane.v_axis)) declare(d, p);
    }
  }
  for (const PlaneSpec& plane : scene.planes) plane_names_.push_back(plane.name);
  if (scene.site && writer_) site_ = std::make_unique<SiteFrame>(*scene.site);
}

RunOutputs::~RunOutputs() = default;

std::optional<std::size_t> RunOutputs::slotOf(const Declared& d, std::size_t plane) const {
  for (std::size_t i = 0; i < declared_.size(); ++i) {
    if (declared_[i] == &d && planes_[i] == plane) return i;
  }
  return std::nullopt;  // not an output of this scene
}

std::ostream* RunOutputs::summary() {
  return writer_ && files_.at(0) ? &files_[0]->stream() : nullptr;
}

std::unique_ptr<ProgressReporter> RunOutputs::fileProgress(OutputRegion region, std::size_t plane,
                                                           const std::string& noun,
                                                           const WorkCounter& counter) const {
  if (progress_to_ == nullptr) return nullptr;
  std::size_t files = 0;
  for (const Declared* d : writingOrder(region)) {
    if (slotOf(*d, plane)) ++files;
  }
  // A map's file may take a hundred times another's: no time left is estimated.
  return std::make_unique<ProgressReporter>(*progress_to_, terminal_, noun, files, counter, true);
}

void RunOutputs::writeBox(BoxResults& box) {
  if (!writer_) return;
  WorkCounter counter;
  const auto progress = fileProgress(Region::Box, 0, "files of the observer box", counter);
  for (const Declared* d : writingOrder(Region::Box)) {
    const std::optional<std::size_t> i = slotOf(*d, 0);
    if (!i) continue;
    if (d->staged_folder) {
      amr_ = std::make_unique<StagedAmr>(writeAmr(dir_ / names_[*i], box.field, box.info.scaled));
      amr_->addTo(set_);
    } else {
      files_[*i]->write([&](std::ostream& out) { d->write(out, box); });
    }
    ++counter.items_done;
  }
}

template <class Results>
void RunOutputs::writeRegion(OutputRegion region, std::size_t plane, const Results& results,
                             const std::string& noun) {
  WorkCounter counter;
  const auto progress = noun.empty() ? nullptr : fileProgress(region, plane, noun, counter);
  for (const Declared* d : writingOrder(region)) {
    if (const std::optional<std::size_t> i = slotOf(*d, plane)) {
      files_[*i]->write([&](std::ostream& out) { d->write(out, results); });
      ++counter.items_done;
    }
  }
}

void RunOutputs::writePlane(std::size_t index, const PlaneResults& plane) {
  if (!writer_) return;
  PlaneResults placed = plane;
  placed.site = site_.get();
  placed.plane_name = plane_names_.at(index);
  writeRegion(Region::Plane, index, placed, "files of plane " + placed.plane_name);
}

void RunOutputs::writeEngagementPlane(std::size_t index, const EngagementPlaneResults& plane) {
  if (!writer_) return;
  EngagementPlaneResults placed = plane;
  placed.site = site_.get();
  placed.plane_name = plane_names_.at(index);
  writeRegion(Region::EngagementPlane, index, placed, "");
}

void RunOutputs::writeEngagementBox(const EngagementBoxResults& box) {
  if (!writer_) return;
  writeRegion(Region::EngagementBox, 0, box, "");
}

void RunOutputs::writeFar(const FarResults& far) {
  if (!writer_) return;
  writeRegion(Region::Far, 0, far, "files of the far field");
}

void RunOutputs::writeReach(const ReachResults& reach) {
  if (!writer_) return;
  ReachResults placed = reach;
  placed.site = site_.get();
  writeRegion(Region::Reach, 0, placed, "files of the hazard reach");
}

void RunOutputs::commit(const std::function<void()>& after_first) { set_.commit(after_first); }

namespace {

// Writes a scenario's maps of @p region (of plane @p plane: its name) into @p dir, each
// committed once written. Returns their names.
template <class Results>
std::vector<std::string> writeScenarioMaps(const Scene& scene, const std::filesystem::path& dir,
                                           Region region, const std::string& plane,
                                           Results& results) {
  std::vector<std::string> names;
  for (const Declared* d : writingOrder(region)) {
    if (!d->scenario || !d->wanted(scene)) continue;
    names.push_back(d->fileName(plane));
    AtomicFile file(dir / names.back());
    file.write([&](std::ostream& out) { d->write(out, results); });
    file.commit();
  }
  return names;
}

}  // namespace

ScenarioMaps::ScenarioMaps(const Scene& scene, std::filesystem::path dir)
    : scene_(scene), dir_(std::move(dir)) {}

std::vector<std::string> ScenarioMaps::names() const {
  std::vector<std::string> names;
  auto add = [&](Region region, const std::string& plane) {
    for (const Declared& d : kOutputs) {
      if (d.region == region && d.scenario && d.wanted(scene_)) names.push_back(d.fileName(plane));
    }
  };
  add(Region::Box, "");
  add(Region::EngagementBox, "");
  for (const PlaneSpec& plane : scene_.planes) {
    add(Region::Plane, plane.name);
    add(Region::EngagementPlane, plane.name);
  }
  return names;
}

std::vector<std::string> ScenarioMaps::writeBox(BoxResults& box) const {
  return writeScenarioMaps(scene_, dir_, Region::Box, "", box);
}

std::vector<std::string> ScenarioMaps::writePlane(std::size_t index,
                                                  const PlaneResults& plane) const {
  return writeScenarioMaps(scene_, dir_, Region::Plane, scene_.planes.at(index).name, plane);
}

std::vector<std::string> ScenarioMaps::writeEngagementPlane(
    std::size_t index, const EngagementPlaneResults& plane) const {
  return writeScenarioMaps(scene_, dir_, Region::EngagementPlane, scene_.planes.at(index).name,
                           plane);
}

std::vector<std::string> ScenarioMaps::writeEngagementBox(const EngagementBoxResults& box) const {
  return writeScenarioMaps(scene_, dir_, Region::EngagementBox, "", box);
}

std::vector<std::string> ScenarioMaps::folderNames(const Scene& base) {
  std::vector<std::string> names = {output_names::kScenarioScene, output_names::kScenarioResult};
  for (const Declared& d : kOutputs) {
    if (!d.scenario) continue;
    if (d.plane_name == nullptr) {
      names.emplace_back(d.name);
      continue;
    }
    for (const PlaneSpec& plane : base.planes) {
      // A pose's plane map and an engagement's share their name.
      std::string name = d.plane_name(plane.name);
      if (std::find(names.begin(), names.end(), name) == names.end())
        names.push_back(std::move(name));
    }
  }
  return names;
}

ExrInfo exrInfo(const RunInfo& info) {
  return {info.program_version, info.wavelength_nm, info.mpe_w_m2, info.mpe_rule};
}

}  // namespace glint
