#include "dispel/io/atomic_file.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "dispel/io/errors.hpp"

namespace dispel::io {
namespace {

// /dev/null, /dev/stdout, a named pipe: written in place. Renaming a file over them would
// replace the device or pipe with a regular file (as root, /dev/null itself).
bool is_special_file(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode);
}

}  // namespace

AtomicFile::AtomicFile(std::string path)
    : path_(std::move(path)), temp_(path_ + ".partial"), direct_(is_special_file(path_)) {
  if (direct_) {
    temp_ = path_;
    return;
  }
  std::remove(temp_.c_str());  // A leftover of an earlier run that was killed outright.
}

AtomicFile::~AtomicFile() {
  if (!committed_ && !direct_) std::remove(temp_.c_str());
}

void AtomicFile::commit() {
  if (!direct_ && std::rename(temp_.c_str(), path_.c_str()) != 0) {
    throw OutputError("cannot move " + temp_ + " to " + path_ + ": " + std::strerror(errno));
  }
  committed_ = true;
}

void write_file_atomically(const std::string& path, const std::string& text) {
  AtomicFile file(path);
  errno = 0;
  std::FILE* f = std::fopen(file.temp_path().c_str(), "w");
  if (f == nullptr) throw OutputError(path + ": cannot write (" + std::strerror(errno) + ")");
  const bool written = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  const bool flushed = written && std::fflush(f) == 0;
  const int error = errno;
  const bool closed = std::fclose(f) == 0;
  if (!written || !flushed || !closed) {
    throw OutputError(path + ": cannot write (" + std::strerror(error != 0 ? error : errno) + ")");
  }
  file.commit();
}

}  // namespace dispel::io
