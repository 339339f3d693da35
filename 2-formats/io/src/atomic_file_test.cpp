#include "dispel/io/atomic_file.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "test_files.hpp"

namespace dispel::io {
namespace {

using test::exists;
using test::temp_path;

void write_through(AtomicFile& f, const std::string& text) {
  std::ofstream out(f.temp_path());
  out << text;
}

TEST(AtomicFile, AppearsOnlyWhenCommitted) {
  const std::string path = temp_path("atomic.txt");
  std::remove(path.c_str());
  {
    AtomicFile f(path);
    write_through(f, "half");
    EXPECT_FALSE(exists(path));
  }  // Not committed: nothing left.
  EXPECT_FALSE(exists(path));
  EXPECT_FALSE(exists(path + ".partial"));
  AtomicFile f(path);
  write_through(f, "whole");
  f.commit();
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  EXPECT_EQ(s.str(), "whole");
  EXPECT_FALSE(exists(path + ".partial"));
}

// A named pipe (like /dev/null or /dev/stdout, which `-o` may name) is written in place and stays
// a pipe: renaming a file over it would replace it (as root, /dev/null itself).
TEST(AtomicFile, APipeIsWrittenInPlaceAndStaysAPipe) {
  const std::string path = temp_path("atomic.fifo");
  std::remove(path.c_str());
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
  // The reading end, opened without blocking; what is written stays in the pipe's buffer. If the
  // file were written elsewhere, the read below finds nothing instead of waiting.
  const int reader = ::open(path.c_str(), O_RDONLY | O_NONBLOCK);
  ASSERT_GE(reader, 0);
  {
    AtomicFile f(path);
    EXPECT_EQ(f.temp_path(), path);
    write_through(f, "through the pipe");
    f.commit();
  }
  char buffer[64] = {};
  const ssize_t n = ::read(reader, buffer, sizeof buffer - 1);
  ::close(reader);
  EXPECT_EQ(std::string(buffer, n > 0 ? static_cast<std::size_t>(n) : 0), "through the pipe");
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  EXPECT_FALSE(exists(path + ".partial"));
  std::remove(path.c_str());
}

}  // namespace
}  // namespace dispel::io
