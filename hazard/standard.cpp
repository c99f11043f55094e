#include "hazard/standard.h"

#include <limits>

namespace glint {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// ANSI Z136.1-2014: C_C of Table 6 stays 8 beyond 1200 nm; rule 3 (8.2.3.3) reduces every
// train by C_P = n^-0.25, n the pulses of the whole exposure.
constexpr StandardClauses kAnsi2014{.name = "ANSI Z136.1-2014",
                                    .edition_year = 2014,
                                    .point_source_mpe = "Table 5a",
                                    .skin_mpe = "Table 7",
                                    .repeated_pulses = "8.2.3",
                                    .optical_aids = "8.3",
                                    .near_ir_factor = "C_C",
                                    .near_ir_factor_climbs = false,
                                    .anterior_eye_limit = false,
                                    .rule_three_factor = "C_P",
                                    .rule_three_formula = "C_P = n^-0.25",
                                    .rule_three_key = "c_p",
                                    .rule_three_window_s = kInfinity,
                                    .rule_three_from_pulses = -kInfinity,
                                    .rule_three_scale = 1.0,
                                    .rule_three_floor = 0.0,
                                    .rule_three_only_within_t_i = false,
                                    .rule_three_cites_count = false};
// IEC 60825-1:2014 gives the MPEs in its informative Annex A: Table A.1 for the eye where the
// source subtends at most 1.5 mrad (C6 = 1), Table A.5 for the skin, A.3 for repeated pulses
// (the same rules as the classification's 4.3 f)) and A.2 for the limiting apertures an optical
// aid is judged against.
// Its C7 climbs to 10⁶ at 1400 nm as the ocular media absorb what would reach the retina, and
// 1200–1400 nm has a limit for the anterior eye besides; rule 3 (A.3, 4.3 f) 3)) counts N within
// T2 = 10 s for a point source and reduces pulses no longer than T_i only beyond 600 of them,
// to C5 = 5 N^-0.25, never below 0.4.
constexpr StandardClauses kIec2014{.name = "IEC 60825-1:2014",
                                   .edition_year = 2014,
                                   .point_source_mpe = "Table A.1",
                                   .skin_mpe = "Table A.5",
                                   .repeated_pulses = "A.3",
                                   .optical_aids = "A.2",
                                   .near_ir_factor = "C7",
                                   .near_ir_factor_climbs = true,
                                   .anterior_eye_limit = true,
                                   .rule_three_factor = "C5",
                                   .rule_three_formula = "C5 = 5 N^-0.25",
                                   .rule_three_key = "c5",
                                   .rule_three_window_s = 10.0,
                                   .rule_three_from_pulses = 600.0,
                                   .rule_three_scale = 5.0,
                                   .rule_three_floor = 0.4,
                                   .rule_three_only_within_t_i = true,
                                   .rule_three_cites_count = true};

}  // namespace

const StandardClauses& clauses(SafetyStandard standard) {
  switch (standard) {
    case SafetyStandard::AnsiZ136_1_2014:
      return kAnsi2014;
    case SafetyStandard::Iec60825_1_2014:
      return kIec2014;
  }
  return kAnsi2014;  // every enumerator is handled above
}

const char* mpeTable(SafetyStandard standard, Tissue tissue) {
  const StandardClauses& c = clauses(standard);
  return tissue == Tissue::Skin ? c.skin_mpe : c.point_source_mpe;
}

std::optional<SafetyStandard> standardNamed(std::string_view name) {
  for (SafetyStandard s : kStandards) {
    if (name == clauses(s).name) return s;
  }
  return std::nullopt;
}

const char* toString(Tissue tissue) { return tissue == Tissue::Skin ? "skin" : "eye"; }

}  // namespace glint
