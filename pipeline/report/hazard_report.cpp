#include "pipeline/report/hazard_report.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "pipeline/base/number_format.h"
#include "pipeline/base/output_names.h"

namespace glint {

namespace {
// Appended piece by piece: GCC 12 warns (-Wrestrict, falsely) on a literal + string chain here.
std::string pointLine(const Vec3& p) {
  std::string s = "(";
  s += formatNumber("%.6g", p.x);
  s += ", ";
  s += formatNumber("%.6g", p.y);
  s += ", ";
  s += formatNumber("%.6g", p.z);
  s += ")";
  return s;
}
}  // namespace

std::string laserLine(const Beam& laser, const HazardSpec& h) {
  std::string s;
  if (h.pulse) {
    const PulseSpec& p = *h.pulse;
    s += formatNumber("%.4g", p.energy_j);
    s += " J pulses of ";
    s += formatNumber("%.3g", p.duration_s);
    s += " s";
    if (p.repetition_rate_hz) {
      s += " at ";
      s += formatNumber("%.4g", *p.repetition_rate_hz);
      s += " Hz (";
      s += formatNumber("%.6g", laser.power_w);
      s += " W mean)";
    } else {
      s += " (a single pulse)";
    }
  } else {
    s += formatNumber("%.6g", laser.power_w);
    s += " W";
  }
  s += " at ";
  s += formatNumber("%.10g", h.wavelength_nm);
  s += " nm; ";
  s += laser.profile == BeamProfile::Gaussian ? "Gaussian beam, w " : "flat-top beam, radius ";
  s += formatNumber("%.4g", laser.radius_m);
  s += " m, ";
  if (laser.divergence_rad > 0.0) {
    s += "divergence ";
    s += formatNumber("%.4g", 1e3 * laser.divergence_rad);
    s += " mrad";
  } else {
    s += "collimated";
  }
  s += "; from ";
  s += pointLine(laser.origin_m);
  s += " m toward ";
  s += pointLine(laser.direction);
  return s;
}

nlohmann::json laserJson(const Beam& laser, const HazardSpec& h) {
  nlohmann::json beam = {
      {"profile", laser.profile == BeamProfile::Gaussian ? "gaussian" : "flat_top"},
      {laser.profile == BeamProfile::Gaussian ? "w_m" : "radius_m", laser.radius_m},
      {"divergence_rad", laser.divergence_rad}};
  nlohmann::json j = {{"position_m", {laser.origin_m.x, laser.origin_m.y, laser.origin_m.z}},
                      {"direction", {laser.direction.x, laser.direction.y, laser.direction.z}},
                      {"power_w", laser.power_w},
                      {"wavelength_nm", h.wavelength_nm},
                      {"exposure_s", h.exposure_s},
                      {"beam", beam}};
  if (h.pulse) {
    nlohmann::json pulse = {{"energy_j", h.pulse->energy_j}, {"duration_s", h.pulse->duration_s}};
    if (h.pulse->repetition_rate_hz) pulse["repetition_rate_hz"] = *h.pulse->repetition_rate_hz;
    j["pulse"] = pulse;
  }
  return j;
}

std::string hazardLine(const HazardSpec& h) {
  std::string s = std::string(clauses(h.standard).name) + ", " + toString(h.tissue) + ": MPE " +
                  formatNumber("%.4g", h.mpe_w_m2) + " W/m² for " +
                  formatNumber("%g", h.exposure_s) + " s (" +
                  (h.exposure_default ? "default, " : "") + toString(h.mpe.limit) + ")";
  if (h.train) {
    s += ", " + formatNumber("%.4g", h.mpe_w_m2 * h.pulse_exposure_s) + " J/m² a pulse (rule " +
         std::to_string(h.train->rule) + ", " + formatNumber("%.4g", h.train->pulses) +
         (h.train->grouped ? " groups of pulses)" : " pulses)");
  } else if (h.pulse) {
    s += ", " + formatNumber("%.4g", h.mpe_w_m2 * h.pulse_exposure_s) + " J/m² (single pulse)";
  }
  if (h.atmosphere.extinction_per_m > 0.0) {
    s += "; air " + formatNumber("%.3g", h.atmosphere.extinction_per_m) + " /m";
  }
  if (h.aid) s += "; optical aid gain " + formatNumber("%.3g", h.aid->gain);
  return s;
}

std::string levelLine(const ExposureLevel& l) {
  std::string s = l.label + ": " + formatNumber("%.4g", l.thresholdW_m2()) + " W/m²";
  if (l.visually_corrected) {
    s += " (" + formatNumber("%.4g", l.level_w_m2) + " W/m² effective, visual correction " +
         formatNumber("%.3g", l.visual_correction) + ")";
  }
  if (l.pulse_factor != 1.0) {
    s += "; pulsed: reached where the brightest " + formatNumber("%g", kFlightZoneAveragingS) +
         " s holds " + formatNumber("%.4g", l.level_w_m2 * kFlightZoneAveragingS) + " J/m²" +
         (l.visually_corrected ? " effective" : "");
  }
  return s;
}

nlohmann::json levelJson(const ExposureLevel& l) {
  return {{"level_w_m2", l.level_w_m2},
          {"visually_corrected", l.visually_corrected},
          {"visual_correction", l.visual_correction},
          {"averaged_over_s",
           l.averaged_over_window ? nlohmann::json(kFlightZoneAveragingS) : nlohmann::json()},
          {"pulse_factor", l.pulse_factor},
          {"threshold_w_m2", l.thresholdW_m2()},
          {"source", l.source}};
}

nlohmann::json hazardLimitsJson(const HazardSpec& h) {
  const StandardClauses& c = clauses(h.standard);
  nlohmann::json j = {{"standard", c.name},
                      {"standard_edition", c.edition_year},
                      {"tissue", toString(h.tissue)},
                      {"mpe_table", mpeTable(h.standard, h.tissue)},
                      {"exposure_s", h.exposure_s},
                      {"exposure_default", h.exposure_default},
                      {"mpe_w_m2", h.mpe_w_m2},
                      {"mpe_j_m2", h.mpe_w_m2 * h.exposure_s},
                      {"mpe_limit", toString(h.mpe.limit)},
                      {"mpe_rule", hazardCitation(h)}};
  if (h.pulse) {
    const PulseSpec& p = *h.pulse;
    nlohmann::json pulse = {{"energy_j", p.energy_j},
                            {"duration_s", p.duration_s},
                            {"mpe_j_m2_per_pulse", h.mpe_w_m2 * h.pulse_exposure_s}};
    if (p.repetition_rate_hz) pulse["repetition_rate_hz"] = *p.repetition_rate_hz;
    if (h.train) {
      const PulseTrainMpe& t = *h.train;
      pulse["pulses_in_exposure"] = t.pulses;
      pulse["grouped_within_t_min"] = t.grouped;
      pulse["rule"] = t.rule;
      pulse["rule_1_single_pulse_j_m2"] = t.single_pulse_j_m2;
      pulse["rule_2_average_j_m2"] = t.average_j_m2;
      if (t.reduced_j_m2 > 0.0) {
        pulse["rule_3_reduced_j_m2"] = t.reduced_j_m2;
        pulse["rule_3_reduction"] = t.c_p;
        pulse["rule_3_pulses"] = t.reduction_pulses;
        pulse[clauses(h.standard).rule_three_key] = t.c_p;
      }
    }
    j["pulse"] = pulse;
  }
  const AtmosphereSpec& a = h.atmosphere;
  nlohmann::json air = {{"extinction_per_m", a.extinction_per_m}};
  if (a.visibility_m) {
    air["visibility_m"] = *a.visibility_m;
    air["visibility_model"] = a.model == VisibilityModel::Kim ? "kim" : "kruse";
  }
  j["atmosphere"] = air;
  if (h.aid) {
    nlohmann::json aid = {{"gain", h.aid->gain}, {"aided_mpe_w_m2", h.aidedMpeW_m2()}};
    if (h.aid->aperture_m) {
      aid["aperture_m"] = *h.aid->aperture_m;
      aid["magnification"] = *h.aid->magnification;
      aid["transmission"] = *h.aid->transmission;
    }
    j["optical_aid"] = aid;
  }
  if (!h.levels.empty()) {
    nlohmann::json levels = nlohmann::json::object();
    for (const ExposureLevel& l : h.levels) levels[l.name] = levelJson(l);
    j["levels"] = levels;
    j["levels_rule"] =
        "each level is reached where irradiance x visual_correction >= level_w_m2 x "
        "pulse_factor, i.e. irradiance >= threshold_w_m2 (the naked eye's mean irradiance over "
        "the exposure); a level averaged over averaged_over_s has a pulse_factor other than 1 "
        "for a pulsed laser: the mean irradiance at which the brightest such window reaches it";
  }
  return j;
}

namespace {
nlohmann::json reachJson(const FarReach& r, const std::string& prefix) {
  const Vec3& d = r.direction;
  return {{prefix + "max_nohd_m", r.nohd_m},
          {prefix + "max_nohd_direction", {d.x, d.y, d.z}},
          {prefix + "max_nohd_azimuth_deg", std::atan2(d.y, d.x) * 180.0 / kPi},
          {prefix + "max_nohd_elevation_deg", std::asin(std::clamp(d.z, -1.0, 1.0)) * 180.0 / kPi},
          {prefix + "far_radius_toward_max_nohd_m", r.far_radius_m},
          {prefix + "hazard_beyond_far_radius", r.nohd_m > 0.0}};
}
}  // namespace

nlohmann::json farHazardJson(const FarHazard& hazard, const HazardSpec& h) {
  nlohmann::json j = reachJson(hazard.unaided, "");
  if (hazard.aided) j.update(reachJson(*hazard.aided, "aided_"));
  if (!hazard.levels.empty()) {
    nlohmann::json levels = nlohmann::json::object();
    for (std::size_t k = 0; k < hazard.levels.size(); ++k) {
      // max_nohd_m is the level's distance: the same rule with the level for the MPE.
      levels[h.levels.at(k).name] = reachJson(hazard.levels[k], "");
    }
    j["levels"] = levels;
  }
  return j;
}

namespace {
nlohmann::json zoneJson(const ObserverField::Exceedance& r, const Vec3& target_centre_m) {
  nlohmann::json nhz = {{"points", r.points},
                        {"unconverged_points_counted", r.by_error_points},
                        {"volume_m3", r.volume_m3},
                        {"reaches_box_edge", r.reaches_edge}};
  if (r.points > 0) {
    nhz["box"] = {{"min_m", {r.min_m.x, r.min_m.y, r.min_m.z}},
                  {"max_m", {r.max_m.x, r.max_m.y, r.max_m.z}}};
    nhz["farthest_from_target_m"] = r.farthest_m;
    nhz["farthest_at_m"] = {r.farthest_at_m.x, r.farthest_at_m.y, r.farthest_at_m.z};
    nhz["target_centre_m"] = {target_centre_m.x, target_centre_m.y, target_centre_m.z};
  }
  return nhz;
}
}  // namespace

nlohmann::json hazardJson(const HazardSpec& h, const HazardZone* zone) {
  nlohmann::json j = hazardLimitsJson(h);
  if (zone == nullptr) return j;
  const HazardZone& z = *zone;
  j["peak_hazard_ratio"] = z.peak_ratio;
  if (h.aid) j["aided_peak_hazard_ratio"] = z.aided_peak_ratio;
  if (h.pulse) j["peak_radiant_exposure_j_m2_per_pulse"] = z.peak_pulse_j_m2;
  j["unconverged_may_be_hazardous"] = z.unconvergedMayBeHazardous();
  j["narrow_glint_may_be_hazardous"] = z.narrow_glint_may_be_hazardous;
  j["nominal_hazard_zone"] = zoneJson(z.above_mpe, z.target_centre_m);
  if (z.aided_above_mpe) {
    j["aided_nominal_hazard_zone"] = zoneJson(*z.aided_above_mpe, z.target_centre_m);
  }
  if (!z.levels.empty()) {
    for (std::size_t k = 0; k < z.levels.size(); ++k) {
      const HazardZone::Level& l = z.levels[k];
      nlohmann::json& level = j["levels"][h.levels.at(k).name];
      level["peak_ratio"] = l.peak_ratio;
      level["zone"] = zoneJson(l.above, z.target_centre_m);
      level["unconverged_may_reach"] = l.unconverged_may_reach;
      level["narrow_glint_may_reach"] = l.narrow_glint_may_reach;
    }
  }
  return j;
}

std::vector<ScaledArray> hazardArrays(const HazardSpec& h) {
  std::vector<ScaledArray> arrays = {{"hazard_ratio", "1 (irradiance / MPE)", 1.0 / h.mpe_w_m2}};
  if (h.aid) {
    arrays.push_back({"aided_hazard_ratio", "1 (irradiance x optical aid gain / MPE)",
                      h.aid->gain / h.mpe_w_m2});
  }
  for (const ExposureLevel& l : h.levels) {
    arrays.push_back({output_names::levelRatio(l.name),
                      "1 (irradiance" +
                          std::string(l.visually_corrected ? " x visual correction" : "") + " / " +
                          l.name + " level)",
                      1.0 / l.thresholdW_m2()});
  }
  return arrays;
}

std::vector<float> planeIrradiance(const ObserverField& field) {
  const auto n = field.spec().nodes();
  std::vector<float> e;
  e.reserve(static_cast<std::size_t>(n[0]) * static_cast<std::size_t>(n[1]));
  for (int j = 0; j < n[1]; ++j)
    for (int i = 0; i < n[0]; ++i) e.push_back(static_cast<float>(field.irradiance(i, j, 0)));
  return e;
}

PlaneMap planeMap(const ObserverField& field, const HazardSpec& h) {
  const FieldSpec& spec = field.spec();
  const auto n = spec.nodes();
  PlaneMap m;
  m.width = n[0];
  m.height = n[1];
  m.origin_m = spec.min_m;
  m.u_axis = spec.axes[0];
  m.v_axis = spec.axes[1];
  m.pixel_m = spec.voxel_m;
  m.irradiance_w_m2 = planeIrradiance(field);
  m.irradiance_upper_w_m2 = field.upperLattice();
  const std::size_t count = m.irradiance_w_m2.size();
  for (auto* channel : {&m.hazard_ratio, &m.level, &m.status}) channel->reserve(count);
  if (h.aid) m.aided_hazard_ratio.reserve(count);
  for (const ExposureLevel& l : h.levels) {
    m.level_ratios.push_back({output_names::levelRatio(l.name), {}});
    m.level_ratios.back().second.reserve(count);
  }
  for (int j = 0; j < n[1]; ++j)
    for (int i = 0; i < n[0]; ++i) {
      // The stored float is the field's own (irradiance() widens it), so the ratios are as
      // before.
      const double e = static_cast<double>(
          m.irradiance_w_m2[static_cast<std::size_t>(j) * static_cast<std::size_t>(n[0]) +
                            static_cast<std::size_t>(i)]);
      m.hazard_ratio.push_back(static_cast<float>(h.ratio(e)));
      if (h.aid) m.aided_hazard_ratio.push_back(static_cast<float>(h.aidedRatio(e)));
      for (std::size_t k = 0; k < h.levels.size(); ++k)
        m.level_ratios[k].second.push_back(static_cast<float>(h.levels[k].ratio(e)));
      m.level.push_back(static_cast<float>(field.level(i, j, 0)));
      m.status.push_back(static_cast<float>(static_cast<int>(field.status(i, j, 0))));
      if (spec.surface) m.observer_z_m.push_back(static_cast<float>(spec.position(i, j, 0).z));
    }
  return m;
}

}  // namespace glint
