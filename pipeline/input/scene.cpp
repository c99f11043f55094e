#include "pipeline/input/scene.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <type_traits>
#include <utility>

#include "export/fnv1a.h"
#include "pipeline/base/input_error.h"
#include "pipeline/base/memory_budget.h"
#include "pipeline/base/memory_model.h"
#include "pipeline/base/number_format.h"
#include "pipeline/base/output_names.h"
#include "pipeline/input/brdf_table_file.h"
#include "pipeline/input/gltf_loader.h"
#include "pipeline/input/json_reader.h"
#include "pipeline/input/output_registry.h"
#include "pipeline/input/scene_memory.h"

namespace glint {
namespace {

// A pulsed laser (`laser.pulse`): the pulse's duration and its energy (or peak power, or
// from the mean power), and the repetition rate of a train. Sets @p mean_power_w, the mean power
// over the exposure, which the file's power_w may leave out, and checks it where it does not.
PulseSpec readPulse(ObjectReader r, const std::optional<double>& power_w, double& mean_power_w) {
  PulseSpec p;
  p.duration_s = inRange(r, "duration_s", r.number("duration_s"), 1e-9, 3e4, "s");
  if (auto f = r.optionalNumber("repetition_rate_hz")) {
    p.repetition_rate_hz = inRange(r, "repetition_rate_hz", *f, 1e-6, 1e12, "Hz");
    if (p.duration_s * *p.repetition_rate_hz > 1.0) {
      r.fail("duration_s", "longer than the time between pulses (1 / repetition_rate_hz)");
    }
  }
  const auto energy = r.optionalNumber("energy_j");
  const auto peak = r.optionalNumber("peak_power_w");
  if (energy && peak) r.failHere("give energy_j or peak_power_w, not both");
  // The mean power over the exposure: of a train, energy × rate; of a single pulse (whose
  // exposure is its duration), energy / duration.
  const double per_joule = p.repetition_rate_hz ? *p.repetition_rate_hz : 1.0 / p.duration_s;
  if (energy) {
    p.energy_j = positive(r, "energy_j", *energy);
  } else if (peak) {
    p.energy_j = positive(r, "peak_power_w", *peak) * p.duration_s;
  } else if (power_w) {
    p.energy_j = *power_w / per_joule;
  } else {
    r.failHere("needs energy_j or peak_power_w (or the laser's power_w, its mean power)");
  }
  const double mean_w = p.energy_j * per_joule;
  if (power_w && !(std::abs(*power_w - mean_w) <= 1e-3 * mean_w)) {
    r.failHere("the laser's power_w (" + formatNumber("%.6g", *power_w) +
               " W) is not the pulse's mean power, " +
               (p.repetition_rate_hz ? "energy × repetition rate = " : "energy / duration = ") +
               formatNumber("%.6g", mean_w) + " W; leave power_w out or make them agree");
  }
  mean_power_w = mean_w;
  r.finish();
  return p;
}

// The exposure; its MPE once the pulse and the optical aid are known (completeHazard).
HazardSpec readExposure(ObjectReader& r, double wavelength_nm,
                        const std::optional<double>& exposure_s,
                        const std::optional<PulseSpec>& pulse, const HazardSpec& limits) {
  HazardSpec h;
  h.standard = limits.standard;
  h.tissue = limits.tissue;
  h.levels = limits.levels;
  h.wavelength_nm = wavelength_nm;
  if (!(wavelength_nm >= 400.0 && wavelength_nm <= 1.0e6)) {
    r.fail("wavelength_nm",
           "must be in 400 nm to 1 mm, the range of the MPE table (ANSI "
           "Z136.1 / IEC 60825-1) that glint's hazard uses");
  }
  h.pulse = pulse;
  // A single pulse's exposure is its duration, which the file gives: never the default.
  h.exposure_default = !exposure_s.has_value() && !(pulse && !pulse->repetition_rate_hz);
  if (pulse && !pulse->repetition_rate_hz) {
    if (exposure_s) {
      r.fail("exposure_s",
             "a single pulse's exposure is its duration (pulse/duration_s); leave "
             "exposure_s out, or give pulse/repetition_rate_hz for a train");
    }
    h.exposure_s = pulse->duration_s;
    return h;
  }
  h.exposure_s = exposure_s.value_or(defaultExposureS(wavelength_nm, h.tissue));
  if (!(h.exposure_s >= 1e-9 && h.exposure_s <= 3e4)) {
    r.fail("exposure_s", "must be in 1e-9 s to 3e4 s, the range of the MPE table");
  }
  if (pulse && *pulse->repetition_rate_hz * h.exposure_s < 1.0) {
    r.fail("exposure_s",
           "holds fewer than one pulse (exposure_s × pulse/repetition_rate_hz < "
           "1); describe a single pulse by leaving repetition_rate_hz out");
  }
  if (pulse && pulse->duration_s > h.exposure_s) {
    r.fail("exposure_s", "is shorter than one pulse (pulse/duration_s)");
  }
  return h;
}

// The laser as a beam; its wavelength and exposure go to @p hazard, whose standard and tissue
// are read already.
Beam readLaser(ObjectReader r, HazardSpec& hazard) {
  Beam laser;
  laser.origin_m = position(r, "position");
  laser.direction = r.direction("direction");
  std::optional<double> power_w = r.optionalNumber("power_w");
  if (power_w)
    inRange(r, "power_w", positive(r, "power_w", *power_w), 0.0, limits::kMaxPowerW, "W");
  const double wavelength_nm = positive(r, "wavelength_nm", r.number("wavelength_nm"));
  std::optional<double> exposure_s;
  if (auto t = r.optionalNumber("exposure_s")) exposure_s = positive(r, "exposure_s", *t);
  std::optional<PulseSpec> pulse;
  if (r.has("pulse")) {
    pulse = readPulse(r.object("pulse"), power_w, laser.power_w);
    inRange(r, "power_w", laser.power_w, 0.0, limits::kMaxPowerW, "W (the pulse's mean power)");
  } else {
    laser.power_w = r.number("power_w");  // required: fails with the key's name when missing
  }
  hazard = readExposure(r, wavelength_nm, exposure_s, pulse, hazard);

  ObjectReader beam = r.object("beam");
  const std::size_t profile = beam.choice("profile", {"flat_top", "gaussian"});
  laser.profile = profile == 0 ? BeamProfile::FlatTop : BeamProfile::Gaussian;
  const std::string radius_key = profile == 0 ? "radius_m" : "w_m";
  laser.radius_m = inRange(beam, radius_key, beam.number(radius_key), limits::kMinLengthM,
                           limits::kMaxLengthM, "m");
  laser.divergence_rad = beam.number("divergence_rad", 0.0);
  if (!(laser.divergence_rad >= 0.0 && laser.divergence_rad < kPi)) {
    beam.fail("divergence_rad", "must be in [0, π) (a full angle in radians)");
  }
  beam.finish();
  r.finish();
  return laser;
}

// Where the local frame lies on the Earth (`site`).
SiteSpec readSite(ObjectReader r) {
  SiteSpec site;
  site.projection = r.choice("projection", {"utm", "local_tm"}, 0) == 0
                        ? MapProjection::Utm
                        : MapProjection::LocalTransverseMercator;
  // UTM is defined from 80° S to 84° N; the local transverse Mercator anywhere short of a pole.
  const bool utm = site.projection == MapProjection::Utm;
  site.latitude_deg = inRange(r, "latitude_deg", r.number("latitude_deg"), utm ? -80.0 : -89.0,
                              utm ? 84.0 : 89.0, "degrees");
  site.longitude_deg =
      inRange(r, "longitude_deg", r.number("longitude_deg"), -180.0, 180.0, "degrees");
  // From the Dead Sea's shore to above Everest's summit.
  site.height_m = inRange(r, "height_m", r.number("height_m", 0.0), -500.0, 9000.0, "m");
  site.bearing_deg =
      inRange(r, "bearing_deg", r.number("bearing_deg", 0.0), -360.0, 360.0, "degrees");
  r.finish();
  return site;
}

// The levels beside the MPE (`hazard.flight_zones`, `hazard.levels`); what they need of the
// laser is checked once it is read (checkLevels()).
void readLevels(ObjectReader& r, HazardSpec& h) {
  if (r.has("flight_zones")) {
    bool wanted = true, corrected = true;
    if (r.raw().at("flight_zones").is_object()) {
      ObjectReader z = r.object("flight_zones");
      corrected = z.boolean("visual_correction", true);
      z.finish();
    } else {
      wanted = r.boolean("flight_zones", false);
    }
    if (wanted) h.levels = flightZoneLevels(corrected);
  }
  if (!r.has("levels")) return;
  const nlohmann::json& list = r.raw().at("levels");
  if (!list.is_array() || list.empty()) r.fail("levels", "must be a non-empty array of levels");
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string at = r.at("levels") + "/" + std::to_string(i);
    if (!list[i].is_object()) throw InputError(r.source() + ": " + at + ": must be an object");
    ObjectReader l(list[i], at, r.source());
    ExposureLevel level;
    level.name = l.string("name");
    if (const std::string problem = levelNameProblem(level.name); !problem.empty())
      l.fail("name", problem);
    for (const ExposureLevel& other : h.levels) {
      if (other.name == level.name) l.fail("name", "\"" + level.name + "\" is named twice");
    }
    level.level_w_m2 = positive(l, "irradiance_w_m2", l.number("irradiance_w_m2"));
    inRange(l, "irradiance_w_m2", level.level_w_m2, 1e-12, 1e12, "W/m²");
    level.visually_corrected = l.boolean("visual_correction", false);
    level.source = l.string("source", "the scene's own level");
    level.label = level.name + " (" + formatNumber("%.3g", level.level_w_m2) + " W/m²" +
                  (level.visually_corrected ? " effective" : "") + ")";
    l.finish();
    h.levels.push_back(level);
  }
}

// What the levels ask of the laser: the flight zones are visual levels for a pilot's eye, from
// 400 nm to 700 nm; any visually corrected level is visible only.
void checkLevels(ObjectReader& r, const HazardSpec& h) {
  if (h.levels.empty()) return;
  ObjectReader hazard = r.object("hazard");
  const bool zones = hazard.has("flight_zones") && hazard.raw().at("flight_zones") != false;
  // Enough digits that a wavelength just past a band's edge never reads as the edge itself.
  const std::string wavelength = formatNumber("%.10g", h.wavelength_nm) + " nm";
  const bool visible = h.wavelength_nm >= kVisibleMinNm && h.wavelength_nm <= kVisibleMaxNm;
  if (zones) {
    if (!visible) {
      hazard.fail("flight_zones",
                  "the flight zones' levels are visual interference (glare, flash blindness) and "
                  "apply from 400 nm to 700 nm; the laser's wavelength is " +
                      wavelength + ". Its hazard to aircrew is the MPE's alone");
    }
    if (h.tissue == Tissue::Skin) {
      hazard.fail("flight_zones", "are levels for a pilot's eye, and hazard.tissue is \"skin\"");
    }
  }
  for (const ExposureLevel& l : h.levels) {
    if (l.visually_corrected && !visible) {
      hazard.fail(zones ? "flight_zones" : "levels",
                  "a visually corrected level applies from 400 nm to 700 nm (CIE V(λ)); the "
                  "laser's wavelength is " +
                      wavelength + "; set visual_correction to false");
    }
  }
}

// The limits' standard and tissue (`hazard`); ANSI Z136.1-2014 for the eye by default.
void readHazardLimits(ObjectReader r, HazardSpec& h) {
  if (r.has("standard")) {
    const std::string name = r.string("standard");
    const std::optional<SafetyStandard> standard = standardNamed(name);
    if (!standard) {
      // "A" (the default), "B" or "C".
      std::string names;
      const std::size_t n = std::size(kStandards);
      for (std::size_t k = 0; k < n; ++k) {
        names += (k == 0       ? ""
                  : k + 1 == n ? " or "
                               : ", ") +
                 std::string("\"") + clauses(kStandards[k]).name + "\"" +
                 (k == 0 ? " (the default)" : "");
      }
      r.fail("standard", "must be " + names);
    }
    h.standard = *standard;
  }
  h.tissue = r.choice("tissue", {"eye", "skin"}, 0) == 0 ? Tissue::Eye : Tissue::Skin;
  readLevels(r, h);
  r.finish();
}

// The air (`atmosphere`): an extinction coefficient, or a visibility and the model that turns
// it into one at the laser's wavelength.
AtmosphereSpec readAtmosphere(ObjectReader r, double wavelength_nm) {
  AtmosphereSpec a;
  const bool by_extinction = r.has("extinction_per_m");
  const bool by_visibility = r.has("visibility_m");
  if (by_extinction == by_visibility) {
    r.failHere("give extinction_per_m or visibility_m (one of them)");
  }
  if (by_extinction) {
    a.extinction_per_m = r.number("extinction_per_m");
    inRange(r, "extinction_per_m", a.extinction_per_m, 0.0, 1.0, "1/m");
  } else {
    // Below 50 m a fog's extinction depends on more than the visibility; above 1000 km nothing
    // is that clear.
    a.visibility_m = inRange(r, "visibility_m", r.number("visibility_m"), 50.0, 1e6, "m");
    a.model = r.choice("visibility_model", {"kim", "kruse"}, 0) == 0 ? VisibilityModel::Kim
                                                                     : VisibilityModel::Kruse;
    a.extinction_per_m = extinctionFromVisibility(*a.visibility_m, wavelength_nm, a.model);
  }
  r.finish();
  return a;
}

// An optical aid (`optical_aid`): its aperture, magnification and transmission, or its gain.
OpticalAidSpec readOpticalAid(ObjectReader r, double wavelength_nm, SafetyStandard standard) {
  if (!(wavelength_nm >= 302.5 && wavelength_nm <= 4000.0)) {
    const StandardClauses& c = clauses(standard);
    r.failHere(std::string("optical aids transmit 302.5 nm to 4000 nm (") + c.name + " " +
               c.optical_aids + "); at " + formatNumber("%g", wavelength_nm) +
               " nm the standards apply none");
  }
  OpticalAidSpec aid;
  if (r.has("gain")) {
    if (r.has("aperture_m") || r.has("magnification") || r.has("transmission")) {
      r.failHere("give gain, or aperture_m, magnification and transmission, not both");
    }
    aid.gain = inRange(r, "gain", r.number("gain"), 1e-6, 1e6, "");
  } else {
    aid.aperture_m = inRange(r, "aperture_m", r.number("aperture_m"), 1e-3, 10.0, "m");
    aid.magnification = inRange(r, "magnification", r.number("magnification"), 1.0, 1e4, "");
    aid.transmission = r.number("transmission");
    if (!(*aid.transmission > 0.0 && *aid.transmission <= 1.0)) {
      r.fail("transmission", "must be in (0, 1]");
    }
    aid.gain = opticalGain(*aid.aperture_m, *aid.magnification, *aid.transmission, wavelength_nm);
  }
  r.finish();
  return aid;
}

// A value of the file that breaks one of its rules: the key named (empty: the object itself)
// and what is wrong.
struct Violation {
  std::string key;
  std::string message;
};

// One lobe's rules: its reflectance and σ, under the keys @p reflectance_key and @p sigma_key.
std::optional<Violation> lobeViolation(double reflectance, const Beckmann& shape,
                                       const std::string& reflectance_key,
                                       const std::string& sigma_key) {
  if (auto v = unitIntervalVerdict(reflectance)) return Violation{reflectance_key, *v};
  if (auto v = positiveVerdict(shape.sigma)) return Violation{sigma_key, *v};
  if (auto v = inRangeVerdict(shape.sigma, limits::kMinSigma, 1e6, ""))
    return Violation{sigma_key, *v};
  return std::nullopt;
}

// ABg's rules: A, B and g in range, its peak A/B within what the arithmetic carries
// (limits.h) and its width no finer than the finest lobe's. The keys are the object's own.
std::optional<Violation> abgViolation(const AbgScatter& abg) {
  if (auto v = inRangeVerdict(abg.a_per_sr, 0.0, 1e6, "1/sr")) return Violation{"a_per_sr", *v};
  if (auto v = inRangeVerdict(abg.b, 1e-12, 1e6, "")) return Violation{"b", *v};
  if (!(abg.g > 0.0 && abg.g <= 4.0)) return Violation{"g", "must be in (0, 4]"};
  if (!(abg.a_per_sr / abg.b <= 1e10)) {
    return Violation{
        "", "the peak A/B must be ≤ 1e10 1/sr, not " + formatNumber("%.6g", abg.a_per_sr / abg.b)};
  }
  if (abg.a_per_sr > 0.0 && !(abg.widthRad() >= limits::kMinSigma)) {
    return Violation{"",
                     "the peak is narrower than any surface glint models (B^(1/g) / (2 "
                     "max(1, g)) = " +
                         formatNumber("%.3g", abg.widthRad()) + " rad < " +
                         formatNumber("%g", limits::kMinSigma) + "): raise B or g"};
  }
  return std::nullopt;
}

// The energy a material reflects at most, and its parts in words, for the refusal.
struct EnergyBudget {
  double total = 0.0;
  std::vector<std::string> parts;
};

EnergyBudget energyBudget(const Material& m) {
  EnergyBudget e;
  const bool listed = !m.more_lobes.empty();
  e.total = m.totalSpecularReflectance() + m.diffuse_reflectance;
  e.parts.emplace_back(listed ? "the lobes' reflectances" : "specular_reflectance");
  if (m.abg) {
    const double tis = m.abg->totalIntegratedScatter();
    e.total += tis;
    e.parts.push_back("ABg's total integrated scatter (" + formatNumber("%.4g", tis) + ")");
  }
  if (m.table) {
    const BrdfTable::Reflectance r = m.table->maxHemisphericalReflectance();
    e.total += r.value;
    e.parts.push_back("the table's largest hemispherical reflectance (" +
                      formatNumber("%.4g", r.value) + " at θi " +
                      formatNumber("%.3g", r.theta_i_rad * 180.0 / kPi) + "°)");
  }
  e.parts.emplace_back("diffuse_reflectance");
  return e;
}

// A material's rules, in the order its reader applies them. A material of several lobes came
// from the key `lobes`, and its lobes are named there.
std::optional<Violation> materialViolation(const Material& m) {
  const bool listed = !m.more_lobes.empty();
  if (auto v = lobeViolation(m.specular_reflectance, m.lobe,
                             listed ? "lobes/0/reflectance" : "specular_reflectance",
                             listed ? "lobes/0/sigma" : "sigma"))
    return v;
  for (std::size_t k = 0; k < m.more_lobes.size(); ++k) {
    const std::string at = "lobes/" + std::to_string(k + 1) + "/";
    if (auto v = lobeViolation(m.more_lobes[k].reflectance, m.more_lobes[k].shape,
                               at + "reflectance", at + "sigma"))
      return v;
  }
  if (m.abg) {
    if (auto v = abgViolation(*m.abg))
      return Violation{v->key.empty() ? "abg" : "abg/" + v->key, v->message};
  }
  if (auto v = unitIntervalVerdict(m.diffuse_reflectance))
    return Violation{"diffuse_reflectance", *v};
  const EnergyBudget e = energyBudget(m);
  if (e.total > 1.0) {
    std::string sum;
    for (const std::string& part : e.parts) sum += (sum.empty() ? "" : " + ") + part;
    return Violation{
        "", sum + " must be ≤ 1 (energy conservation), not " + formatNumber("%.6g", e.total)};
  }
  return std::nullopt;
}

// The key `lobes`: each lobe's reflectance and σ, the first as the material's own.
void readLobes(ObjectReader& r, Material& m) {
  const nlohmann::json& list = r.raw().at("lobes");
  if (!list.is_array() || list.empty() || list.size() > limits::kMaxLobes) {
    r.fail("lobes", "must be a list of 1 to " + std::to_string(limits::kMaxLobes) +
                        " lobes, each {\"reflectance\", \"sigma\"}");
  }
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string at = r.at("lobes") + "/" + std::to_string(i);
    if (!list[i].is_object()) throw InputError(r.source() + ": " + at + ": must be an object");
    ObjectReader l(list[i], at, r.source());
    SpecularLobe lobe{l.number("reflectance"), Beckmann{l.number("sigma")}};
    if (auto v = lobeViolation(lobe.reflectance, lobe.shape, "reflectance", "sigma"))
      l.fail(v->key, v->message);
    l.finish();
    if (i == 0) {
      m.specular_reflectance = lobe.reflectance;
      m.lobe = lobe.shape;
    } else {
      m.more_lobes.push_back(lobe);
    }
  }
}

// The key `abg`: {a_per_sr, b, g}.
AbgScatter readAbg(ObjectReader r) {
  AbgScatter abg;
  abg.a_per_sr = r.number("a_per_sr");
  abg.b = r.number("b");
  abg.g = r.number("g");
  if (auto v = abgViolation(abg)) {
    if (v->key.empty()) r.failHere(v->message);
    r.fail(v->key, v->message);
  }
  r.finish();
  return abg;
}

// A material, and the file of its measured table (empty: none), resolved against @p base and
// read within @p memory_budget_bytes (0: none).
std::pair<Material, std::filesystem::path> readMaterial(ObjectReader r,
                                                        const std::filesystem::path& base,
                                                        std::uint64_t memory_budget_bytes) {
  Material m;
  std::filesystem::path table_file;
  const bool other = r.has("abg") || r.has("table") || r.has("diffuse_reflectance");
  if (r.has("lobes")) {
    for (const char* single : {"specular_reflectance", "sigma"}) {
      if (r.has(single))
        r.fail(single, "give the lobes either in `lobes` or as specular_reflectance and sigma");
    }
    readLobes(r, m);
  } else if (!other || r.has("specular_reflectance") || r.has("sigma")) {
    // A material of ABg, a table or a Lambertian part alone needs no lobe.
    m.specular_reflectance = r.number("specular_reflectance");
    m.lobe.sigma = r.number("sigma");
  }
  if (r.has("abg")) m.abg = readAbg(r.object("abg"));
  if (r.has("table")) {
    table_file = base / r.string("table");
    try {
      m.table = readBrdfTable(table_file, memory_budget_bytes);
    } catch (const InputError& e) {
      r.fail("table", e.what());
    }
  }
  m.diffuse_reflectance = r.number("diffuse_reflectance", 0.0);
  if (auto v = materialViolation(m)) {
    if (v->key.empty()) r.failHere(v->message);
    r.fail(v->key, v->message);
  }
  r.finish();
  return {std::move(m), std::move(table_file)};
}

MeshTransform readTransform(ObjectReader r) {
  MeshTransform t;
  if (r.has("translation")) t.translation_m = position(r, "translation");
  if (r.has("rotation") && r.has("yaw_pitch_roll_deg")) {
    r.failHere("give either rotation (a quaternion) or yaw_pitch_roll_deg, not both");
  }
  if (r.has("rotation")) {
    const json& q = r.require("rotation");
    if (!q.is_array() || q.size() != 4 || !std::all_of(q.begin(), q.end(), [](const json& x) {
          return x.is_number() && std::isfinite(x.get<double>());
        })) {
      r.fail("rotation", "must be a quaternion [x, y, z, w] of 4 finite numbers (glTF's order)");
    }
    const glm::dquat rotation(q[3].get<double>(), q[0].get<double>(), q[1].get<double>(),
                              q[2].get<double>());
    const double length = glm::length(rotation);
    if (!(std::abs(length - 1.0) < 1e-3)) r.fail("rotation", "must be a unit quaternion");
    t.rotation = rotation / length;
  }
  if (r.has("yaw_pitch_roll_deg")) {
    const Vec3 a = r.vec3("yaw_pitch_roll_deg");
    t.rotation = yawPitchRoll(a[0], a[1], a[2]);
  }
  if (r.has("scale")) {
    const json& v = r.require("scale");
    t.scale = v.is_number() ? Vec3(r.number("scale")) : r.vec3("scale");
    for (int i = 0; i < 3; ++i) {
      if (!(std::abs(t.scale[i]) > 0.0)) r.fail("scale", "must be non-zero (negative mirrors)");
    }
  }
  r.finish();
  return t;
}

// The memory a mesh may take as a target: the run's budget (0: none) and whether its facets
// join an occluder (the scene's accuracy.occlusion; any mesh can shadow itself).
struct MeshBudget {
  std::uint64_t budget_bytes = 0;
  bool occlusion = true;
};

MeshSpec readMesh(ObjectReader& r, const std::filesystem::path& folder, const GltfLimits& limits,
                  const MeshBudget& budget) {
  MeshSpec m;
  const std::string file = r.string("file");
  m.file = folder / file;
  static constexpr MeshSurface kSurfaces[] = {MeshSurface::PN, MeshSurface::QuadricFit,
                                              MeshSurface::Flat, MeshSurface::Nagata};
  std::vector<std::string> names;
  for (const MeshSurface s : kSurfaces) names.emplace_back(toString(s));
  m.surface = kSurfaces[r.choice("surface", names, 0)];
  m.crease_angle_deg = r.number("crease_angle_deg", m.crease_angle_deg);
  if (!(m.crease_angle_deg >= 0.0 && m.crease_angle_deg <= 180.0)) {
    r.fail("crease_angle_deg", "must be in [0, 180]");
  }
  if (r.has("transform")) m.transform = readTransform(r.object("transform"));

  GltfModel model;
  try {
    GltfLimits budgeted = limits;
    if (budget.budget_bytes > 0) {
      budgeted.before_decoding = [&](const GltfCounts& c) {
        requireWithinBudget(
            file + " (" + std::to_string(c.triangles) + " triangles, as a target)",
            meshMemoryFloorBytes(c.triangles, c.vertices, m.surface, budget.occlusion),
            budget.budget_bytes, "decimate the mesh, or raise --memory");
      };
    }
    model = loadGltf(m.file, budgeted);
  } catch (const InputError& e) {
    r.fail("file", e.what());
  }
  // Into the object's frame: scaled, rotated, relative to the translation. A mirroring scale
  // turns the faces inside out, so their winding is flipped back.
  const MeshTransform& t = m.transform;
  double reach_m = 0.0;
  for (Vec3& p : model.mesh.positions_m) {
    p = t.rotation * (t.scale * p);
    const double length = glm::length(p);
    if (!(length <= reach_m)) reach_m = length;  // a NaN is kept, and refused below
    if (!std::isfinite(reach_m)) break;
  }
  if (!(reach_m <= limits::kMaxLengthM)) {
    char message[128];
    std::snprintf(message, sizeof message,
                  "the mesh, transformed, reaches %g m from its origin: at most %g m", reach_m,
                  limits::kMaxLengthM);
    r.fail(r.has("transform") ? "transform" : "file", message);
  }
  for (Vec3& n : model.mesh.normals) {
    n = tryNormalize(t.rotation * (n / t.scale)).value_or(Vec3(0.0));
  }
  if (t.scale.x * t.scale.y * t.scale.z < 0.0) {
    for (auto& tri : model.mesh.triangles) std::swap(tri[1], tri[2]);
  }
  // A target that is not there must not read as a safe one.
  if (usableTriangles(model.mesh) == 0) {
    r.fail("file", m.file.string() + ": none of its " +
                       std::to_string(model.mesh.triangles.size()) +
                       " triangles is usable (each has zero area or a non-finite corner, as "
                       "transformed), so there is no target to judge");
  }
  m.normals_computed = fillNormals(model.mesh, m.crease_angle_deg * kPi / 180.0);
  m.primitives_skipped = model.primitives_skipped;
  m.mirrored_instances = model.mirrored_instances;
  m.mesh = std::make_shared<const TriangleMesh>(std::move(model.mesh));
  return m;
}

// Each analytic shape's own keys, beside `center` and `radius` (docs/scene.md). An alternative
// of AnalyticShape without its reader here does not compile (shapeTable()).
CylinderShape readShape(ObjectReader& r, const Vec3& centre_m, double radius_m,
                        std::type_identity<CylinderShape>) {
  const Vec3 axis = r.direction("axis");
  const double length_m =
      inRange(r, "length", r.number("length"), limits::kMinLengthM, limits::kMaxLengthM, "m");
  return {centre_m, axis, radius_m, length_m};
}
SphereShape readShape(ObjectReader&, const Vec3& centre_m, double radius_m,
                      std::type_identity<SphereShape>) {
  return {centre_m, radius_m};
}
DiskShape readShape(ObjectReader& r, const Vec3& centre_m, double radius_m,
                    std::type_identity<DiskShape>) {
  return {centre_m, r.direction("normal"), radius_m};
}
ConeShape readShape(ObjectReader& r, const Vec3& centre_m, double radius_m,
                    std::type_identity<ConeShape>) {
  const Vec3 axis = r.direction("axis");
  const double top_radius_m = inRange(r, "top_radius", r.number("top_radius"), limits::kMinLengthM,
                                      limits::kMaxLengthM, "m");
  const double length_m =
      inRange(r, "length", r.number("length"), limits::kMinLengthM, limits::kMaxLengthM, "m");
  // Equal radii make the cone's quadric a cylinder's with its apex at infinity.
  if (std::abs(top_radius_m - radius_m) <= 1e-6 * std::max(top_radius_m, radius_m)) {
    r.fail("top_radius", "must differ from radius (equal radii: use shape \"cylinder\")");
  }
  return {centre_m, axis, radius_m, top_radius_m, length_m};
}

// The analytic shapes by their names in scene files, in AnalyticShape's order.
struct ShapeEntry {
  const char* name;
  AnalyticShape (*read)(ObjectReader& r, const Vec3& centre_m, double radius_m);
};
template <std::size_t... I>
constexpr std::array<ShapeEntry, sizeof...(I)> shapeTable(std::index_sequence<I...>) {
  return {ShapeEntry{std::variant_alternative_t<I, AnalyticShape>::kName,
                     [](ObjectReader& r, const Vec3& centre_m, double radius_m) -> AnalyticShape {
                       return readShape(
                           r, centre_m, radius_m,
                           std::type_identity<std::variant_alternative_t<I, AnalyticShape>>{});
                     }}...};
}
constexpr auto kShapes = shapeTable(std::make_index_sequence<std::variant_size_v<AnalyticShape>>{});

ObjectSpec readObject(ObjectReader r, const std::vector<std::string>& material_names,
                      const std::filesystem::path& folder, const GltfLimits& mesh_limits,
                      const MeshBudget& mesh_budget) {
  ObjectSpec o;
  std::vector<std::string> shapes;
  for (const ShapeEntry& e : kShapes) shapes.emplace_back(e.name);
  shapes.emplace_back("mesh");
  const std::size_t shape = r.choice("shape", shapes);
  if (shape < kShapes.size()) {
    const Vec3 centre_m = position(r, "center");
    const double radius_m =
        inRange(r, "radius", r.number("radius"), limits::kMinLengthM, limits::kMaxLengthM, "m");
    o.shape = kShapes[shape].read(r, centre_m, radius_m);
  } else {
    o.shape = readMesh(r, folder, mesh_limits, mesh_budget);
  }
  const std::string material = r.string("material");
  const auto it = std::find(material_names.begin(), material_names.end(), material);
  if (it == material_names.end()) {
    std::vector<std::string> names;
    for (const auto& name : material_names) names.push_back("\"" + name + "\"");
    r.fail("material", "no material named \"" + material + "\" (defined: " + joinKeys(names) + ")");
  }
  o.material = static_cast<std::uint32_t>(it - material_names.begin());
  if (o.analytic()) {
    const std::int64_t segments = r.integer("segments", o.segments);
    if (segments < 3 || segments > 4096) r.fail("segments", "must be an integer in [3, 4096]");
    o.segments = static_cast<int>(segments);
  }
  r.finish();
  return o;
}

// A floor `key` of @p floor_w_m2, refused where it could read a hazard of @p hazard as none
// (HazardSpec::largestFloorW_m2()).
double floorBelowHazard(ObjectReader& r, const char* key, double floor_w_m2,
                        const HazardSpec& hazard) {
  const double largest = hazard.largestFloorW_m2();
  if (!(floor_w_m2 <= largest)) {
    r.fail(key, formatNumber("%.3g", floor_w_m2) +
                    " W/m² could hide a hazard: it must be at most a hundredth of the lowest "
                    "hazardous irradiance (the MPE" +
                    (hazard.aidGain() > 1.0 ? " through the optical aid" : "") + ", " +
                    formatNumber("%.3g", hazard.lowestHazardousW_m2()) + " W/m²), " +
                    formatNumber("%.3g", largest) + " W/m²");
  }
  return floor_w_m2;
}

// The `accuracy` settings; the floor is @p default_floor_w_m2 unless the file gives one.
IntegratorOptions readAccuracy(ObjectReader r, double default_floor_w_m2,
                               const HazardSpec& hazard) {
  IntegratorOptions a;
  a.tolerance = r.number("tolerance", a.tolerance);
  if (!(a.tolerance > 0.0 && a.tolerance < 1.0)) r.fail("tolerance", "must be in (0, 1)");
  a.floor_w_m2 = default_floor_w_m2;
  if (auto floor = r.optionalNumber("floor_w_m2")) {
    if (!(*floor >= 0.0)) r.fail("floor_w_m2", "must be ≥ 0");
    a.floor_w_m2 = floorBelowHazard(r, "floor_w_m2", *floor, hazard);
  }
  const std::int64_t depth = r.integer("max_depth", a.max_depth);
  if (depth < 0 || depth > 24) r.fail("max_depth", "must be an integer in [0, 24]");
  a.max_depth = static_cast<int>(depth);
  a.max_evaluations = r.integer("max_evaluations", a.max_evaluations);
  if (a.max_evaluations < 1) r.fail("max_evaluations", "must be an integer ≥ 1");
  a.normals =
      r.choice("normals", {"surface", "flat"}, 0) == 0 ? NormalModel::Surface : NormalModel::Flat;
  if (r.has("scheme")) {
    a.scheme = static_cast<IntegrationScheme>(r.choice("scheme", integrationSchemeNames(), 0));
    if (a.normals == NormalModel::Flat && a.scheme != IntegrationScheme::Paper)
      r.fail("scheme",
             "flat normals (normals: flat) are the paper scheme's only; use scheme: paper");
  } else if (a.normals == NormalModel::Flat) {
    a.scheme = IntegrationScheme::Paper;
  }
  if (r.has("occlusion")) {
    const json& v = r.require("occlusion");
    if (!v.is_boolean()) r.fail("occlusion", "must be true or false");
    a.occlusion = v.get<bool>();
  }
  r.finish();
  return a;
}

// A coarsest block of `block_key`: `lattice_m` times a power of two (default 16).
double blockSize(ObjectReader& r, const char* block_key, const char* lattice_key,
                 double lattice_m) {
  const double block_m = r.number(block_key, FieldSpec{}.block_voxels * lattice_m);
  const double ratio = block_m / lattice_m;
  const double power = std::round(std::log2(ratio));
  if (!(ratio >= 1.0) || std::abs(ratio - std::exp2(power)) > 1e-9 * ratio || power > 12) {
    r.fail(block_key,
           std::string("must be ") + lattice_key + " times a power of two (1, 2, 4, ..., 4096)");
  }
  return lattice_m * std::exp2(power);
}

// The refinement's `tolerance` (kept as given when absent) and `floor_w_m2` of an observer
// box or plane.
void readRefinement(ObjectReader& r, double& tolerance, std::optional<double>& floor_w_m2,
                    const HazardSpec& hazard) {
  tolerance = r.number("tolerance", tolerance);
  if (!(tolerance > 0.0 && tolerance < 1.0)) r.fail("tolerance", "must be in (0, 1)");
  if (auto floor = r.optionalNumber("floor_w_m2")) {
    if (!(*floor > 0.0)) r.fail("floor_w_m2", "must be > 0");
    floor_w_m2 = floorBelowHazard(r, "floor_w_m2", *floor, hazard);
  }
}

ObserversSpec readObservers(ObjectReader r, const HazardSpec& hazard) {
  ObserversSpec o;
  o.min_m = position(r, "min");
  o.max_m = position(r, "max");
  for (int a = 0; a < 3; ++a) {
    if (!(o.max_m[a] > o.min_m[a])) r.fail("max", "must exceed min on every axis");
  }
  o.voxel_m =
      inRange(r, "voxel_m", r.number("voxel_m"), limits::kMinLengthM, limits::kMaxLengthM, "m");
  const Vec3 extent = o.max_m - o.min_m;
  const double longest = std::max({extent.x, extent.y, extent.z});
  // Bounds the lattice (and the dense twin) to what a 32-bit OpenVDB index and memory allow.
  if (longest / o.voxel_m > 65536.0)
    r.fail("voxel_m", "gives more than 65536 voxels along an axis");
  o.block_m = blockSize(r, "block_m", "voxel_m", o.voxel_m);
  readRefinement(r, o.tolerance, o.floor_w_m2, hazard);
  r.finish();
  return o;
}

PlaneSpec readPlane(ObjectReader r, const std::vector<PlaneSpec>& earlier,
                    const HazardSpec& hazard) {
  PlaneSpec p;
  p.name = r.string("name");
  const bool safe =
      !p.name.empty() && p.name.size() <= 64 &&
      std::all_of(p.name.begin(), p.name.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '-';
      });
  if (!safe) r.fail("name", "must be 1 to 64 letters, digits, '_' or '-' (it names the .exr file)");
  for (const PlaneSpec& e : earlier) {
    if (e.name == p.name) r.fail("name", "\"" + p.name + "\" names two planes");
  }
  // Its map would take the name of the far field's or the reach's.
  for (const char* taken : {output_names::kFarFieldExr, output_names::kReachExr}) {
    if (output_names::planeExr(p.name) == taken)
      r.fail("name", "\"" + p.name + "\" is taken: glint run writes " + taken);
  }
  p.origin_m = position(r, "origin");
  p.u_axis = r.direction("u_axis");
  p.v_axis = r.direction("v_axis");
  if (!(std::abs(glm::dot(p.u_axis, p.v_axis)) <= 1e-6)) {
    r.fail("v_axis", "must be perpendicular to u_axis");
  }
  // Exactly perpendicular from here on: the lattice's axes must be orthonormal.
  p.v_axis = glm::normalize(p.v_axis - glm::dot(p.v_axis, p.u_axis) * p.u_axis);
  const json& size = r.require("size_m");
  if (!size.is_array() || size.size() != 2 || !size[0].is_number() || !size[1].is_number())
    r.fail("size_m", "must be an array of 2 numbers (extent along u_axis, along v_axis)");
  p.width_m = size[0].get<double>();
  p.height_m = size[1].get<double>();
  if (!(p.width_m > 0.0 && p.height_m > 0.0 && p.width_m <= 2.0 * limits::kMaxCoordinateM &&
        p.height_m <= 2.0 * limits::kMaxCoordinateM)) {
    r.fail("size_m", "must be > 0 and at most 2e7 m");
  }
  p.pixel_m =
      inRange(r, "pixel_m", r.number("pixel_m"), limits::kMinLengthM, limits::kMaxLengthM, "m");
  if (std::max(p.width_m, p.height_m) / p.pixel_m > 65536.0)
    r.fail("pixel_m", "gives more than 65536 pixels along an axis");
  p.block_m = blockSize(r, "block_m", "pixel_m", p.pixel_m);
  readRefinement(r, p.tolerance, p.floor_w_m2, hazard);
  if (auto above = r.optionalNumber("above_terrain_m")) {
    // Over the ground, from a person lying down to a mast.
    p.above_terrain_m = inRange(r, "above_terrain_m", *above, 0.05, 1000.0, "m");
    if (!(std::abs(glm::cross(p.u_axis, p.v_axis).z) >= 1.0 - 1e-9))
      r.fail("above_terrain_m", "needs a horizontal plane (u_axis and v_axis with z = 0)");
  }
  r.finish();
  return p;
}

}  // namespace

FieldSpec planeLattice(const PlaneSpec& plane) {
  FieldSpec f;
  f.plane = true;
  f.axes = {plane.u_axis, plane.v_axis, glm::cross(plane.u_axis, plane.v_axis)};
  f.min_m = plane.origin_m;
  f.max_m = plane.origin_m + plane.width_m * plane.u_axis + plane.height_m * plane.v_axis;
  f.voxel_m = plane.pixel_m;
  f.block_voxels = static_cast<int>(std::lround(plane.block_m / plane.pixel_m));
  f.surface = plane.surface;
  return f;
}

namespace {

// The local horizontal rectangle the terrain must cover: the laser, the objects, the box and
// the planes (with the whole blocks their lattices extend to), and a margin.
HorizontalBox sceneRegion(const Scene& scene) {
  Vec3 lo = scene.laser.origin_m, hi = scene.laser.origin_m;
  const auto take = [&](const Vec3& p) { lo = glm::min(lo, p), hi = glm::max(hi, p); };
  for (const ObjectSpec& o : scene.objects) take(o.centre_m());
  if (scene.observers) take(scene.observers->min_m), take(scene.observers->max_m);
  for (const PlaneSpec& p : scene.planes) {
    const double u = p.width_m + p.block_m, v = p.height_m + p.block_m;
    for (const Vec3& c : {p.origin_m, p.origin_m + u * p.u_axis, p.origin_m + v * p.v_axis,
                          p.origin_m + u * p.u_axis + v * p.v_axis})
      take(c);
  }
  if (scene.reach.footprint && !scene.objects.empty()) {
    // The footprint's square about the lit centre, which lies among the objects.
    const double r = scene.reach.footprint->radius_m;
    for (const ObjectSpec& o : scene.objects)
      take(o.centre_m() - Vec3(r, r, 0.0)), take(o.centre_m() + Vec3(r, r, 0.0));
  }
  const double margin = 10.0 + 0.05 * std::hypot(hi.x - lo.x, hi.y - lo.y);
  return {lo.x - margin, lo.y - margin, hi.x + margin, hi.y + margin};
}

// Why a terrain.file cannot be read, if it names something other than a file on this machine:
// a URL or one of GDAL's virtual file systems (/vsicurl/, /vsis3/, ...; the local ones too,
// /vsistdin/ among them). A scene file opens no connection (the GDAL module cannot either).
std::optional<std::string> nonLocalVerdict(const std::string& name) {
  std::string lower = name;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  static constexpr std::array<std::string_view, 9> kNetwork = {
      "/vsicurl", "/vsis3",    "/vsigs",   "/vsiaz",     "/vsiadls",
      "/vsioss",  "/vsiswift", "/vsihdfs", "/vsiwebhdfs"};
  for (std::string_view prefix : kNetwork) {
    if (lower.starts_with(prefix)) {
      return "is a network path (" + std::string(prefix.substr(1)) +
             "): a scene file opens no connection; download the elevation model and name the "
             "local file";
    }
  }
  if (lower.starts_with("/vsi")) {
    return "is a path in one of GDAL's virtual file systems: name the elevation model's own "
           "file (unpacked, if it is in an archive)";
  }
  // A URL: a scheme (RFC 3986: a letter, then letters, digits, +, -, .) and "://".
  const std::size_t colon = lower.find("://");
  if (colon != std::string::npos && colon > 0 &&
      std::isalpha(static_cast<unsigned char>(lower[0])) &&
      lower.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789+-.") >= colon) {
    return "is a URL: a scene file opens no connection; download the elevation model and name "
           "the local file";
  }
  return std::nullopt;
}

// Each lattice point of a plane laid over the terrain, raised to its height above the ground.
std::shared_ptr<const SurfaceOffsets> surfaceOffsets(const PlaneSpec& p, const Terrain& terrain,
                                                     const std::string& at) {
  const FieldSpec lattice = planeLattice(p);
  const auto n = lattice.nodes();
  auto s = std::make_shared<SurfaceOffsets>();
  s->width = n[0];
  s->height = n[1];
  s->offset_m.reserve(static_cast<std::size_t>(n[0]) * static_cast<std::size_t>(n[1]));
  for (int j = 0; j < n[1]; ++j)
    for (int i = 0; i < n[0]; ++i) {
      const Vec3 flat = lattice.position(i, j, 0);
      const std::optional<double> ground = terrain.surfaceZ(flat.x, flat.y);
      if (!ground) {
        throw InputError(at + ": the plane reaches beyond the terrain (or over a hole in it) at (" +
                         formatNumber("%.1f", flat.x) + ", " + formatNumber("%.1f", flat.y) +
                         ") m");
      }
      s->offset_m.push_back((*ground + *p.above_terrain_m - flat.z) / lattice.axes[2].z);
    }
  return s;
}

FarFieldSettings readFarField(ObjectReader r) {
  FarFieldSettings f;
  f.enabled = r.boolean("enabled", true);
  f.tolerance = r.number("tolerance", f.tolerance);
  if (!(f.tolerance > 0.0 && f.tolerance < 1.0)) r.fail("tolerance", "must be in (0, 1)");
  if (r.has("face_pixels")) {
    const std::int64_t n = r.integer("face_pixels", 0);
    if (n < 16 || n > 8192 || (n & (n - 1)) != 0)
      r.fail("face_pixels", "must be a power of two from 16 to 8192");
    f.face_pixels = static_cast<int>(n);
  }
  if (auto floor = r.optionalNumber("floor_w_sr")) {
    if (!(*floor > 0.0)) r.fail("floor_w_sr", "must be > 0");
    f.floor_w_sr = *floor;
  }
  r.finish();
  return f;
}

ReachSettings readReach(ObjectReader r) {
  ReachSettings reach;
  reach.enabled = r.boolean("enabled", true);
  const std::int64_t cells = r.integer("face_cells", reach.face_cells);
  if (cells < 16 || cells > 512 || cells % 16 != 0)
    r.fail("face_cells", "must be a multiple of 16 from 16 to 512");
  reach.face_cells = static_cast<int>(cells);
  reach.layer_ratio = r.number("layer_ratio", reach.layer_ratio);
  if (!(reach.layer_ratio > 1.0 && reach.layer_ratio <= 1.5))
    r.fail("layer_ratio", "must be in (1, 1.5]");
  if (r.has("footprint")) {
    ObjectReader f = r.object("footprint");
    FootprintSpec spec;
    spec.radius_m = inRange(f, "radius_m", f.number("radius_m", spec.radius_m), 1.0, 1e5, "m");
    if (auto pixel = f.optionalNumber("pixel_m")) {
      spec.pixel_m = inRange(f, "pixel_m", *pixel, 0.01, 1e4, "m");
      if (spec.radius_m / spec.pixel_m > 4096.0)
        f.fail("pixel_m", "gives more than 8193 pixels a side");
    }
    spec.above_ground_m = inRange(
        f, "above_ground_m", f.number("above_ground_m", spec.above_ground_m), 0.05, 1000.0, "m");
    if (f.has("flight_altitudes_m")) {
      const nlohmann::json& list = f.raw().at("flight_altitudes_m");
      if (!list.is_array() || list.empty() || list.size() > 16)
        f.fail("flight_altitudes_m", "must be a list of 1 to 16 altitudes (m)");
      for (const nlohmann::json& a : list) {
        if (!a.is_number() || !(a.get<double>() >= -500.0 && a.get<double>() <= 20000.0))
          f.fail("flight_altitudes_m", "each must be a number in [-500, 20000] m");
        spec.flight_altitudes_m.push_back(a.get<double>());
      }
    }
    spec.altitudes_above_ellipsoid =
        f.choice("altitude_reference", {"ground", "ellipsoid"}, 0) == 1;
    f.finish();
    reach.footprint = spec;
  }
  r.finish();
  return reach;
}

// The target's motion: keyed poses, or a constant velocity (and turn rate) through the scene's
// pose at t = 0.
void readTargetMotion(ObjectReader r, MotionSpec& m, std::optional<double>& start,
                      std::optional<double>& end) {
  const bool keyed = r.has("poses"), crossing = r.has("velocity_m_s") || r.has("turn_deg_s");
  if (keyed == crossing) {
    r.failHere("needs either `poses` or `velocity_m_s` (with, optionally, `turn_deg_s`)");
  }
  if (keyed) {
    const json& list = r.require("poses");
    if (!list.is_array() || list.empty()) r.fail("poses", "must be a non-empty array of poses");
    for (std::size_t i = 0; i < list.size(); ++i) {
      m.poses.push_back(
          readPoseKey(ObjectReader(list[i], r.at("poses") + "/" + std::to_string(i), r.source())));
      if (i > 0 && !(m.poses[i].time_s > m.poses[i - 1].time_s))
        r.fail("poses", "times must increase from pose to pose (pose " + std::to_string(i) + ")");
    }
    const std::size_t how = r.choice("interpolation", {"linear", "spline"}, 0);
    m.interpolation = how == 0 ? PoseInterpolation::Linear : PoseInterpolation::Spline;
    if (!start) start = m.poses.front().time_s;
    if (!end) end = m.poses.back().time_s;
  } else {
    if (!start || !end) r.failHere("a constant velocity needs the engagement's start_s and end_s");
    const Vec3 v = r.has("velocity_m_s") ? r.vec3("velocity_m_s") : Vec3(0.0);
    const Vec3 w = r.has("turn_deg_s") ? r.vec3("turn_deg_s") : Vec3(0.0);
    if (!(glm::length(v) <= 1e5)) r.fail("velocity_m_s", "must be at most 1e5 m/s");
    for (int a = 0; a < 3; ++a) {
      if (!(std::abs(w[a]) <= 1e5)) r.fail("turn_deg_s", "rates must be within ±1e5 deg/s");
    }
    for (double t : {*start, *end}) m.poses.push_back({t, v * t, w * t});
  }
  r.finish();
}

// Where the laser points: `fixed` (the default), `track` or `keyed` through `directions`.
void readLaserPointing(ObjectReader r, MotionSpec& m) {
  const std::size_t how = r.choice("pointing", {"fixed", "track", "keyed"}, 0);
  m.pointing = static_cast<LaserPointing>(how);
  if (m.pointing != LaserPointing::Keyed) {
    r.finish();
    return;
  }
  const json& list = r.require("directions");
  if (!list.is_array() || list.empty())
    r.fail("directions", "must be a non-empty array of {time_s, direction}");
  for (std::size_t i = 0; i < list.size(); ++i) {
    ObjectReader k(list[i], r.at("directions") + "/" + std::to_string(i), r.source());
    DirectionKey key{k.number("time_s"), k.direction("direction")};
    k.finish();
    if (i > 0) {
      const DirectionKey& before = m.laser_keys.back();
      if (!(key.time_s > before.time_s))
        r.fail("directions", "times must increase (key " + std::to_string(i) + ")");
      // Beyond a half turn the way between two keys is not unique.
      if (!(angleBetween(before.direction, key.direction) <= 0.5 * kPi))
        r.fail("directions", "consecutive directions must be at most 90 degrees apart (key " +
                                 std::to_string(i) + ")");
    }
    m.laser_keys.push_back(key);
  }
  r.finish();
}

EngagementSpec readEngagement(ObjectReader r, const Scene& scene) {
  EngagementSpec e;
  MotionSpec& m = e.motion;
  std::optional<double> start = r.optionalNumber("start_s"), end = r.optionalNumber("end_s");
  Vec3 centres(0.0);
  for (const ObjectSpec& o : scene.objects) centres += o.centre_m();
  m.pivot_m =
      r.has("pivot") ? position(r, "pivot") : centres / static_cast<double>(scene.objects.size());
  readTargetMotion(r.object("target"), m, start, end);
  if (r.has("laser")) readLaserPointing(r.object("laser"), m);
  if (r.has("observers")) {
    ObjectReader o = r.object("observers");
    m.observer_velocity_m_s = o.vec3("velocity_m_s");
    if (!(glm::length(m.observer_velocity_m_s) <= 1e5))
      o.fail("velocity_m_s", "must be at most 1e5 m/s");
    o.finish();
  }
  m.start_s = *start;
  m.end_s = *end;
  // The MPE table runs from 1 ns to 30 000 s: every window must lie in it.
  if (!(m.end_s - m.start_s >= 1e-9 && m.end_s - m.start_s <= 3e4))
    r.fail("end_s", "must follow start_s by 1e-9 to 30000 s");
  e.time.tolerance = scene.accuracy.tolerance;
  e.time.floor_w_m2 = scene.hazard.negligibleW_m2();
  if (r.has("time")) {
    ObjectReader t = r.object("time");
    e.time.tolerance = t.number("tolerance", e.time.tolerance);
    if (!(e.time.tolerance > 0.0 && e.time.tolerance < 1.0))
      t.fail("tolerance", "must be in (0, 1)");
    if (auto floor = t.optionalNumber("floor_w_m2")) {
      e.time.floor_w_m2 =
          floorBelowHazard(t, "floor_w_m2", positive(t, "floor_w_m2", *floor), scene.hazard);
    }
    const std::int64_t n = t.integer("initial_intervals", e.time.initial_intervals);
    if (n < 1 || n > 4096) t.fail("initial_intervals", "must be from 1 to 4096");
    e.time.initial_intervals = static_cast<int>(n);
    const std::int64_t depth = t.integer("max_depth", e.time.max_depth);
    if (depth < 0 || depth > 30) t.fail("max_depth", "must be from 0 to 30");
    e.time.max_depth = static_cast<int>(depth);
    t.finish();
  }
  e.longest_window_s = std::min(m.end_s - m.start_s, scene.hazard.exposure_s);
  if (scene.hazard.pulse) {
    r.failHere(
        "an engagement needs a continuous laser: a pulsed laser swept across an eye is a train "
        "of its own pulses within the train of crossings, which engagements do not judge yet; "
        "remove laser.pulse");
  }
  r.finish();
  return e;
}

// The laser and what its light is judged by: the hazard's limits, the atmosphere and any
// optical aid of the viewer.
void readLaserAndHazard(ObjectReader& r, Scene& scene) {
  if (r.has("hazard")) readHazardLimits(r.object("hazard"), scene.hazard);
  scene.laser = readLaser(r.object("laser"), scene.hazard);
  checkLevels(r, scene.hazard);
  const double wavelength_nm = scene.hazard.wavelength_nm;
  if (r.has("atmosphere")) {
    scene.hazard.atmosphere = readAtmosphere(r.object("atmosphere"), wavelength_nm);
  }
  scene.laser.extinction_per_m = scene.hazard.atmosphere.extinction_per_m;
  scene.laser.return_extinction_per_m = scene.hazard.atmosphere.extinction_per_m;
  if (r.has("optical_aid")) {
    if (scene.hazard.tissue == Tissue::Skin) {
      r.fail("optical_aid",
             "is a viewer's: it changes the eye's exposure, and hazard.tissue is \"skin\"");
    }
    scene.hazard.aid =
        readOpticalAid(r.object("optical_aid"), wavelength_nm, scene.hazard.standard);
  }
  completeHazard(scene.hazard);
}

void readMaterials(ObjectReader materials, Scene& scene, const std::filesystem::path& base,
                   std::uint64_t memory_budget_bytes) {
  if (materials.raw().empty()) materials.failHere("must define at least one material");
  for (const auto& [name, value] : materials.raw().items()) {
    materials.has(name);
    auto [material, table_file] = readMaterial(
        ObjectReader(value, materials.at(name), materials.source()), base, memory_budget_bytes);
    scene.materials.push_back(std::move(material));
    scene.material_table_files.push_back(std::move(table_file));
    scene.material_names.push_back(name);
  }
  materials.finish();
}

void readAccuracyAndObjects(ObjectReader& r, Scene& scene, const std::filesystem::path& base,
                            const GltfLimits& mesh_limits, std::uint64_t memory_budget_bytes) {
  const json& objects = r.require("objects");
  if (!objects.is_array() || objects.empty()) {
    r.fail("objects", "must be a non-empty array of objects");
  }
  // Before the objects: whether a mesh joins an occluder decides what it costs in memory.
  // The default floor: far below the beam (a focused beam lights its spot far above any limit)
  // and below every threshold judged (HazardSpec::negligibleW_m2()).
  const double default_floor_w_m2 =
      std::min(1e-9 * scene.laser.peakIrradiance(), scene.hazard.negligibleW_m2());
  scene.accuracy.floor_w_m2 = default_floor_w_m2;
  if (r.has("accuracy")) {
    scene.accuracy = readAccuracy(r.object("accuracy"), default_floor_w_m2, scene.hazard);
  }
  for (std::size_t i = 0; i < objects.size(); ++i) {
    scene.objects.push_back(readObject(
        ObjectReader(objects[i], "/objects/" + std::to_string(i), r.source()), scene.material_names,
        base, mesh_limits, {memory_budget_bytes, scene.accuracy.occlusion}));
  }
}

void readPlanes(ObjectReader& r, Scene& scene) {
  const json& planes = r.require("planes");
  if (!planes.is_array()) r.fail("planes", "must be an array of planes");
  for (std::size_t i = 0; i < planes.size(); ++i) {
    scene.planes.push_back(
        readPlane(ObjectReader(planes[i], "/planes/" + std::to_string(i), r.source()), scene.planes,
                  scene.hazard));
  }
}

// The terrain's memory, with the target's that the run holds beside it, is held to the budget
// before a height is read.
void requireTerrainWithinBudget(const Scene& scene, std::size_t posts,
                                std::uint64_t memory_budget_bytes) {
  if (memory_budget_bytes == 0) return;
  const std::uint64_t target_bytes = targetMemory(scene, scene.accuracy).floor_bytes;
  requireWithinBudget(
      "the terrain (" + std::to_string(posts) + " posts over the scene's region" +
          (target_bytes > 0
               ? ", with the target's " + formatBytes(static_cast<double>(target_bytes))
               : std::string()) +
          ")",
      Terrain::memoryBytes(posts) + target_bytes, memory_budget_bytes,
      "crop the elevation model or resample it to a coarser post spacing, shrink the "
      "scene's region, or raise --memory");
}

void readTerrain(ObjectReader& r, Scene& scene, const std::filesystem::path& base,
                 std::uint64_t memory_budget_bytes) {
  ObjectReader t = r.object("terrain");
  const std::string file = t.string("file");
  if (const auto why = nonLocalVerdict(file)) t.fail("file", *why);
  scene.terrain_file = base / file;
  const std::int64_t max_posts = t.integer("max_posts", 4'000'000);
  if (max_posts < 4 || max_posts > 100'000'000) t.fail("max_posts", "must be from 4 to 1e8");
  t.finish();
  if (!scene.site) r.fail("terrain", "needs a site: the elevation model lies on the Earth");
  if (scene.engagement) {
    r.fail("terrain", "cannot join an engagement yet: the target moves and the ground does not");
  }
  const auto within_budget = [&](std::size_t posts) {
    requireTerrainWithinBudget(scene, posts, memory_budget_bytes);
  };
  try {
    scene.terrain = Terrain::read(scene.terrain_file, SiteFrame(*scene.site), sceneRegion(scene),
                                  static_cast<std::size_t>(max_posts), within_budget);
  } catch (const std::runtime_error& e) {
    throw InputError(r.source() + ": /terrain/file: " + e.what());
  }
  scene.accuracy.terrain = scene.terrain->mesh();
}

// The planes given a height above the terrain follow its ground.
void placePlanesOnTerrain(Scene& scene, const std::string& source) {
  for (std::size_t i = 0; i < scene.planes.size(); ++i) {
    PlaneSpec& p = scene.planes[i];
    if (!p.above_terrain_m) continue;
    const std::string at = source + ": /planes/" + std::to_string(i) + "/above_terrain_m";
    if (!scene.terrain) throw InputError(at + ": there is no terrain");
    p.surface = surfaceOffsets(p, *scene.terrain, at);
  }
}

}  // namespace

Scene parseScene(std::string_view text, const std::string& source,
                 const std::optional<std::filesystem::path>& folder, const GltfLimits& mesh_limits,
                 std::uint64_t memory_budget_bytes) {
  const std::filesystem::path base = folder ? *folder : std::filesystem::path(source).parent_path();
  const json root = parseJson(text, source);
  Scene scene;
  scene.source = source;
  ObjectReader r(root, "", source);
  scene.description = r.string("description", "");
  readLaserAndHazard(r, scene);
  readMaterials(r.object("materials"), scene, base, memory_budget_bytes);
  readAccuracyAndObjects(r, scene, base, mesh_limits, memory_budget_bytes);

  if (r.has("observers")) scene.observers = readObservers(r.object("observers"), scene.hazard);
  if (r.has("planes")) readPlanes(r, scene);
  if (r.has("far_field")) scene.far_field = readFarField(r.object("far_field"));
  if (r.has("reach")) scene.reach = readReach(r.object("reach"));
  if (r.has("engagement")) scene.engagement = readEngagement(r.object("engagement"), scene);
  if (r.has("site")) scene.site = readSite(r.object("site"));
  if (scene.reach.footprint && !scene.site)
    r.fail("reach", "has a footprint, which needs a site: it is drawn on the Earth");
  requireDistinctOutputNames(scene);
  if (r.has("terrain")) readTerrain(r, scene, base, memory_budget_bytes);
  placePlanesOnTerrain(scene, source);
  r.finish();
  return scene;
}

std::uint64_t terrainMemoryBytes(const Scene& scene) {
  return scene.terrain ? scene.terrain->memoryBytes() : 0;
}

std::string terrainMemoryWhat(const Scene& scene) {
  return scene.terrain ? "the terrain (" + std::to_string(scene.terrain->windowPosts()) + " posts)"
                       : std::string();
}

void noteTerrain(MemoryWatch& watch, const Scene& scene) {
  if (!scene.terrain) return;
  watch.noteHeld(terrainMemoryWhat(scene), terrainMemoryBytes(scene),
                 "crop the elevation model or resample it to a coarser post spacing");
}

std::string readUserFile(const std::filesystem::path& path, const std::string& what,
                         std::uintmax_t max_bytes) {
  std::ifstream in(path, std::ios::binary);
  const std::string name = path.string();
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw InputError(name + ": is a folder, not a " + what);
  if (!in) throw InputError(name + ": cannot open the " + what);
  // In chunks up to the cap: the size a file claims is no help for a pipe or a device.
  std::string text;
  std::vector<char> chunk(std::size_t{1} << 20);
  while (in) {
    in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
    const auto got = static_cast<std::size_t>(in.gcount());
    if (text.size() + got > max_bytes) {
      char limit[32];
      std::snprintf(limit, sizeof limit, "%.3g", static_cast<double>(max_bytes) / (1 << 20));
      throw InputError(name + ": longer than " + limit + " MiB, more than a " + what + " may be");
    }
    text.append(chunk.data(), got);
  }
  if (in.bad()) throw InputError(name + ": cannot read the " + what);
  return text;
}

std::string fnv1a64Hex(std::string_view bytes) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(fnv1a64(bytes)));
  return buf;
}

void recheckScene(const Scene& scene) {
  // The reader's own rules (materialViolation(), positionVerdict()), so that a value made in
  // memory is refused with the words and JSON pointer the same value in a file gets.
  auto refuse = [&](const std::string& at, const std::string& message) {
    throw InputError(scene.source + ": " + at + ": " + message);
  };
  for (std::size_t i = 0; i < scene.materials.size(); ++i) {
    if (auto v = materialViolation(scene.materials[i])) {
      const std::string at = "/materials/" + escapeToken(scene.material_names[i]);
      // The keys are the reader's own, already JSON pointer fragments (`lobes/1/sigma`).
      refuse(v->key.empty() ? at : at + "/" + v->key, v->message);
    }
  }
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    const ObjectSpec& o = scene.objects[i];
    if (auto v = positionVerdict(o.centre_m())) {
      refuse("/objects/" + std::to_string(i) + (o.mesh() ? "/transform/translation" : "/center"),
             *v);
    }
  }
}

Scene loadScene(const std::filesystem::path& path, std::uint64_t memory_budget_bytes) {
  return parseScene(readUserFile(path, "scene file"), path.string(), path.parent_path(), {},
                    memory_budget_bytes);
}

void overrideAccuracy(IntegratorOptions& accuracy, std::optional<NormalModel> normals,
                      std::optional<IntegrationScheme> scheme, const std::string& source) {
  if (normals) {
    accuracy.normals = *normals;
    if (*normals == NormalModel::Flat && !scheme) accuracy.scheme = IntegrationScheme::Paper;
  }
  if (scheme) accuracy.scheme = *scheme;
  if (accuracy.normals == NormalModel::Flat && accuracy.scheme != IntegrationScheme::Paper) {
    throw InputError(source +
                     ": flat normals (--normals flat or accuracy.normals) are the paper scheme's "
                     "only; pass --scheme paper");
  }
}

}  // namespace glint
