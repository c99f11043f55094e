#pragma once
/// @file
/// @brief The error of bad user input (scene file, points file, command line).

#include <stdexcept>
#include <string>
#include <string_view>

namespace glint {

/// @brief Bad input, with a message that names the file and the place in it. The command line
/// prints it and exits with status 2.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// @brief @p text as it may be quoted in a message: control bytes and DEL escaped (\\xNN, so
/// a garbage file cannot ring the bell or move the terminal's cursor), cut after
/// @p max_chars bytes with "…".
std::string printable(std::string_view text, std::size_t max_chars = 64);

}  // namespace glint
