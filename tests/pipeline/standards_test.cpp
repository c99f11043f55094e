// The two standards and two tissues glint judges by: IEC 60825-1:2014 (Tables A.1 and A.5, the
// repeated-pulse rules of A.3) beside ANSI Z136.1-2014 (Tables 5a and 7, 8.2.3). Every expected
// value is worked by hand in its comment from the tables' rows (converted to J/m² and W/m²,
// × 10⁴); tolerances are rounding of the factors only.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "hazard/hazard.h"
#include "hazard/mpe.h"
#include "pipeline/input/scene.h"
#include "pipeline/report/hazard_report.h"
#include "support/cli.h"
#include "support/files.h"
#include "support/refusal.h"

namespace glint {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
constexpr double kRel = 1e-12;
constexpr SafetyStandard kAnsi = SafetyStandard::AnsiZ136_1_2014;
constexpr SafetyStandard kIec = SafetyStandard::Iec60825_1_2014;

void expectNearRel(double got, double want, const std::string& what) {
  EXPECT_NEAR(got, want, kRel * std::abs(want)) << what;
}

// Outside 1150–1400 nm the point-source rows of Table A.1 are those of Table 5a (both follow
// ICNIRP): the same value at every wavelength and duration on both sides of each row's edge.
TEST(IecMpe, PointSourceRowsAreAnsisOutsideTheC7Band) {
  for (double nm : {400.0, 450.0, 532.0, 599.0, 600.0, 633.0, 700.0, 808.0, 1000.0, 1050.0, 1064.0,
                    1150.0, 1400.5, 1450.0, 1550.0, 2000.0, 3000.0, 10600.0, 1e6}) {
    for (double t : {1e-9, 1e-8, 1e-7, 4.9e-6, 5e-6, 12e-6, 13e-6, 1e-3, 0.25, 1.0, 9.99, 10.0,
                     99.0, 100.0, 1000.0, 3e4}) {
      const Mpe iec = ocularMpe(nm, t, kIec), ansi = ocularMpe(nm, t, kAnsi);
      expectNearRel(iec.irradiance_w_m2, ansi.irradiance_w_m2,
                    std::to_string(nm) + " nm, " + std::to_string(t) + " s: " + iec.rule);
      EXPECT_EQ(iec.limit, ansi.limit) << nm << " nm, " << t << " s";
    }
  }
}

// C7 = 8 + 10^(0.04 (λ − 1250)) from 1200 nm (IEC) against ANSI's C_C = 8. From 10 s the
// retinal row is 10 C4 C7 = 50 C7 W/m²: at 1200 nm 50 × 8.01 = 400.5, at 1250 nm 50 × 9 = 450.
// At 1300 nm C7 = 108 gives 5400 W/m², above the anterior eye's 1000 W/m², which glint applies
// beside it (the lower holds). Short pulses stay retinal: at 1300 nm, 10 ns, 2e-2 × 108 =
// 2.16 J/m² against the cornea's 1000 J/m².
TEST(IecMpe, C7RaisesTheRetinalLimitUpTo1400NanometresUnderTheAnteriorEyes) {
  expectNearRel(ocularMpe(1200.0, 100.0, kIec).irradiance_w_m2, 50.0 * 8.01, "1200 nm");
  expectNearRel(ocularMpe(1250.0, 100.0, kIec).irradiance_w_m2, 450.0, "1250 nm");
  expectNearRel(ocularMpe(1175.0, 100.0, kIec).irradiance_w_m2, 50.0 * std::pow(10.0, 0.45),
                "1175 nm: 10^(0.018 × 25) as ANSI's C_C");
  const Mpe at1300 = ocularMpe(1300.0, 100.0, kIec);
  expectNearRel(at1300.irradiance_w_m2, 1000.0, at1300.rule);
  EXPECT_NE(at1300.rule.find("anterior eye"), std::string::npos) << at1300.rule;
  expectNearRel(ocularMpe(1300.0, 1e-8, kIec).radiant_exposure_j_m2, 2e-2 * 108.0, "10 ns");
  // ANSI keeps C_C = 8 over 1200–1400 nm: 400 W/m² from 10 s.
  expectNearRel(ocularMpe(1300.0, 100.0, kAnsi).irradiance_w_m2, 400.0, "ANSI at 1300 nm");
  // Across 1200–1400 nm IEC's limit never exceeds the 1400–1500 nm row just past 1400 nm.
  for (double nm = 1200.0; nm <= 1400.0; nm += 5.0) {
    for (double t : {1e-8, 1e-5, 1e-3, 0.1, 1.0, 10.0, 1000.0}) {
      EXPECT_LE(ocularMpe(nm, t, kIec).irradiance_w_m2,
                ocularMpe(1400.5, t, kIec).irradiance_w_m2 * (1.0 + kRel))
          << nm << " nm, " << t << " s";
    }
  }
}

// The skin (ANSI Table 7, IEC Table A.5, alike): 400–1400 nm 200 C_A J/m² to 100 ns, 1.1e4 C_A
// t^0.25 J/m² to 10 s, 2000 C_A W/m² beyond; 1.4 µm to 1 mm the eye's corneal rows, but beyond
// 10 s the 100 W/m² of lit areas above 0.1 m² (glint does not know the area).
TEST(SkinMpe, RowsOfBothStandardsAtTheirEdges) {
  for (SafetyStandard s : {kAnsi, kIec}) {
    const std::string name = clauses(s).name;
    expectNearRel(skinMpe(532.0, 1e-8, s).radiant_exposure_j_m2, 200.0, name + " 532 nm 10 ns");
    expectNearRel(skinMpe(532.0, 1.0, s).irradiance_w_m2, 1.1e4, name + " 532 nm 1 s");
    expectNearRel(skinMpe(1064.0, 100.0, s).irradiance_w_m2, 1.0e4, name + " 2000 × C_A = 5");
    const double ca808 = std::pow(10.0, 0.002 * 108.0);
    expectNearRel(skinMpe(808.0, 0.25, s).irradiance_w_m2, 1.1e4 * ca808 * std::pow(0.25, -0.75),
                  name + " 808 nm 0.25 s");
    expectNearRel(skinMpe(1550.0, 1.0, s).irradiance_w_m2, 1.0e4, name + " 1550 nm 1 s");
    expectNearRel(skinMpe(10600.0, 1.0, s).irradiance_w_m2, 5600.0, name + " 10.6 µm 1 s");
    expectNearRel(skinMpe(10600.0, 100.0, s).irradiance_w_m2, 100.0, name + " large area");
    expectNearRel(skinMpe(1450.0, 1e-4, s).radiant_exposure_j_m2, 1000.0, name + " 1450 nm");
    // The rows meet within the standards' rounding at 100 ns: 1.1e4 × (1e-7)^0.25 = 195.6.
    EXPECT_NEAR(skinMpe(532.0, 1e-7, s).radiant_exposure_j_m2, 200.0, 0.03 * 200.0) << name;
    EXPECT_EQ(skinMpe(532.0, 1.0, s).tissue, Tissue::Skin);
  }
  // The skin tolerates far more than the retina: at 532 nm for 10 s, 2000 W/m² against 10.
  EXPECT_GT(skinMpe(532.0, 10.0).irradiance_w_m2, 100.0 * ocularMpe(532.0, 10.0).irradiance_w_m2);
  EXPECT_NE(mpeCitation(skinMpe(532.0, 1.0, kIec)).find("IEC 60825-1:2014 Table A.5"),
            std::string::npos);
  EXPECT_NE(mpeCitation(skinMpe(532.0, 1.0, kAnsi)).find("ANSI Z136.1-2014 Table 7"),
            std::string::npos);
}

PulseSpec train(double duration_s, double rate_hz) { return {1e-3, duration_s, rate_hz}; }

// IEC's rule 3 for a point source: nanosecond pulses (no longer than T_i) are not reduced up to
// 600 pulses within T2 = 10 s. The textbook Nd:YAG (1064 nm, 10 ns at 10 Hz for 10 s) is then
// set by rule 1, 2e-2 J/m², where ANSI's C_P = 100^-0.25 gives 6.32e-3 J/m².
TEST(IecPulseTrain, UpTo600NanosecondPulsesTheSinglePulseRuleHolds) {
  const PulseTrainMpe iec = pulseTrainMpe(1064.0, train(10e-9, 10.0), 10.0, kIec);
  EXPECT_EQ(iec.rule, 1);
  EXPECT_DOUBLE_EQ(iec.c_p, 1.0) << "N = 100 ≤ 600";
  EXPECT_DOUBLE_EQ(iec.reduction_pulses, 100.0);
  expectNearRel(iec.per_pulse_j_m2, 2e-2, "rule 1");
  const PulseTrainMpe ansi = pulseTrainMpe(1064.0, train(10e-9, 10.0), 10.0, kAnsi);
  EXPECT_EQ(ansi.rule, 3);
  expectNearRel(ansi.per_pulse_j_m2, 2e-2 / std::sqrt(10.0), "ANSI rule 3");
}

// Beyond 600 pulses: 532 nm, 10 ns at 100 Hz for 100 s. N counts the pulses within T2 = 10 s,
// 1000: C5 = 5 × 1000^-0.25 = 0.8891, rule 3 = 2e-3 × 0.8891 = 1.778e-3 J/m². Rule 2: 10 W/m²
// × 100 s over 10⁴ pulses = 0.1 J/m². At 10 kHz for 10 s, N = 10⁵ and 5 N^-0.25 = 0.281 is
// held at 0.4: 8e-4 J/m², below rule 2's 100 J/m² / 10⁵ = 1e-3 J/m².
TEST(IecPulseTrain, BeyondSixHundredPulsesWithinT2C5FallsToFourTenths) {
  const PulseTrainMpe a = pulseTrainMpe(532.0, train(10e-9, 100.0), 100.0, kIec);
  EXPECT_DOUBLE_EQ(a.reduction_pulses, 1000.0) << "within T2, not the 10⁴ of the exposure";
  expectNearRel(a.c_p, 5.0 * std::pow(1000.0, -0.25), "C5");
  EXPECT_EQ(a.rule, 3);
  expectNearRel(a.per_pulse_j_m2, 2e-3 * 5.0 * std::pow(1000.0, -0.25), "rule 3");
  expectNearRel(a.average_j_m2, 0.1, "rule 2");
  const PulseTrainMpe b = pulseTrainMpe(532.0, train(10e-9, 1e4), 10.0, kIec);
  EXPECT_DOUBLE_EQ(b.c_p, 0.4);
  EXPECT_EQ(b.rule, 3);
  expectNearRel(b.per_pulse_j_m2, 8e-4, "0.4 × 2e-3");
}

// Pulses longer than T_i from a source below 5 mrad are not reduced at all: 532 nm, 1 ms at
// 100 Hz for 10 s. Rule 1: 18 × (1e-3)^0.75 = 0.1012 J/m²; rule 2: 100 J/m² / 1000 = 0.1 J/m²,
// the limit. ANSI's rule 3 would give 0.1012 × 1000^-0.25 = 0.0180 J/m².
TEST(IecPulseTrain, PulsesLongerThanTiFromAPointSourceAreNotReduced) {
  const PulseTrainMpe m = pulseTrainMpe(532.0, train(1e-3, 100.0), 10.0, kIec);
  EXPECT_DOUBLE_EQ(m.c_p, 1.0);
  EXPECT_EQ(m.rule, 2);
  expectNearRel(m.per_pulse_j_m2, 0.1, "rule 2");
  expectNearRel(pulseTrainMpe(532.0, train(1e-3, 100.0), 10.0, kAnsi).per_pulse_j_m2,
                18.0 * std::pow(1e-3, 0.75) * std::pow(1000.0, -0.25), "ANSI rule 3");
}

// Under either standard and for either tissue, rule 2 keeps every train at least as restrictive
// as continuous light of its mean power; and IEC is never more restrictive than ANSI for the
// eye away from 1150–1400 nm (its C5 is never below ANSI's C_P there: 5 N^-0.25 ≥ n^-0.25 and
// 0.4 ≥ n^-0.25 once n ≥ 39).
TEST(IecPulseTrain, NoTrainIsLessRestrictiveThanItsMeanPowerUnderEitherStandard) {
  for (SafetyStandard s : {kAnsi, kIec}) {
    for (Tissue tissue : {Tissue::Eye, Tissue::Skin}) {
      for (double nm : {450.0, 532.0, 800.0, 1064.0, 1300.0, 1550.0, 10600.0}) {
        for (double tau : {1e-9, 1e-6, 1e-4}) {
          for (double f : {10.0, 1e3, 1e5}) {
            if (tau * f > 1.0) continue;
            for (double t : {0.25, 10.0, 100.0}) {
              const PulseTrainMpe m = pulseTrainMpe(nm, train(tau, f), t, s, tissue);
              const double cw = tableMpe(nm, t, s, tissue).irradiance_w_m2;
              EXPECT_LE(m.per_pulse_j_m2 * f, cw * (1.0 + 1e-9))
                  << clauses(s).name << " " << toString(tissue) << " " << nm << " nm " << tau
                  << " s " << f << " Hz " << t << " s";
              if (s == kIec && tissue == Tissue::Eye && (nm < 1150.0 || nm > 1400.0)) {
                EXPECT_GE(m.per_pulse_j_m2,
                          pulseTrainMpe(nm, train(tau, f), t, kAnsi).per_pulse_j_m2 * (1.0 - 1e-12))
                    << nm << " nm " << tau << " s " << f << " Hz " << t << " s";
              }
              if (tissue == Tissue::Skin) {
                EXPECT_EQ(m.reduced_j_m2, 0.0) << "no rule 3 for skin";
              }
            }
          }
        }
      }
    }
  }
}

json sceneWithHazard(const json& hazard) {
  json j = json::parse(R"({
    "laser": {"position": [-10, 0, 0], "direction": [1, 0, 0], "power_w": 1.0,
              "wavelength_nm": 532, "beam": {"profile": "flat_top", "radius_m": 0.2}},
    "materials": {"white": {"specular_reflectance": 0.0, "sigma": 0.1,
                            "diffuse_reflectance": 0.8}},
    "objects": [{"shape": "disk", "center": [0, 0, 0], "normal": [-1, 0, 0], "radius": 0.05,
                 "material": "white"}]
  })");
  if (!hazard.is_null()) j["hazard"] = hazard;
  return j;
}

// Every standard of kStandards is read by its name, refused names list them all, and its
// clauses are whole: each rule reads them, none asks which standard it is.
TEST(SceneStandard, EveryKnownStandardIsReadByItsNameAndHasEveryClause) {
  const std::string refusal = test::refusalOf([] {
    parseScene(sceneWithHazard({{"standard", "no such standard"}}).dump(), "s.json");
  });
  for (SafetyStandard s : kStandards) {
    const StandardClauses& c = clauses(s);
    EXPECT_EQ(standardNamed(c.name), s) << c.name;
    EXPECT_NE(refusal.find(std::string("\"") + c.name + "\""), std::string::npos)
        << refusal << " does not name " << c.name;
    for (const char* text :
         {c.point_source_mpe, c.skin_mpe, c.repeated_pulses, c.optical_aids, c.near_ir_factor,
          c.rule_three_factor, c.rule_three_formula, c.rule_three_key}) {
      ASSERT_NE(text, nullptr) << c.name;
      EXPECT_GT(std::string(text).size(), 0u) << c.name;
    }
    // Rule 3 never raises a limit and never reduces it to nothing.
    EXPECT_GE(c.rule_three_window_s, 10.0) << c.name;
    for (double n : {2.0, 601.0, 1e6}) {
      const double reduction = ruleThreeReduction(s, 1064.0, 1e-8, n);
      EXPECT_GT(reduction, 0.0) << c.name << ", " << n << " pulses";
      EXPECT_LE(reduction, 1.0) << c.name << ", " << n << " pulses";
    }
  }
  EXPECT_EQ(kStandards[0], kAnsi) << "ANSI Z136.1-2014 is the default";
}

TEST(SceneStandard, HazardKeysChooseTheTableAndTheSkinsDefaultExposure) {
  const Scene ansi = parseScene(sceneWithHazard(nullptr).dump(), "scene.json");
  EXPECT_EQ(ansi.hazard.standard, kAnsi) << "the default";
  EXPECT_EQ(ansi.hazard.tissue, Tissue::Eye);
  EXPECT_DOUBLE_EQ(ansi.hazard.exposure_s, 0.25);
  const Scene iec =
      parseScene(sceneWithHazard({{"standard", "IEC 60825-1:2014"}}).dump(), "scene.json");
  EXPECT_EQ(iec.hazard.standard, kIec);
  EXPECT_NE(hazardCitation(iec.hazard).find("IEC 60825-1:2014 Table A.1"), std::string::npos)
      << hazardCitation(iec.hazard);
  // The skin at 532 nm: 10 s by default, 2000 W/m².
  const Scene skin = parseScene(
      sceneWithHazard({{"standard", "IEC 60825-1:2014"}, {"tissue", "skin"}}).dump(), "s.json");
  EXPECT_DOUBLE_EQ(skin.hazard.exposure_s, 10.0);
  EXPECT_NEAR(skin.hazard.mpe_w_m2, 2000.0, 1e-9);
  EXPECT_NE(hazardLine(skin.hazard).find("IEC 60825-1:2014, skin"), std::string::npos)
      << hazardLine(skin.hazard);
  EXPECT_NE(test::refusalOf([] {
              parseScene(sceneWithHazard({{"standard", "IEC 60825-1:2007"}}).dump(), "s.json");
            }).find("\"IEC 60825-1:2014\""),
            std::string::npos);
  json aided = sceneWithHazard({{"tissue", "skin"}});
  aided["optical_aid"] = {{"gain", 10.0}};
  EXPECT_NE(test::refusalOf([&] { parseScene(aided.dump(), "s.json"); }).find("optical_aid"),
            std::string::npos);
}

// What a run records: summary.json names the standard, its edition, the tissue, the table and
// the row, for each standard; the plane map's header carries the same citation.
TEST(SceneStandard, EachStandardsCitationReachesSummaryJson) {
  const fs::path dir = fs::temp_directory_path() / "glint_standard_citation";
  fs::remove_all(dir);
  fs::create_directories(dir);
  struct Case {
    json hazard;
    std::string standard, table;
    int edition;
  };
  const Case cases[] = {
      {nullptr, "ANSI Z136.1-2014", "Table 5a", 2014},
      {{{"standard", "IEC 60825-1:2014"}}, "IEC 60825-1:2014", "Table A.1", 2014},
      {{{"standard", "IEC 60825-1:2014"}, {"tissue", "skin"}},
       "IEC 60825-1:2014",
       "Table A.5",
       2014},
      {{{"tissue", "skin"}}, "ANSI Z136.1-2014", "Table 7", 2014},
  };
  int i = 0;
  for (const Case& c : cases) {
    json scene = sceneWithHazard(c.hazard);
    scene["far_field"] = {{"enabled", false}};
    scene["planes"] = {{{"name", "wall"},
                        {"origin", {-5, -1, -1}},
                        {"u_axis", {0, 1, 0}},
                        {"v_axis", {0, 0, 1}},
                        {"size_m", {2, 2}},
                        {"pixel_m", 0.5}}};
    const fs::path file = dir / ("scene" + std::to_string(i) + ".json");
    std::ofstream(file) << scene.dump();
    const fs::path out = dir / ("out" + std::to_string(i++));
    const test::Outcome run = test::glint({"run", file.string(), "-o", out.string(), "--quiet"});
    ASSERT_EQ(run.status, 0) << run.err;
    const json h = json::parse(test::readFile(out / "summary.json")).at("hazard");
    EXPECT_EQ(h.at("standard"), c.standard) << h.dump();
    EXPECT_EQ(h.at("standard_edition"), c.edition) << h.dump();
    EXPECT_EQ(h.at("mpe_table"), c.table) << h.dump();
    EXPECT_EQ(h.at("mpe_rule").get<std::string>().rfind(c.standard + " " + c.table + ": ", 0), 0u)
        << h.dump();
    EXPECT_NE(test::readFile(out / "wall.exr").find(c.standard + " " + c.table), std::string::npos)
        << "the map's header cites it too";
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace glint
