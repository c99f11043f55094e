#include "pipeline/input/points_file.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "pipeline/base/input_error.h"
#include "pipeline/base/limits.h"
#include "pipeline/input/json_reader.h"

namespace glint {
namespace {

std::string_view trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t\r");
  return s.substr(first, last - first + 1);
}

std::vector<std::string_view> splitFields(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const auto comma = line.find(',', start);
    fields.push_back(trim(line.substr(start, comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return fields;
}

}  // namespace

std::vector<Vec3> parsePoints(std::string_view text, const std::string& source) {
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
  std::vector<Vec3> points;
  // One point per line at most: held once, not grown by doubling past what the budget counts.
  points.reserve(static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')) + 1);
  std::size_t line_no = 0;
  bool header_seen = false;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const auto end = text.find('\n', pos);
    const std::string_view line =
        text.substr(pos, end == std::string_view::npos ? std::string_view::npos : end - pos);
    pos = end == std::string_view::npos ? text.size() + 1 : end + 1;
    ++line_no;
    const auto where = [&] { return source + ":" + std::to_string(line_no) + ": "; };
    if (trim(line).empty()) continue;

    const std::vector<std::string_view> fields = splitFields(line);
    if (!header_seen) {
      if (fields.size() != 3 || fields[0] != "x" || fields[1] != "y" || fields[2] != "z") {
        throw InputError(where() + "the header must be x,y,z (found \"" + printable(trim(line)) +
                         "\")");
      }
      header_seen = true;
      continue;
    }
    if (fields.size() != 3) {
      throw InputError(where() + "expected 3 columns (x,y,z), found " +
                       std::to_string(fields.size()));
    }
    Vec3 p;
    for (int i = 0; i < 3; ++i) {
      const std::string_view f = fields[static_cast<std::size_t>(i)];
      double v = 0.0;
      const auto [ptr, ec] = std::from_chars(f.data(), f.data() + f.size(), v);
      const std::string column =
          std::string("column ") + std::to_string(i + 1) + " (" + "xyz"[i] + ")";
      if (ec == std::errc::result_out_of_range) {
        throw InputError(where() + column + ": \"" + printable(f) + "\" is out of range");
      }
      if (f.empty() || ec != std::errc() || ptr != f.data() + f.size()) {
        throw InputError(where() + column + ": \"" + printable(f) + "\" is not a number");
      }
      if (!std::isfinite(v)) {
        throw InputError(where() + column + ": \"" + printable(f) + "\" is not finite");
      }
      if (!(std::abs(v) <= limits::kMaxCoordinateM)) {
        throw InputError(where() + column + ": " + printable(f) +
                         " m is beyond ±1e7 m, the coordinates glint's arithmetic carries");
      }
      p[i] = v;
    }
    points.push_back(p);
  }
  if (!header_seen) throw InputError(source + ": empty file (expected a header x,y,z)");
  if (points.empty()) throw InputError(source + ": no observer points after the header");
  return points;
}

std::vector<Vec3> loadPoints(const std::filesystem::path& path, std::uintmax_t max_bytes) {
  return parsePoints(readUserFile(path, "points file", max_bytes), path.string());
}

}  // namespace glint
