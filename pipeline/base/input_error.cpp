#include "pipeline/base/input_error.h"

#include <algorithm>
#include <cstdio>

namespace glint {

std::string printable(std::string_view text, std::size_t max_chars) {
  std::string out;
  const std::size_t n = std::min(text.size(), max_chars);
  out.reserve(n + 8);
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c < 0x20 || c == 0x7f) {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\x%02x", static_cast<unsigned>(c));
      out.append(escaped);
    } else {
      out.push_back(static_cast<char>(c));
    }
  }
  if (text.size() > max_chars) out.append("…");
  return out;
}

}  // namespace glint
