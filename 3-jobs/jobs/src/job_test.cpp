// jobs::check_files: outputs never destroy inputs or each other; checked before any work.
#include "dispel/jobs/job.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <string>

#include "test_files.hpp"

namespace dispel::jobs {
namespace {

using test::temp_dir;
using test::temp_path;
using test::write_text;

std::string error_of(const std::vector<FileArgument>& inputs,
                     const std::vector<FileArgument>& outputs) {
  try {
    check_files(inputs, outputs);
  } catch (const JobError& e) {
    return e.what();
  }
  return "";
}

TEST(CheckFiles, AnOutputThatIsAnInputIsRefusedWhateverItsSpelling) {
  const std::string log = write_text("in.log", "FLASER 2 1 1 0 0 0 0 0 0 1 h 1\n");
  const std::string spelled =
      temp_dir() + "/./../" + std::string(temp_dir()).substr(temp_dir().rfind('/') + 1) + "/in.log";
  const std::string m = error_of({{"", log}}, {{"-o", spelled}});
  EXPECT_NE(m.find("is the same file as the input '" + log + "'; the input would be overwritten"),
            std::string::npos)
      << m;
  // A hard link is the same file too.
  const std::string link = temp_path("link.log");
  ASSERT_EQ(::link(log.c_str(), link.c_str()), 0);
  EXPECT_NE(error_of({{"--wheels-csv", log}}, {{"-o", link}}).find("same file as the input"),
            std::string::npos);
}

TEST(CheckFiles, TwoOutputsNamingOneFileAreRefusedBeforeEitherExists) {
  const std::string a = temp_path("o.bag");
  const std::string m = error_of({}, {{"-o", a}, {"--stats", temp_dir() + "/./o.bag"}});
  EXPECT_NE(m.find("--stats '" + temp_dir() + "/./o.bag' and -o '" + a + "' are the same file"),
            std::string::npos)
      << m;
  EXPECT_EQ(error_of({}, {{"-o", a}, {"--stats", temp_path("s.json")}}), "");
  // A device is written in place: two outputs to /dev/null are fine.
  EXPECT_EQ(error_of({}, {{"-o", "/dev/null"}, {"--stats", "/dev/null"}}), "");
}

TEST(CheckFiles, AnOutputInAMissingDirectoryIsRefused) {
  const std::string m = error_of({}, {{"--stats", temp_path("nodir/s.json")}});
  EXPECT_NE(m.find("--stats '" + temp_path("nodir/s.json") + "': the directory '" +
                   temp_path("nodir") + "' does not exist"),
            std::string::npos)
      << m;
  EXPECT_NE(error_of({}, {{"-o", temp_dir()}}).find("is a directory"), std::string::npos);
}

TEST(CheckFiles, AnInputThatIsADirectoryOrAFifoIsRefusedByItsType) {
  EXPECT_EQ(error_of({{"--config", temp_dir()}}, {}),
            "--config '" + temp_dir() + "': not a regular file (a directory)");
  const std::string fifo = temp_path("fifo.yaml");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(error_of({{"--config", fifo}}, {}),
            "--config '" + fifo + "': not a regular file (a FIFO)");
  // A missing input is left to the reader, which says "No such file" in its own words.
  EXPECT_EQ(error_of({{"", temp_path("missing.bag")}}, {}), "");
}

}  // namespace
}  // namespace dispel::jobs
