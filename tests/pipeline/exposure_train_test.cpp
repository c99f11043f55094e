// A train of glints judged as a pulse train: the pulses of an irradiance history counted and
// rule 3 of the repetitive-pulse rules applied to them (hazard/exposure_train.h), against the
// pulsed laser of the same train (pulseTrainMpe()) and against the standards' rows worked by
// hand.
#include "hazard/exposure_train.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace glint {
namespace {

// A history of rectangular pulses: each (start_s, duration_s, irradiance_w_m2) rises and falls
// within a millionth of its duration, on a constant background, over [0, span_s].
struct Pulse {
  double start_s, duration_s, irradiance_w_m2;
};

struct History {
  std::vector<double> t, e;
};

History rectangles(const std::vector<Pulse>& pulses, double span_s, double background_w_m2 = 0.0) {
  History h;
  auto add = [&](double t, double e) {
    h.t.push_back(t);
    h.e.push_back(e);
  };
  add(0.0, background_w_m2);
  for (const Pulse& p : pulses) {
    const double edge = 1e-6 * p.duration_s;
    add(p.start_s - edge, background_w_m2);
    add(p.start_s, background_w_m2 + p.irradiance_w_m2);
    add(p.start_s + p.duration_s, background_w_m2 + p.irradiance_w_m2);
    add(p.start_s + p.duration_s + edge, background_w_m2);
  }
  add(span_s, background_w_m2);
  return h;
}

// @p count pulses of @p duration_s at @p rate_hz from a tenth of a period on, each delivering
// @p energy_j_m2.
std::vector<Pulse> regular(int count, double duration_s, double rate_hz, double energy_j_m2) {
  std::vector<Pulse> p;
  for (int i = 0; i < count; ++i)
    p.push_back({(i + 0.1) / rate_hz, duration_s, energy_j_m2 / duration_s});
  return p;
}

HazardSpec hazardAt(double wavelength_nm, SafetyStandard standard = SafetyStandard::AnsiZ136_1_2014,
                    Tissue tissue = Tissue::Eye) {
  HazardSpec h;
  h.wavelength_nm = wavelength_nm;
  h.standard = standard;
  h.tissue = tissue;
  return h;
}

// The verdict of @p h over @p span_s, pulses counted above a thousandth of @p peak_w_m2.
ExposureVerdict judge(const History& h, const HazardSpec& hazard, double span_s, double peak_w_m2) {
  return judgeExposure(h.t, h.e, peak_w_m2, hazard, span_s, 1e-3 * peak_w_m2);
}

// A train of N equal pulses is judged as the pulsed laser of that train: the verdict is the
// pulse's energy over pulseTrainMpe()'s limit per pulse (within the window search's 0.1 %), set
// by the same rule, with as many pulses (or groups) counted as rule 3 counts.
TEST(PulseTrain, NEqualPulsesAreJudgedAsThePulsedLaserOfThatTrain) {
  struct Case {
    const char* what;
    double nm, duration_s, rate_hz, span_s;
    SafetyStandard standard;
    DecidingRule rule;  // None: rules 2 and 3 tie exactly (a grouped train, t^0.75 rows)
    Tissue tissue = Tissue::Eye;
  };
  const std::vector<Case> cases = {
      {"1064 nm, 100 µs at 10 Hz for 10 s, ANSI: C_P = 100^-0.25", 1064.0, 1e-4, 10.0, 10.0,
       SafetyStandard::AnsiZ136_1_2014, DecidingRule::Train},
      {"1550 nm, 10 ns at 10 Hz for 10 s: no rule 3, the average", 1550.0, 1e-8, 10.0, 10.0,
       SafetyStandard::AnsiZ136_1_2014, DecidingRule::Average},
      {"1064 nm, 100 µs at 10 Hz for 10 s, IEC: longer than T_i, C5 = 1", 1064.0, 1e-4, 10.0, 10.0,
       SafetyStandard::Iec60825_1_2014, DecidingRule::SinglePulse},
      {"532 nm, 1 ns at 1 MHz for 1 ms: groups of 5 within t_min", 532.0, 1e-9, 1e6, 1e-3,
       SafetyStandard::AnsiZ136_1_2014, DecidingRule::None},
      {"1064 nm, 100 µs at 1 Hz for 10 s on the skin: no rule 3", 1064.0, 1e-4, 1.0, 10.0,
       SafetyStandard::AnsiZ136_1_2014, DecidingRule::SinglePulse, Tissue::Skin},
  };
  const double energy_j_m2 = 1e-3;
  for (const Case& c : cases) {
    const int n = static_cast<int>(std::lround(c.rate_hz * c.span_s));
    const History h = rectangles(regular(n, c.duration_s, c.rate_hz, energy_j_m2), c.span_s);
    const HazardSpec hazard = hazardAt(c.nm, c.standard, c.tissue);
    const PulseTrainMpe laser =
        pulseTrainMpe(c.nm, {energy_j_m2, c.duration_s, c.rate_hz}, c.span_s, c.standard, c.tissue);
    const double want = energy_j_m2 / laser.per_pulse_j_m2;
    const ExposureVerdict v = judge(h, hazard, c.span_s, energy_j_m2 / c.duration_s);
    EXPECT_GE(v.ratio, want * (1.0 - 1e-9)) << c.what << ": never below the laser's verdict";
    EXPECT_LE(v.ratio, want * (1.0 + 1.1e-3)) << c.what << ": within the search's 0.1 %";
    if (c.rule != DecidingRule::None) {
      EXPECT_EQ(static_cast<int>(v.rule), laser.rule) << c.what;
      EXPECT_EQ(v.rule, c.rule) << c.what;
    }
    if (laser.reduced_j_m2 > 0.0) {
      EXPECT_NEAR(static_cast<double>(v.train.pulses), laser.reduction_pulses, 1e-9)
          << c.what << ": the pulses rule 3 counts";
      // Equal pulses' ratios agree to rounding, so each weighs 1 within 1e-9.
      EXPECT_NEAR(v.train.reduction, laser.c_p, 1e-9) << c.what;
      EXPECT_EQ(v.train.grouped, laser.grouped) << c.what;
    } else {
      EXPECT_EQ(v.train.reduction, 1.0) << c.what << ": rule 3 does not apply";
      EXPECT_LE(v.train.ratio, v.ratio) << c.what << ": a pulse alone, read at its half peak";
      EXPECT_EQ(v.train.pulses, n) << c.what << ": the pulses are counted all the same";
    }
  }
}

// IEC 60825-1:2014's C5 at 532 nm: pairs of 1 µs pulses 2 µs apart act as one pulse of T_i =
// 5 µs carrying both energies; 100 pairs a second for 20 s are 2000 groups, of which C5 counts
// the 1000 within T2 = 10 s: C5 = 5 × 1000^-0.25 = 0.889. Rule 3 per group: 2H against
// 18 × (5 µs)^0.75 J/m² × 0.889. ANSI counts all 2000 over the 20 s: C_P = 2000^-0.25.
TEST(PulseTrain, IecCountsGroupsWithinTiAndOnlyTheOnesWithinT2) {
  const double h_j_m2 = 1e-4, span_s = 20.0;
  std::vector<Pulse> pulses;
  for (int i = 0; i < 2000; ++i) {
    const double start = (i + 0.5) / 100.0;
    pulses.push_back({start, 1e-6, h_j_m2 / 1e-6});
    pulses.push_back({start + 2e-6, 1e-6, h_j_m2 / 1e-6});
  }
  const History h = rectangles(pulses, span_s);
  const double group_mpe_j_m2 = 18.0 * std::pow(5e-6, 0.75);  // Table A.1, 5 µs to 10 s
  const ExposureVerdict iec =
      judge(h, hazardAt(532.0, SafetyStandard::Iec60825_1_2014), span_s, h_j_m2 / 1e-6);
  EXPECT_EQ(iec.rule, DecidingRule::Train);
  EXPECT_TRUE(iec.train.grouped);
  EXPECT_EQ(iec.train.pulses, 1000) << "the groups within T2, not the 2000 of the exposure";
  EXPECT_STREQ(iec.train.reduction_name, "C5");
  // The groups' ratios agree to rounding, so each weighs 1 within 1e-9.
  EXPECT_NEAR(iec.train.reduction, 5.0 * std::pow(1000.0, -0.25), 1e-9);
  const double want_iec = 2.0 * h_j_m2 / (group_mpe_j_m2 * 5.0 * std::pow(1000.0, -0.25));
  EXPECT_GE(iec.ratio, want_iec * (1.0 - 1e-9));
  EXPECT_LE(iec.ratio, want_iec * (1.0 + 1.1e-3));
  // The pulses are as far apart as the pairs: within T_i only the pair's two.
  EXPECT_NEAR(iec.train.pulse_duration_s, 5e-6, 1e-12) << "a group lasts t_min";
  EXPECT_NEAR(iec.train.pulse_exposure_j_m2, 2.0 * h_j_m2, 1e-5 * h_j_m2) << "the pair's";
  const ExposureVerdict ansi = judge(h, hazardAt(532.0), span_s, h_j_m2 / 1e-6);
  EXPECT_EQ(ansi.train.pulses, 2000);
  const double want_ansi = 2.0 * h_j_m2 / (group_mpe_j_m2 * std::pow(2000.0, -0.25));
  EXPECT_GE(ansi.ratio, want_ansi * (1.0 - 1e-9));
  EXPECT_LE(ansi.ratio, want_ansi * (1.0 + 1.1e-3));
}

// Unequal pulses count by their share of the strongest to the fourth power, the weighing under
// which rule 3's N^-1/4 is exact: at 1064 nm, 20 pulses at 20 Hz alternating 0.02 J/m² over
// 100 µs (0.02 / (90 × (1e-4)^0.75) = 0.222 alone) and 0.05 J/m² over 1 ms (0.05 / (90 ×
// (1e-3)^0.75) = 0.0988 alone, though it carries more energy). The train counts as 10 +
// 10 × (0.0988 / 0.222)^4 = 10.39 pulses as strong as the short one: 0.222 × 10.39^0.25 =
// 0.399, never below the 10 identical short pulses alone (0.395), and below the 0.470 of 20
// copies of the strongest, which would count the weak pulses as strong ones.
TEST(PulseTrain, UnequalPulsesCountByTheirShareOfTheStrongestToTheFourthPower) {
  std::vector<Pulse> pulses;
  for (int i = 0; i < 20; ++i) {
    const bool short_pulse = i % 2 == 0;
    const double d = short_pulse ? 1e-4 : 1e-3;
    pulses.push_back({(i + 0.1) / 20.0, d, (short_pulse ? 0.02 : 0.05) / d});
  }
  const History h = rectangles(pulses, 1.0);
  const ExposureVerdict v = judge(h, hazardAt(1064.0), 1.0, 200.0);
  const double strong = 0.02 / (90.0 * std::pow(1e-4, 0.75));
  const double weak = 0.05 / (90.0 * std::pow(1e-3, 0.75));
  const double effective = 10.0 + 10.0 * std::pow(weak / strong, 4.0);
  const double want = strong * std::pow(effective, 0.25);
  EXPECT_EQ(v.rule, DecidingRule::Train);
  EXPECT_EQ(v.train.pulses, 20);
  EXPECT_NEAR(v.train.effective_pulses, effective, 2e-3 * effective);
  EXPECT_GE(v.ratio, want * (1.0 - 1e-9));
  EXPECT_LE(v.ratio, want * (1.0 + 1.1e-3));
  EXPECT_NEAR(v.train.pulse.duration_s, 1e-4, 1e-6) << "the short pulse sets it";
  EXPECT_NEAR(v.train.pulse_exposure_j_m2, 0.02, 1e-5 * 0.02);
  EXPECT_GE(v.ratio, strong * std::pow(10.0, 0.25) * (1.0 - 1e-9)) << "the 10 short pulses alone";
  EXPECT_LT(v.ratio, strong * std::pow(20.0, 0.25)) << "20 copies of the strongest";
}

// A glint with faint glimmers beside it (the missile's body light beside its fin's glint) is
// judged as the glint alone, within their fourth-power weight: 100 µs of 1000 W/m² at 1064 nm
// (0.1 / (90 × (1e-4)^0.75) = 1.11) and two 100 µs glimmers of 3 W/m² a tenth of a second away,
// above the floor (1 W/m²): three pulses, which weigh as 1 + 2 × (3/1000)^4.
TEST(PulseTrain, FaintGlimmersBesideAGlintAddNextToNothing) {
  const History h = rectangles({{0.1, 1e-4, 3.0}, {0.2, 1e-4, 1000.0}, {0.3, 1e-4, 3.0}}, 0.5);
  const ExposureVerdict v = judge(h, hazardAt(1064.0), 0.5, 1000.0);
  const double glint = 0.1 / (90.0 * std::pow(1e-4, 0.75));
  EXPECT_EQ(v.train.pulses, 3);
  EXPECT_NEAR(v.train.effective_pulses, 1.0, 1e-9);
  EXPECT_NEAR(v.ratio, glint, 1.1e-3 * glint);
}

// Glints on light that never falls back to the floor (a diffuse background of 1 W/m² under
// 500 W/m² glints of 100 µs at 10 Hz for 10 s, 1064 nm) are still 100 pulses: counted above a
// doubling of the floor where the background lies below it. Their energy is counted with the
// background under them: (500 + 1) W/m² × 100 µs.
TEST(PulseTrain, GlintsOnABackgroundAboveTheFloorAreStillSeparatePulses) {
  const History h = rectangles(regular(100, 1e-4, 10.0, 0.05), 10.0, 1.0);
  const ExposureVerdict v = judgeExposure(h.t, h.e, 501.0, hazardAt(1064.0), 10.0, 0.05);
  EXPECT_EQ(v.rule, DecidingRule::Train);
  EXPECT_EQ(v.train.pulses, 100);
  EXPECT_GT(v.train.threshold_w_m2, 1.0) << "above the background";
  const double want = 501.0 * 1e-4 / (90.0 * std::pow(1e-4, 0.75)) * std::pow(100.0, 0.25);
  EXPECT_GE(v.ratio, want * (1.0 - 1e-6));
  EXPECT_LE(v.ratio, want * (1.0 + 1.1e-3));
  // Above the floor alone the history is one exposure of 10 s: no train there.
  const std::vector<HistoryPulse> at_floor = historyPulses(h.t, h.e, 0.05, pulseGroupingS(1064.0));
  EXPECT_EQ(at_floor.size(), 1u);
}

}  // namespace
}  // namespace glint
