#pragma once
// A file's whole content, for tests that compare what glint wrote (or left alone) byte for byte.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace glint::test {

/// @brief The bytes of @p path ("" when it cannot be opened).
inline std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace glint::test
