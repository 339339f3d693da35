#pragma once
// What the fuzz targets share: the check that an error is one bounded printable line, and the
// files the readers that take a path read the input from.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>

namespace dispel::fuzz {

/// The longest error message accepted: io::one_line() keeps 400 characters, and a few messages
/// name a file (a short temporary path here) before it.
inline constexpr std::size_t kMaxMessage = 512;

/// Aborts (a finding) unless @p what is what dispel promises of an error (docs/cli.md,
/// Reliability): one line of printable ASCII, not empty, at most kMaxMessage characters.
inline void check_message(const char* what) {
  const std::string s = what;
  bool ok = !s.empty() && s.size() <= kMaxMessage;
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u >= 0x7f) ok = false;
  }
  if (!ok) {
    std::fprintf(stderr,
                 "fuzz: the error is not one printable line of at most %zu characters "
                 "(%zu characters): %s\n",
                 kMaxMessage, s.size(), s.c_str());
    std::abort();
  }
}

/// A folder of its own in the temporary directory, for the files of one process's inputs (the
/// files are rewritten for each input); removed with them when the process exits normally.
class TempFolder {
 public:
  ~TempFolder() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  TempFolder(const TempFolder&) = delete;
  TempFolder& operator=(const TempFolder&) = delete;
  TempFolder() {
    const char* tmp = std::getenv("TMPDIR");
    std::string pattern =
        std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") + "/dispel_fuzz_XXXXXX";
    if (::mkdtemp(pattern.data()) == nullptr) {
      std::perror("fuzz: mkdtemp");
      std::abort();
    }
    path_ = pattern;
  }
  const std::string& path() const { return path_; }

  /// Writes @p size bytes of @p data to the file @p name in the folder; its path.
  std::string write(const std::string& name, const std::uint8_t* data, std::size_t size) const {
    const std::string file = path_ + "/" + name;
    std::FILE* f = std::fopen(file.c_str(), "wb");
    if (f == nullptr || (size > 0 && std::fwrite(data, 1, size, f) != size) ||
        std::fclose(f) != 0) {
      std::perror(("fuzz: cannot write " + file).c_str());
      std::abort();
    }
    return file;
  }
  std::string write(const std::string& name, const std::string& text) const {
    return write(name, reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
  }

 private:
  std::string path_;
};

/// The process's temporary folder.
inline const TempFolder& temp_folder() {
  static const TempFolder folder;
  return folder;
}

}  // namespace dispel::fuzz
