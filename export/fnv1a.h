#pragma once
/// @file
/// @brief FNV-1a, 64 bit: names the inputs or content a result came from (not a security
/// measure).

#include <cstdint>
#include <string_view>

namespace glint {

inline constexpr std::uint64_t kFnv1aOffsetBasis = 1469598103934665603ull;

/// @brief The hash of @p bytes, continuing from @p h (the offset basis for a fresh hash).
inline std::uint64_t fnv1a64(std::string_view bytes, std::uint64_t h = kFnv1aOffsetBasis) {
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

}  // namespace glint
