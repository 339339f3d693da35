#include "dispel/io/atomic_file.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace dispel::io {

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)), temp_(path_ + ".partial") {
  std::remove(temp_.c_str());  // A leftover of an earlier run that was killed outright.
}

AtomicFile::~AtomicFile() {
  if (!committed_) std::remove(temp_.c_str());
}

void AtomicFile::commit() {
  if (std::rename(temp_.c_str(), path_.c_str()) != 0) {
    throw std::runtime_error("cannot move " + temp_ + " to " + path_ + ": " + std::strerror(errno));
  }
  committed_ = true;
}

}  // namespace dispel::io
