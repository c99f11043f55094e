#include "hazard/hazard.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace glint {
namespace {

// The retinal hazard region, where rule 3 and the grouping of close pulses apply.
bool retinal(double wavelength_nm) { return wavelength_nm < 1400.0; }

std::string formatCount(double n) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", n);
  return text;
}

}  // namespace

double defaultExposureS(double wavelength_nm, Tissue tissue) {
  if (tissue == Tissue::Skin) return 10.0;
  return wavelength_nm <= 700.0 ? 0.25 : 10.0;
}

double pulseGroupingS(double wavelength_nm, Tissue tissue) {
  if (tissue != Tissue::Eye || !retinal(wavelength_nm)) return 0.0;
  return wavelength_nm < 1050.0 ? 5e-6 : 13e-6;
}

bool ruleThreeApplies(double wavelength_nm, Tissue tissue, MpeLimit limit) {
  return tissue == Tissue::Eye && retinal(wavelength_nm) && limit == MpeLimit::Thermal;
}

double ruleThreeCountingS(SafetyStandard standard, double exposure_s) {
  // IEC 60825-1:2014 A.3 (4.3 f) 3)) for α ≤ α_min: N counts the pulses within T2 (10 s for a
  // point source) or the exposure if shorter; ANSI Z136.1-2014 8.2.3.3 the n of the exposure.
  return std::min(exposure_s, clauses(standard).rule_three_window_s);
}

double ruleThreeReduction(SafetyStandard standard, double wavelength_nm, double duration_s,
                          double counted) {
  const StandardClauses& c = clauses(standard);
  if (c.rule_three_only_within_t_i && duration_s > pulseGroupingS(wavelength_nm) * (1.0 + 1e-12))
    return 1.0;
  if (counted <= c.rule_three_from_pulses) return 1.0;
  // Never above 1: IEC's 5 N^-0.25 is above 1 from 601 to 624 pulses, where taken literally it
  // would relax the single-pulse limit; rule 3 only ever lowers it.
  return std::min(1.0, std::max(c.rule_three_scale * std::pow(counted, -0.25), c.rule_three_floor));
}

PulseTrainMpe pulseTrainMpe(double wavelength_nm, const PulseSpec& pulse, double exposure_s,
                            SafetyStandard standard, Tissue tissue) {
  const double f = *pulse.repetition_rate_hz;
  const double grouping_s = pulseGroupingS(wavelength_nm, tissue);
  PulseTrainMpe r;
  double duration_s = pulse.duration_s;
  double rate_hz = f;
  if (1.0 / f < grouping_s) {
    r.grouped = true;
    duration_s = grouping_s;
    rate_hz = 1.0 / duration_s;
  }
  r.pulses = rate_hz * exposure_s;
  const Mpe single = tableMpe(wavelength_nm, duration_s, standard, tissue);
  const Mpe whole = tableMpe(wavelength_nm, exposure_s, standard, tissue);
  r.single_pulse_j_m2 = single.radiant_exposure_j_m2;
  r.average_j_m2 = whole.radiant_exposure_j_m2 / r.pulses;
  double limit = r.single_pulse_j_m2;
  r.rule = 1;
  if (r.average_j_m2 < limit) {
    limit = r.average_j_m2;
    r.rule = 2;
  }
  // Rule 3 guards against the additive heating of the retina by many pulses: the eye's
  // thermal limit only.
  if (ruleThreeApplies(wavelength_nm, tissue, single.limit)) {
    r.reduction_pulses = rate_hz * ruleThreeCountingS(standard, exposure_s);
    r.c_p = ruleThreeReduction(standard, wavelength_nm, duration_s, r.reduction_pulses);
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

double flightZonePulseFactor(const PulseSpec& pulse) {
  const double window_s = kFlightZoneAveragingS;
  if (!pulse.repetition_rate_hz) return window_s / std::min(pulse.duration_s, window_s);
  // A window of T_w, its ends included, touches at most ⌊f T_w⌋ + 1 pulses of the train: the
  // light it holds is at most that many pulses' exposure E / f.
  const double per_window = *pulse.repetition_rate_hz * window_s;
  return per_window / (std::floor(per_window) + 1.0);
}

void completeHazard(HazardSpec& h) {
  const double wavelength_nm = h.wavelength_nm;
  for (ExposureLevel& l : h.levels) {
    if (l.visually_corrected &&
        !(wavelength_nm >= kVisibleMinNm && wavelength_nm <= kVisibleMaxNm)) {
      throw std::out_of_range("a visually corrected level applies from 400 nm to 700 nm only");
    }
    l.visual_correction = l.visually_corrected ? photopicEfficiency(wavelength_nm) : 1.0;
    l.pulse_factor = l.averaged_over_window && h.pulse ? flightZonePulseFactor(*h.pulse) : 1.0;
  }
  h.train.reset();
  if (!h.pulse) {
    h.mpe = tableMpe(wavelength_nm, h.exposure_s, h.standard, h.tissue);
    h.mpe_w_m2 = h.mpe.irradiance_w_m2;
    h.pulse_exposure_s = 0.0;
    return;
  }
  const PulseSpec& p = *h.pulse;
  h.mpe = tableMpe(wavelength_nm, p.duration_s, h.standard, h.tissue);
  if (!p.repetition_rate_hz) {
    h.exposure_s = p.duration_s;
    h.mpe_w_m2 = h.mpe.irradiance_w_m2;
    h.pulse_exposure_s = p.duration_s;
    return;
  }
  h.train = pulseTrainMpe(wavelength_nm, p, h.exposure_s, h.standard, h.tissue);
  h.mpe_w_m2 = h.train->per_pulse_j_m2 * *p.repetition_rate_hz;
  h.pulse_exposure_s = 1.0 / *p.repetition_rate_hz;
}

std::string hazardCitation(const HazardSpec& h) {
  std::string s = mpeCitation(h.mpe);
  if (h.train) {
    const StandardClauses& c = clauses(h.standard);
    s += std::string("; repetitive pulses, ") + c.name + " " + c.repeated_pulses + " rule " +
         std::to_string(h.train->rule);
    if (h.train->rule == 3) {
      s += std::string(" (") + c.rule_three_formula +
           (c.rule_three_cites_count
                ? ", N = " + formatCount(h.train->reduction_pulses) + " pulses within T2"
                : std::string()) +
           ")";
    }
    if (h.train->grouped) s += ", pulses within t_min counted as one";
  } else if (h.pulse) {
    s += "; a single pulse";
  }
  return s;
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
  // A level below the MPE lowers the fields' threshold, and with it where points are marked
  // unresolved: only a bound that reaches the MPE makes one hazardous.
  z.narrow_glint_may_be_hazardous = s.unresolved_points > 0 && !(z.narrow_glint_ratio_bound < 1.0);
  for (const ExposureLevel& l : h.levels) {
    HazardZone::Level level;
    level.peak_ratio = l.ratio(s.peak_w_m2);
    level.above = field.exceedance(l.thresholdW_m2(), target_centre_m);
    level.unconverged_may_reach = !(l.ratio(s.unconverged_max_upper_w_m2) < 1.0);
    level.narrow_glint_may_reach =
        s.unresolved_points > 0 && !(l.ratio(s.unresolved_max_bound_w_m2) < 1.0);
    z.levels.push_back(level);
  }
  return z;
}

FarHazard farHazard(const FarField& field, const HazardSpec& h) {
  // One pass for every threshold, in thresholdsW_m2()'s order: the MPE, the aided MPE, the levels.
  const std::vector<FarReach> all =
      farReaches(field, h.thresholdsW_m2(), h.atmosphere.extinction_per_m);
  FarHazard f{all.at(0), std::nullopt, {}};
  std::size_t next = 1;
  if (h.aid) f.aided = all.at(next++);
  for (std::size_t k = 0; k < h.levels.size(); ++k) f.levels.push_back(all.at(next++));
  return f;
}

double hazardousArea(const ObserverField& field, const ObserverField::Exceedance& zone) {
  return static_cast<double>(zone.points) * field.spec().voxel_m * field.spec().voxel_m;
}

}  // namespace glint
