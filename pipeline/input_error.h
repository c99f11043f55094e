#pragma once
/// @file
/// @brief The error of bad user input (scene file, points file, command line).

#include <stdexcept>

namespace glint {

/// @brief Bad input, with a message that names the file and the place in it. The command line
/// prints it and exits with status 2.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace glint
