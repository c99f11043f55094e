#pragma once
/// @file
/// @brief How far apart two words are, for naming what a user likely meant (a misspelt command
/// or key).

#include <algorithm>
#include <cstddef>
#include <string_view>
#include <vector>

namespace glint {

/// @brief The fewest insertions, deletions and substitutions of one character that turn @p a
/// into @p b (Levenshtein).
inline std::size_t editDistance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

/// @brief Whether @p typed is near enough @p meant to be named as a likely misspelling of it:
/// at most two edits, and fewer than half the word.
inline bool likelyMisspelling(std::string_view typed, std::string_view meant) {
  const std::size_t edits = editDistance(typed, meant);
  return edits > 0 && edits <= 2 && 2 * edits < meant.size();
}

}  // namespace glint
