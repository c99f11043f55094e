#pragma once
/// @file
/// @brief The hazard a scene is judged for, in one place: the exposure and its MPE (continuous,
/// single pulse or pulse train), the air's extinction, an optical aid, and the ratios and zones
/// the outputs report (docs/hazard.md). Physics only: what the outputs make of it (JSON, maps,
/// volume arrays) is built in pipeline/report/hazard_report.h.
///
/// Everything glint integrates is the mean irradiance over the exposure, E (W/m²), from the
/// laser's mean power. The limits reduce to one number it is compared with, `mpe_w_m2`: the MPE
/// expressed as mean irradiance. For a pulse train that is the MPE per pulse times the
/// repetition rate (a pulse's radiant exposure is E / f); for a single pulse, whose exposure is
/// its duration τ, the MPE for τ divided by τ.

#include <algorithm>
#include <optional>
#include <string>
#include <vector>

#include "facets/vec3.h"
#include "hazard/levels.h"
#include "hazard/mpe.h"
#include "hazard/standard.h"
#include "observers/far_field.h"
#include "observers/field.h"

namespace glint {

/// @brief A pulsed laser's pulses (scene key `laser.pulse`).
struct PulseSpec {
  double energy_j = 0.0;    ///< per pulse
  double duration_s = 0.0;  ///< each pulse's duration (full width at half maximum)
  /// Pulses per second; none: a single pulse, whose exposure is its duration.
  std::optional<double> repetition_rate_hz;
};

/// @brief The MPE of a train of pulses, per pulse, by the three rules of ANSI Z136.1-2014
/// 8.2.3 or IEC 60825-1:2014 A.3. They agree on rules 1 and 2 and on counting pulses closer than
/// t_min (IEC: T_i) as one; they differ in rule 3's reduction (docs/hazard.md).
struct PulseTrainMpe {
  double pulses = 0.0;  ///< n = f T over the exposure T (of groups, where grouped below)
  /// 400–1400 nm: pulses closer than t_min (5 µs below 1050 nm, 13 µs above) act as one pulse
  /// of duration t_min carrying their summed energy (ANSI Z136.1-2014 8.2.3.2).
  bool grouped = false;
  double single_pulse_j_m2 = 0.0;  ///< rule 1: the MPE of one pulse alone
  double average_j_m2 = 0.0;       ///< rule 2: the MPE for T shared among the n pulses
  /// rule 3 (the eye's retinal thermal limits, 400–1400 nm): rule 1 × the reduction c_p;
  /// 0 where rule 3 does not apply.
  double reduced_j_m2 = 0.0;
  /// Rule 3's reduction: ANSI's C_P = n^-0.25; IEC's C5, for a point source 1 up to 600 pulses
  /// within T2 = 10 s and 5 N^-0.25 (at least 0.4) beyond, 1 for pulses longer than T_i.
  double c_p = 1.0;
  double reduction_pulses = 0.0;  ///< the pulses rule 3 counts: n by ANSI, N within T2 by IEC
  double per_pulse_j_m2 = 0.0;    ///< the most restrictive of the three, per (ungrouped) pulse
  int rule = 1;                   ///< which of the three set it
};

/// @brief t_min of ANSI Z136.1-2014 (IEC 60825-1:2014: T_i) at @p wavelength_nm for @p tissue:
/// 5 µs below 1050 nm, 13 µs to 1400 nm, for the eye's retina only (0 beyond 1400 nm and for
/// the skin). Pulses closer than this act as one pulse of this duration carrying their summed
/// energy, and IEC's C5 reduces only pulses no longer than it.
double pulseGroupingS(double wavelength_nm, Tissue tissue = Tissue::Eye);

/// @brief Whether rule 3 applies to a pulse whose single-pulse MPE is limited by @p limit: the
/// eye's retinal thermal limits (400–1400 nm), which guard against the additive heating of the
/// retina by many pulses.
bool ruleThreeApplies(double wavelength_nm, Tissue tissue, MpeLimit limit);

/// @brief The span over which rule 3 counts pulses for an exposure of @p exposure_s: the whole
/// exposure under ANSI (its n), T2 = 10 s (a point source) or the exposure if shorter under IEC
/// (its N).
double ruleThreeCountingS(SafetyStandard standard, double exposure_s);

/// @brief Rule 3's reduction of the single-pulse limit of pulses of @p duration_s when
/// @p counted pulses (ruleThreeCountingS()) are counted: ANSI's C_P = n^-0.25; IEC's C5, for
/// pulses no longer than T_i 1 up to 600 pulses and 5 N^-0.25 (at least 0.4) beyond, and 1 for
/// longer pulses; never above 1 (IEC's formula is from 601 to 624 pulses). The caller checks
/// ruleThreeApplies().
double ruleThreeReduction(SafetyStandard standard, double wavelength_nm, double duration_s,
                          double counted);

/// @brief The MPE per pulse of @p pulse repeated over @p exposure_s at @p wavelength_nm, for
/// @p tissue under @p standard.
/// @pre the pulse has a repetition rate, duration × rate ≤ 1 and rate × exposure ≥ 1; the MPE
/// table's ranges hold (tableMpe throws std::out_of_range otherwise).
PulseTrainMpe pulseTrainMpe(double wavelength_nm, const PulseSpec& pulse, double exposure_s,
                            SafetyStandard standard = SafetyStandard::AnsiZ136_1_2014,
                            Tissue tissue = Tissue::Eye);

/// @brief How meteorological visibility gives extinction (both: μ = 3.912/V (λ/550 nm)^-q).
enum class VisibilityModel {
  Kim,    ///< Kim, McArthur, Korevaar (SPIE 4214, 2001): q falls to 0 in fog below 0.5 km
  Kruse,  ///< Kruse et al. (1962): q = 0.585 V^(1/3) below 6 km
};

/// @brief The air between laser, target and observers (scene key `atmosphere`): Beer–Lambert
/// extinction along the laser's path to the target and along each reflected path.
struct AtmosphereSpec {
  double extinction_per_m = 0.0;       ///< μ; 0 is vacuum (the default)
  std::optional<double> visibility_m;  ///< where μ came from the visibility
  VisibilityModel model = VisibilityModel::Kim;
};

/// @brief The extinction coefficient (1/m) at @p wavelength_nm for a meteorological
/// visibility (2 % contrast at 550 nm) of @p visibility_m.
double extinctionFromVisibility(double visibility_m, double wavelength_nm, VisibilityModel model);

/// @brief Viewing through binoculars or a telescope (scene key `optical_aid`).
struct OpticalAidSpec {
  std::optional<double> aperture_m;     ///< objective diameter D
  std::optional<double> magnification;  ///< M
  std::optional<double> transmission;   ///< τ in (0, 1]
  /// What the aid multiplies the irradiance at the eye by: τ min(M, D / d)², d the eye's
  /// limiting aperture, or the file's `gain`.
  double gain = 1.0;
};

/// @brief τ min(M, D/d)²: an aid collects the beam over D and sends it through an exit pupil
/// D/M, so it gathers (D/d)² times what the eye's limiting aperture d does, but no more than M²
/// once the exit pupil is smaller than d (ANSI Z136.1-2014 8.3, IEC 60825-1:2014 A.2).
/// d = 7 mm over 400–1400 nm; beyond 1400 nm the smallest limiting aperture of ANSI Z136.1-2014
/// Table 8 (1 mm), which gives the largest gain.
double opticalGain(double aperture_m, double magnification, double transmission,
                   double wavelength_nm);

/// @brief The exposure the hazard is judged for, its limit, the air and the aid: what every
/// hazard ratio, zone and distance of the outputs is computed from.
struct HazardSpec {
  /// The standard whose limits apply (its tables and rules; cited in every output).
  SafetyStandard standard = SafetyStandard::AnsiZ136_1_2014;
  Tissue tissue = Tissue::Eye;  ///< what the limits protect: the eye, or the skin
  double wavelength_nm = 0.0;   ///< the laser's (`laser.wavelength_nm`): the limits' row
  /// `laser.exposure_s`, by default 0.25 s (the aversion response) for 400–700 nm and 10 s
  /// beyond 700 nm, where nothing makes the eye turn away, and 10 s for the skin (whose
  /// limits are a constant irradiance from there on); a single pulse's duration.
  double exposure_s = 0.25;
  /// The exposure is the default for the wavelength (defaultExposureS()): exposure_s was not
  /// in the file and the laser is not a single pulse (whose exposure is its duration).
  bool exposure_default = true;
  /// The table's MPE for the exposure (a continuous laser) or for one pulse (a pulsed laser).
  Mpe mpe;
  std::optional<PulseSpec> pulse;
  std::optional<PulseTrainMpe> train;  ///< a pulse train's MPE per pulse
  /// The MPE as mean irradiance over the exposure: what `irradiance_w_m2` is compared with.
  double mpe_w_m2 = 0.0;
  /// Seconds that turn mean irradiance into one pulse's radiant exposure (J/m²): 1/f for a
  /// train, τ for a single pulse, 0 for a continuous laser.
  double pulse_exposure_s = 0.0;
  AtmosphereSpec atmosphere;
  std::optional<OpticalAidSpec> aid;
  /// Levels judged beside the MPE, for the naked eye (`hazard.flight_zones`, `hazard.levels`).
  std::vector<ExposureLevel> levels;

  /// @brief E / MPE for unaided viewing.
  [[nodiscard]] double ratio(double irradiance_w_m2) const { return irradiance_w_m2 / mpe_w_m2; }
  /// @brief E × gain / MPE through the optical aid (the unaided ratio without one).
  [[nodiscard]] double aidedRatio(double irradiance_w_m2) const {
    return irradiance_w_m2 * aidGain() / mpe_w_m2;
  }
  [[nodiscard]] double aidGain() const { return aid ? aid->gain : 1.0; }
  /// @brief The irradiance at the naked eye that the aid lifts to the MPE: MPE / gain (the
  /// MPE without an aid).
  [[nodiscard]] double aidedMpeW_m2() const { return mpe_w_m2 / aidGain(); }
  /// @brief The lowest irradiance judged for any viewer the scene describes (aided where the aid
  /// gathers more than the eye) or any level: what defaults of floors are scaled from.
  [[nodiscard]] double lowestHazardousW_m2() const {
    double lowest = mpe_w_m2 / std::max(1.0, aidGain());
    for (const ExposureLevel& l : levels) lowest = std::min(lowest, l.thresholdW_m2());
    return lowest;
  }
  /// @brief Every irradiance threshold judged, in the outputs' order: the MPE, the aided MPE
  /// with an aid, then each level's (ExposureLevel::thresholdW_m2()).
  [[nodiscard]] std::vector<double> thresholdsW_m2() const {
    std::vector<double> t = {mpe_w_m2};
    if (aid) t.push_back(aidedMpeW_m2());
    for (const ExposureLevel& l : levels) t.push_back(l.thresholdW_m2());
    return t;
  }
  /// @brief Where the levels begin in thresholdsW_m2().
  [[nodiscard]] std::size_t firstLevelThreshold() const { return aid ? 2 : 1; }
  /// @brief The irradiance below which the fields need not resolve anything: their default
  /// floors. A thousandth of lowestHazardousW_m2(): hazard ratios down to 1e-3 are resolved,
  /// below what even an undeclared 50 mm binocular (about 50× the collected power of a 7 mm
  /// pupil) could lift to 1.
  [[nodiscard]] double negligibleW_m2() const { return 1e-3 * lowestHazardousW_m2(); }
  /// @brief The largest floor a scene may set (W/m²): a hundredth of lowestHazardousW_m2().
  /// What is below a floor counts as nothing (a block skipped, a piece dropped, an observer's
  /// error allowed), so a floor near a threshold could read a hazard as none; at this one an
  /// observer at the threshold may fall short of it by at most the fields' default tolerance.
  [[nodiscard]] double largestFloorW_m2() const { return 1e-2 * lowestHazardousW_m2(); }
  /// @brief One pulse's radiant exposure (J/m²) at mean irradiance @p irradiance_w_m2.
  [[nodiscard]] double pulseRadiantExposureJ_m2(double irradiance_w_m2) const {
    return irradiance_w_m2 * pulse_exposure_s;
  }
};

/// @brief The default exposure at @p wavelength_nm for @p tissue: for the eye 0.25 s (aversion
/// response) to 700 nm and 10 s beyond; for the skin 10 s.
double defaultExposureS(double wavelength_nm, Tissue tissue = Tissue::Eye);

/// @brief Fills @p h's limits from its wavelength, exposure, pulse and aid: the table's MPE, the
/// pulse train's, `mpe_w_m2` and `pulse_exposure_s`.
/// @throw std::out_of_range where the MPE table does not reach (ocularMpe).
void completeHazard(HazardSpec& h);

/// @brief For a level averaged over kFlightZoneAveragingS (a flight zone's), the mean irradiance
/// over the exposure at which @p pulse's brightest averaging window reaches the level, as a
/// multiple of it: a single pulse of τ ≤ T_w puts its whole exposure in one window, so
/// T_w / τ; a train at f holds at most ⌊f T_w⌋ + 1 pulses in a window, so f T_w / (⌊f T_w⌋ + 1)
/// (below 1: a slow train's single flash reaches the level first). docs/hazard.md derives both.
double flightZonePulseFactor(const PulseSpec& pulse);

/// @brief The lines of the standards the limit came from, as outputs record them.
std::string hazardCitation(const HazardSpec& h);

/// @brief The nominal hazard zone of an observer box or plane: where E ≥ MPE, and where an
/// optical aid lifts E × gain to the MPE (the aided zone).
struct HazardZone {
  double peak_ratio = 0.0;
  double aided_peak_ratio = 0.0;        ///< the unaided ratio where there is no aid
  double peak_pulse_j_m2 = 0.0;         ///< one pulse's radiant exposure at the peak (0: CW)
  ObserverField::Exceedance above_mpe;  ///< measured from the target's centre
  std::optional<ObserverField::Exceedance> aided_above_mpe;  ///< with an aid only
  Vec3 target_centre_m{0.0};
  /// The largest (aided, where there is an aid) hazard ratio an unconverged point could have,
  /// its error estimate added (0 when every point converged): below 1 none of them can be
  /// hazardous.
  double unconverged_ratio_upper = 0.0;

  [[nodiscard]] bool unconvergedMayBeHazardous() const { return !(unconverged_ratio_upper < 1.0); }
  /// The largest (aided, where there is an aid) hazard ratio the finite bound of a finest block
  /// allows where a glint narrower than the lattice may pass (status 6); 0 where there is none.
  /// Such points exist only where the bound reaches the MPE: they may be hazardous.
  double narrow_glint_ratio_bound = 0.0;
  /// Some point has status 6 and its bound reaches the MPE (aided, where there is an aid).
  bool narrow_glint_may_be_hazardous = false;

  /// Where a level (HazardSpec::levels, in order) is reached, and what may reach it unseen.
  struct Level {
    double peak_ratio = 0.0;  ///< peak irradiance / the level's threshold
    ObserverField::Exceedance above;
    bool unconverged_may_reach = false;   ///< an unconverged point's value + error reaches it
    bool narrow_glint_may_reach = false;  ///< a status-6 point's bound reaches it
  };
  std::vector<Level> levels;
};

/// @brief The zones of @p field under @p h, distances from @p target_centre_m.
HazardZone hazardZone(const ObserverField& field, const HazardSpec& h, const Vec3& target_centre_m);

/// @brief What the far field proves beyond its far radius, for the naked eye and through the
/// aid, the air's extinction included (hazardDistance()).
struct FarHazard {
  FarReach unaided;
  std::optional<FarReach> aided;  ///< with an aid only
  std::vector<FarReach> levels;   ///< per level (HazardSpec::levels), the naked eye's
  /// The farther of the two: what a study's coverage and a warning are judged by.
  [[nodiscard]] const FarReach& farthest() const {
    return aided && aided->nohd_m > unaided.nohd_m ? *aided : unaided;
  }
  /// @brief Each threshold's, in HazardSpec::thresholdsW_m2()'s order.
  [[nodiscard]] std::vector<FarReach> byThreshold() const {
    std::vector<FarReach> all{unaided};
    if (aided) all.push_back(*aided);
    all.insert(all.end(), levels.begin(), levels.end());
    return all;
  }
};
FarHazard farHazard(const FarField& field, const HazardSpec& h);

/// @brief The area (m²) of a plane's lattice points in @p zone: pixel_m² each.
double hazardousArea(const ObserverField& field, const ObserverField::Exceedance& zone);

}  // namespace glint
