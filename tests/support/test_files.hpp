#pragma once
// Paths and files for tests: the source tree's data, gtest's temporary folder.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace dispel::test {

/// A path below the source tree (DISPEL_SOURCE_DIR, set for every test by dispel_add_test).
inline std::string source_path(const std::string& relative) {
  return std::string(DISPEL_SOURCE_DIR) + "/" + relative;
}

/// This test process's own folder in gtest's temporary folder, removed when the process ends.
/// ctest runs every TEST as a process of its own, several at a time: a file name shared by two
/// tests in one folder would let one of them read or move the other's file.
inline const std::string& temp_dir() {
  // Never destroyed: the exit handler runs after the static objects are gone.
  static const std::string* const dir = [] {
    auto* d = new std::string(::testing::TempDir() + "/dispel_test_" + std::to_string(::getpid()));
    std::filesystem::create_directories(*d);
    std::atexit([] {
      std::error_code ignored;
      std::filesystem::remove_all(temp_dir(), ignored);
    });
    return d;
  }();
  return *dir;
}

/// A path in this test process's temporary folder.
inline std::string temp_path(const std::string& name) { return temp_dir() + "/" + name; }

/// A file with @p text (bytes as given) in gtest's temporary folder; its path.
inline std::string write_text(const std::string& name, const std::string& text) {
  const std::string path = temp_path(name);
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

/// The bytes of the file at @p path (empty when it cannot be read).
inline std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

inline bool exists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

}  // namespace dispel::test
