#include "hazard/standard.h"

namespace glint {
namespace {

constexpr StandardClauses kAnsi2014{"ANSI Z136.1-2014", 2014,    "Table 5a",
                                    "Table 7",          "8.2.3", "8.3"};
// IEC 60825-1:2014 gives the MPEs in its informative Annex A: Table A.1 for the eye where the
// source subtends at most 1.5 mrad (C6 = 1), Table A.5 for the skin, A.3 for repeated pulses
// (the same rules as the classification's 4.3 f)) and A.2 for the limiting apertures an optical
// aid is judged against.
constexpr StandardClauses kIec2014{"IEC 60825-1:2014", 2014,  "Table A.1",
                                   "Table A.5",        "A.3", "A.2"};

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
  for (SafetyStandard s : {SafetyStandard::AnsiZ136_1_2014, SafetyStandard::Iec60825_1_2014}) {
    if (name == clauses(s).name) return s;
  }
  return std::nullopt;
}

const char* toString(Tissue tissue) { return tissue == Tissue::Skin ? "skin" : "eye"; }

}  // namespace glint
