#include "pipeline/hazard.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "pipeline/progress.h"

namespace glint {
namespace {

// t_min of ANSI Z136.1-2014 (IEC 60825-1:2014: T_i): the break point of the single-pulse rows
// of Table 5a, below which the retina integrates a pulse's energy as if it were one instant.
double tMinS(double wavelength_nm) { return wavelength_nm < 1050.0 ? 5e-6 : 13e-6; }

// The retinal hazard region, where rule 3 and the grouping of close pulses apply.
bool retinal(double wavelength_nm) { return wavelength_nm < 1400.0; }

}  // namespace

double defaultExposureS(double wavelength_nm) { return wavelength_nm <= 700.0 ? 0.25 : 10.0; }

PulseTrainMpe pulseTrainMpe(double wavelength_nm, const PulseSpec& pulse, double exposure_s) {
  const double f = *pulse.repetition_rate_hz;
  PulseTrainMpe r;
  double duration_s = pulse.duration_s;
  double rate_hz = f;
  if (retinal(wavelength_nm) && 1.0 / f < tMinS(wavelength_nm)) {
    r.grouped = true;
    duration_s = tMinS(wavelength_nm);
    rate_hz = 1.0 / duration_s;
  }
  r.pulses = rate_hz * exposure_s;
  const Mpe single = ocularMpe(wavelength_nm, duration_s);
  const Mpe whole = ocularMpe(wavelength_nm, exposure_s);
  r.single_pulse_j_m2 = single.radiant_exposure_j_m2;
  r.average_j_m2 = whole.radiant_exposure_j_m2 / r.pulses;
  double limit = r.single_pulse_j_m2;
  r.rule = 1;
  if (r.average_j_m2 < limit) {
    limit = r.average_j_m2;
    r.rule = 2;
  }
  // Rule 3 guards against the additive heating of many pulses: a thermal limit only.
  if (retinal(wavelength_nm) && single.limit == MpeLimit::Thermal) {
    r.c_p = std::pow(r.pulses, -0.25);
    r.reduced_j_m2 = r.single_pulse_j_m2 * r.c_p;
    if (r.reduced_j_m2 < limit) {
      limit = r.reduced_j_m2;
      r.rule = 3;
    }
  }
  // A group of f / rate pulses shares the group's limit.
  r.per_pulse_j_m2 = limit * rate_hz / f;
  return r;
}

double extinctionFromVisibility(double visibility_m, double wavelength_nm, VisibilityModel model) {
  const double v_km = visibility_m / 1000.0;
  double q;
  if (v_km > 50.0) {
    q = 1.6;
  } else if (v_km > 6.0) {
    q = 1.3;
  } else if (model == VisibilityModel::Kruse) {
    q = 0.585 * std::cbrt(v_km);
  } else if (v_km > 1.0) {
    q = 0.16 * v_km + 0.34;
  } else if (v_km > 0.5) {
    q = v_km - 0.5;
  } else {
    q = 0.0;
  }
  // 3.912 = ln(1/0.02): visibility is where a black object's contrast falls to 2 % at 550 nm.
  const double per_km = 3.912 / v_km * std::pow(wavelength_nm / 550.0, -q);
  return per_km / 1000.0;
}

double opticalGain(double aperture_m, double magnification, double transmission,
                   double wavelength_nm) {
  const double eye_aperture_m = retinal(wavelength_nm) ? 7e-3 : 1e-3;
  const double collected = std::min(magnification, aperture_m / eye_aperture_m);
  return transmission * collected * collected;
}

void completeHazard(HazardSpec& h, double wavelength_nm) {
  h.train.reset();
  if (!h.pulse) {
    h.mpe = ocularMpe(wavelength_nm, h.exposure_s);
    h.mpe_w_m2 = h.mpe.irradiance_w_m2;
    h.pulse_exposure_s = 0.0;
    return;
  }
  const PulseSpec& p = *h.pulse;
  h.mpe = ocularMpe(wavelength_nm, p.duration_s);
  if (!p.repetition_rate_hz) {
    h.exposure_s = p.duration_s;
    h.mpe_w_m2 = h.mpe.irradiance_w_m2;
    h.pulse_exposure_s = p.duration_s;
    return;
  }
  h.train = pulseTrainMpe(wavelength_nm, p, h.exposure_s);
  h.mpe_w_m2 = h.train->per_pulse_j_m2 * *p.repetition_rate_hz;
  h.pulse_exposure_s = 1.0 / *p.repetition_rate_hz;
}

std::string hazardCitation(const HazardSpec& h) {
  std::string s = mpeCitation(h.mpe);
  if (h.train) {
    s += "; repetitive pulses, ANSI Z136.1-2014 8.2.3 rule " + std::to_string(h.train->rule);
    if (h.train->rule == 3) s += " (C_P = n^-0.25)";
    if (h.train->grouped) s += ", pulses within t_min counted as one";
  } else if (h.pulse) {
    s += "; a single pulse";
  }
  return s;
}

std::string hazardLine(const HazardSpec& h) {
  std::string s = "MPE " + formatNumber("%.4g", h.mpe_w_m2) + " W/m² for " +
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

nlohmann::json hazardLimitsJson(const HazardSpec& h) {
  nlohmann::json j = {{"exposure_s", h.exposure_s},
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
        pulse["c_p"] = t.c_p;
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
  return j;
}

HazardZone hazardZone(const ObserverField& field, const HazardSpec& h,
                      const Vec3& target_centre_m) {
  const FieldStats& s = field.stats();
  HazardZone z;
  z.peak_ratio = h.ratio(s.peak_w_m2);
  z.aided_peak_ratio = h.aidedRatio(s.peak_w_m2);
  z.peak_pulse_j_m2 = h.pulseRadiantExposureJ_m2(s.peak_w_m2);
  z.above_mpe = field.exceedance(h.mpe_w_m2, target_centre_m);
  if (h.aid) z.aided_above_mpe = field.exceedance(h.aidedMpeW_m2(), target_centre_m);
  z.target_centre_m = target_centre_m;
  z.unconverged_ratio_upper =
      std::max(h.ratio(s.unconverged_max_upper_w_m2), h.aidedRatio(s.unconverged_max_upper_w_m2));
  z.narrow_glint_ratio_bound =
      std::max(h.ratio(s.unresolved_max_bound_w_m2), h.aidedRatio(s.unresolved_max_bound_w_m2));
  z.narrow_glint_may_be_hazardous = s.unresolved_points > 0;
  return z;
}

FarHazard farHazard(const FarField& field, const HazardSpec& h) {
  const double mu = h.atmosphere.extinction_per_m;
  FarHazard f{farReach(field, h.mpe_w_m2, mu), std::nullopt};
  if (h.aid) f.aided = farReach(field, h.aidedMpeW_m2(), mu);
  return f;
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

nlohmann::json farHazardJson(const FarHazard& hazard) {
  nlohmann::json j = reachJson(hazard.unaided, "");
  if (hazard.aided) j.update(reachJson(*hazard.aided, "aided_"));
  return j;
}

namespace {
nlohmann::json zoneJson(const ObserverField::Exceedance& r, const Vec3& target_centre_m) {
  nlohmann::json nhz = {
      {"points", r.points}, {"volume_m3", r.volume_m3}, {"reaches_box_edge", r.reaches_edge}};
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
  return j;
}

std::vector<ScaledArray> hazardArrays(const HazardSpec& h) {
  std::vector<ScaledArray> arrays = {{"hazard_ratio", "1 (irradiance / MPE)", 1.0 / h.mpe_w_m2}};
  if (h.aid) {
    arrays.push_back({"aided_hazard_ratio", "1 (irradiance x optical aid gain / MPE)",
                      h.aid->gain / h.mpe_w_m2});
  }
  return arrays;
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
  const std::size_t count = static_cast<std::size_t>(n[0]) * static_cast<std::size_t>(n[1]);
  for (auto* channel : {&m.irradiance_w_m2, &m.hazard_ratio, &m.level, &m.status})
    channel->reserve(count);
  if (h.aid) m.aided_hazard_ratio.reserve(count);
  for (int j = 0; j < n[1]; ++j)
    for (int i = 0; i < n[0]; ++i) {
      const double e = field.irradiance(i, j, 0);
      m.irradiance_w_m2.push_back(static_cast<float>(e));
      m.hazard_ratio.push_back(static_cast<float>(h.ratio(e)));
      if (h.aid) m.aided_hazard_ratio.push_back(static_cast<float>(h.aidedRatio(e)));
      m.level.push_back(static_cast<float>(field.level(i, j, 0)));
      m.status.push_back(static_cast<float>(static_cast<int>(field.status(i, j, 0))));
    }
  return m;
}

double hazardousArea(const ObserverField& field, const ObserverField::Exceedance& zone) {
  return static_cast<double>(zone.points) * field.spec().voxel_m * field.spec().voxel_m;
}

}  // namespace glint
