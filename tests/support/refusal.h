#pragma once
// The message bad input is refused with, for tests that check what the user is told.
#include <string>

#include "pipeline/base/input_error.h"

namespace glint::test {

/// @brief What @p load throws as an InputError, or "(accepted)" when it throws nothing.
template <class Load>
std::string refusalOf(Load&& load) {
  try {
    load();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

}  // namespace glint::test
