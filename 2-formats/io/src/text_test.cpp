#include "dispel/io/text.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <string>

#include "dispel/io/errors.hpp"
#include "test_files.hpp"

namespace dispel::io {
namespace {

std::string message_of(const std::string& path, const std::string& what) {
  try {
    read_regular_file(path, what);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(Quote, ShortTextIsQuotedAsItIs) { EXPECT_EQ(quote("cluster_gapm"), "'cluster_gapm'"); }

TEST(Quote, LongTextIsCutAndBinaryEscaped) {
  const std::string token(200000000, 'x');  // A 200 MB token, as in issue 16.
  const std::string q = quote(token);
  EXPECT_LT(q.size(), 120u);
  EXPECT_NE(q.find("... (200000000 bytes)"), std::string::npos) << q;
  EXPECT_EQ(quote(std::string("a\0b\n\xff", 5)), "'a\\x00b\\x0a\\xff'");
}

TEST(OneLine, ControlBytesEscapedAndLengthBounded) {
  EXPECT_EQ(one_line("two\nlines"), "two\\x0alines");
  EXPECT_EQ(one_line(std::string(1000, 'y')).size(), 403u);
  // Issue 16, fuzzing: escapes were counted as one character (a file name of 400 bytes 0xff made
  // a message of 1600 characters).
  EXPECT_EQ(one_line(std::string(1000, '\xff')).size(), 403u);
  EXPECT_EQ(one_line("ab" + std::string(1000, '\x01'), 10), "ab\\x01\\x01...");
}

TEST(ReadRegularFile, ReadsAFile) {
  const std::string path = test::write_text("c.yaml", "a: 1\n");
  EXPECT_EQ(read_regular_file(path, "configuration file"), "a: 1\n");
}

TEST(ReadRegularFile, ADirectoryIsRefusedNotReadAsEmpty) {
  const std::string m = message_of(test::temp_dir(), "configuration file");
  EXPECT_NE(m.find("the configuration file is not a regular file (a directory)"), std::string::npos)
      << m;
}

TEST(ReadRegularFile, AFifoIsRefusedWithoutOpeningIt) {
  const std::string path = test::temp_path("fifo.yaml");
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
  // Opening a FIFO without a writer would block this test forever.
  const std::string m = message_of(path, "scenario file");
  EXPECT_NE(m.find("the scenario file is not a regular file (a FIFO)"), std::string::npos) << m;
}

TEST(ReadRegularFile, AMissingFileNamesItAndTheReason) {
  const std::string m = message_of("/nonexistent/x.yaml", "scenario file");
  EXPECT_EQ(m, "/nonexistent/x.yaml: cannot open the scenario file (No such file or directory)");
}

}  // namespace
}  // namespace dispel::io
