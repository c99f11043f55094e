#include "hazard/standard.h"

namespace glint {

const StandardClauses& clauses(SafetyStandard standard) {
  static constexpr StandardClauses kAnsi2014{"ANSI Z136.1-2014", "Table 5a", "8.2.3", "8.3"};
  switch (standard) {
    case SafetyStandard::AnsiZ136_1_2014:
      return kAnsi2014;
  }
  return kAnsi2014;  // every enumerator is handled above
}

}  // namespace glint
