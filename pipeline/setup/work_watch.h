#pragma once
/// @file
/// @brief How a command watches and shows one computation (a field, the far field, the reach,
/// an engagement's samples): one bundle every setup step takes.

#include <ostream>
#include <string>

namespace glint {

class MemoryWatch;    // pipeline/base/memory_budget.h
class PointExchange;  // observers/point_set.h

/// @brief How a command watches and shows one computation.
struct WorkWatch {
  const MemoryWatch& watch;  ///< stops the work when the run's memory passes its budget
  std::string what;          ///< names the work in messages ("the observer box", "plane wall")
  std::ostream* progress_to = nullptr;  ///< none: quiet
  bool terminal = false;                ///< progress as one self-overwriting line
  PointExchange* exchange = nullptr;    ///< MPI: the ranks share the points
};

}  // namespace glint
