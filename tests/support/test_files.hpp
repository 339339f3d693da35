#pragma once
// Paths and files for tests: the source tree's data, gtest's temporary folder.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>
#include <string>

namespace dispel::test {

/// A path below the source tree (DISPEL_SOURCE_DIR, set for every test by dispel_add_test).
inline std::string source_path(const std::string& relative) {
  return std::string(DISPEL_SOURCE_DIR) + "/" + relative;
}

/// A path in gtest's temporary folder.
inline std::string temp_path(const std::string& name) { return ::testing::TempDir() + "/" + name; }

/// A file with @p text (bytes as given) in gtest's temporary folder; its path.
inline std::string write_text(const std::string& name, const std::string& text) {
  const std::string path = temp_path(name);
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

inline bool exists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

}  // namespace dispel::test
