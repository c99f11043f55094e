#pragma once
/// @file
/// @brief The observer points file of `glint points`: a header `x,y,z`, then one observer per
/// row (docs/physics.md, "The points file and the output table").

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "facets/vec3.h"

namespace glint {

/// @brief Reads observer positions (m). Blank lines are skipped; spaces around fields, CRLF
/// line ends and a UTF-8 byte-order mark are accepted.
/// @throw InputError naming the file and line: a missing or wrong header, a row without exactly
/// three columns, a field that is not a finite number, or no rows at all; or a file longer
/// than @p max_bytes.
std::vector<Vec3> loadPoints(const std::filesystem::path& path,
                             std::uintmax_t max_bytes = std::uintmax_t{4} << 30);

/// @brief As loadPoints, from text; @p source names it in messages.
std::vector<Vec3> parsePoints(std::string_view text, const std::string& source);

}  // namespace glint
