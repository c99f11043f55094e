#pragma once
// A file's whole content, for tests that compare what glint wrote (or left alone) byte for byte;
// a fresh folder for the running test.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
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

/// @brief Everything under @p dir: each file's bytes and each folder (as "/"), by path relative
/// to @p dir; what a test compares to say a folder is as it was.
inline std::map<std::string, std::string> folderContents(const std::filesystem::path& dir) {
  std::map<std::string, std::string> all;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir)) {
    all[std::filesystem::relative(e.path(), dir).string()] =
        e.is_directory() ? std::string("/") : readFile(e.path());
  }
  return all;
}

/// @brief An empty folder named @p prefix and the running test's name in the temporary folder
/// (emptied if an earlier run left it); the test removes it when done.
inline std::filesystem::path freshTestFolder(const std::string& prefix) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() /
      (prefix + ::testing::UnitTest::GetInstance()->current_test_info()->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace glint::test
