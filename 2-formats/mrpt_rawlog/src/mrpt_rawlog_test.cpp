#include "dispel/io/mrpt_rawlog.hpp"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "dispel/io/errors.hpp"
#include "test_files.hpp"

namespace dispel::io {
namespace {

using test::temp_path;
using test::write_text;

// Debian's mrpt-common: a wheelchair driving one loop of the Telecom faculty building (Malaga,
// 2006-01-21), one SICK laser with no label, odometry as actions (scripts/setup.sh installs it).
const std::string kSena = DISPEL_MRPT_SENA_RAWLOG;
constexpr double kPi = 3.14159265358979323846;

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

// The log's bytes uncompressed (Debian ships it gzip-compressed).
std::string uncompressed(const std::string& path) {
  gzFile f = gzopen(path.c_str(), "rb");
  std::string bytes;
  char buffer[4096];
  int n = 0;
  while (f != nullptr && (n = gzread(f, buffer, sizeof buffer)) > 0) {
    bytes.append(buffer, static_cast<std::size_t>(n));
  }
  if (f != nullptr) gzclose(f);
  return bytes;
}

// The InputError of opening @p path (empty when it opens).
std::string open_error(const std::string& path) {
  try {
    MrptRawlogReader reader(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return {};
}

class MrptRawlogSena : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(test::exists(kSena))
        << kSena << ": install Debian's mrpt-common (scripts/setup.sh)";
  }
};

TEST_F(MrptRawlogSena, OpensWithTheScansOdometryAndMountItHolds) {
  MrptRawlogReader reader(kSena);
  EXPECT_EQ(reader.format_name(), "MRPT rawlog");
  EXPECT_EQ(reader.path(), kSena);
  const Topics& topics = reader.topics();
  EXPECT_EQ(topics.all().size(), 3u);
  ASSERT_TRUE(topics.has("/scan", MessageKind::kLaserScan));
  ASSERT_TRUE(topics.has("/odom", MessageKind::kOdometry));
  ASSERT_TRUE(topics.has("/tf_static", MessageKind::kTransforms));
  EXPECT_EQ(topics.all().at("/scan").type, "sensor_msgs/LaserScan");
  EXPECT_EQ(topics.all().at("/odom").type, "nav_msgs/Odometry");
  EXPECT_EQ(topics.messages("/scan"), 225);
  // 224 actions, and the identity at the first scan (which comes before the first action).
  EXPECT_EQ(topics.messages("/odom"), 225);
  EXPECT_EQ(topics.messages("/tf_static"), 1);  // The mount never changes.
  EXPECT_EQ(reader.skipped_count(), 0);
  // 2006-01-21 09:03:45.713 UTC, about a minute.
  EXPECT_NEAR(reader.begin_time().seconds(), 1137834225.713, 0.001);
  EXPECT_NEAR(reader.end_time().seconds() - reader.begin_time().seconds(), 59.1, 0.1);
}

TEST_F(MrptRawlogSena, ScansFollowMrptsBeamConventionWithInvalidBeamsNaN) {
  MrptRawlogReader reader(kSena);
  std::int64_t scans = 0, invalid = 0, beams = 0;
  Stamp last;
  bool mount_before_scan = false;
  reader.read({}, [&](const RecordedMessage& m) {
    EXPECT_FALSE(m.time() < last) << "messages out of time order at " << m.time().seconds();
    last = m.time();
    if (m.kind() == MessageKind::kTransforms && scans == 0) mount_before_scan = true;
    if (m.kind() != MessageKind::kLaserScan) return;
    const auto s = m.scan();
    ASSERT_TRUE(s);
    EXPECT_FALSE(m.odometry());
    ++scans;
    EXPECT_EQ(s->header.frame_id, "laser");
    EXPECT_EQ(s->header.stamp, m.time());
    EXPECT_DOUBLE_EQ(s->scan.stamp_s, m.time().seconds());
    ASSERT_EQ(s->scan.size(), 361u);
    EXPECT_NEAR(s->scan.angle_min_rad, -kPi / 2, 1e-6);
    EXPECT_NEAR(s->scan.angle_increment_rad, kPi / 360, 1e-6);
    EXPECT_NEAR(s->angle_max, kPi / 2, 1e-6);
    EXPECT_EQ(s->scan.range_min_m, 0.0F);
    EXPECT_EQ(s->scan.range_max_m, 80.0F);
    for (std::size_t i = 0; i < s->scan.size(); ++i) {
      ++beams;
      if (!s->scan.is_valid(i)) {
        ++invalid;
        EXPECT_TRUE(std::isnan(s->scan.ranges_m[i]));
      }
    }
  });
  EXPECT_TRUE(mount_before_scan);
  EXPECT_EQ(scans, 225);
  // The first scan has 52 beams flagged invalid (MRPT's validity flags); about 14 % overall.
  EXPECT_GT(invalid, 0);
  EXPECT_LT(invalid, beams / 4);
}

TEST_F(MrptRawlogSena, OdometryMovesAboutOneLoopAndTheMountIsTheSicksPose) {
  MrptRawlogReader reader(kSena);
  std::vector<OdometryMessage> odometry;
  std::vector<TransformsMessage> mounts;
  reader.read({"/odom", "/tf_static"}, [&](const RecordedMessage& m) {
    EXPECT_NE(m.topic(), "/scan");
    if (auto o = m.odometry()) odometry.push_back(*o);
    if (auto t = m.transforms()) mounts.push_back(*t);
  });
  ASSERT_EQ(odometry.size(), 225u);
  EXPECT_EQ(odometry.front().header.frame_id, "odom");
  EXPECT_EQ(odometry.front().child_frame_id, "base_link");
  EXPECT_EQ(odometry.front().pose.x_m, 0.0);
  double path = 0.0;
  for (std::size_t k = 1; k < odometry.size(); ++k) {
    EXPECT_FALSE(odometry[k].header.stamp < odometry[k - 1].header.stamp);
    path += std::hypot(odometry[k].pose.x_m - odometry[k - 1].pose.x_m,
                       odometry[k].pose.y_m - odometry[k - 1].pose.y_m);
  }
  // The increments sum to 76.4 m in 59 s (a wheelchair at 1.3 m/s around the building).
  EXPECT_NEAR(path, 76.4, 1.0);
  ASSERT_EQ(mounts.size(), 1u);
  ASSERT_EQ(mounts[0].transforms.size(), 1u);
  const FrameTransform& mount = mounts[0].transforms[0];
  EXPECT_EQ(mount.parent, "base_link");
  EXPECT_EQ(mount.child, "laser");
  EXPECT_NEAR(mount.child_in_parent.x_m, 0.78, 1e-6);  // A float in MRPT.
  EXPECT_NEAR(mount.child_in_parent.y_m, 0.0, 1e-9);
  EXPECT_NEAR(mount.child_in_parent.yaw_rad, 0.0, 1e-9);
}

TEST_F(MrptRawlogSena, ReadingStopsWhenTheVisitorSaysSo) {
  MrptRawlogReader reader(kSena);
  int visits = 0;
  reader.read({"/scan"}, [&](const RecordedMessage&) {
    if (++visits == 3) throw StopReading();
  });
  EXPECT_EQ(visits, 3);
}

TEST_F(MrptRawlogSena, AnUncompressedCopyReadsTheSame) {
  const std::string plain = write_text("sena_plain.rawlog", uncompressed(kSena));
  MrptRawlogReader reader(plain);
  EXPECT_EQ(reader.topics().messages("/scan"), 225);
  EXPECT_EQ(reader.topics().messages("/odom"), 225);
}

// --- What is not a rawlog ---------------------------------------------------------------------

void expect_unreadable(const std::string& path, const std::string& why) {
  const std::string error = open_error(path);
  EXPECT_EQ(error.rfind(path + ": not a readable MRPT rawlog (", 0), 0u) << why << ": " << error;
  EXPECT_EQ(error.find('\n'), std::string::npos) << why << ": " << error;
}

TEST(MrptRawlogReader, MissingFileIsAnInputErrorNamingIt) {
  const std::string error = open_error("/nonexistent/sena.rawlog");
  EXPECT_EQ(error, "/nonexistent/sena.rawlog: cannot open (No such file or directory)");
}

TEST(MrptRawlogReader, EmptyTextAndGarbageFilesAreNotRawlogs) {
  expect_unreadable(write_text("empty.rawlog", ""), "empty");
  expect_unreadable(write_text("text.rawlog", "hello, I am not a rawlog\n"), "text");
  std::string garbage;
  for (int i = 0; i < 5000; ++i) garbage += static_cast<char>((i * 7919 + 13) % 251);
  expect_unreadable(write_text("garbage.rawlog", garbage), "garbage");
}

TEST_F(MrptRawlogSena, TruncatedCompressedCopiesAreRefused) {
  const std::string bytes = file_bytes(kSena);
  ASSERT_GT(bytes.size(), 100000u);
  for (const std::size_t cut :
       {std::size_t{10}, std::size_t{100}, std::size_t{5000}, bytes.size() / 2, bytes.size() - 1}) {
    const std::string path =
        write_text("cut_gz_" + std::to_string(cut) + ".rawlog", bytes.substr(0, cut));
    expect_unreadable(path, "compressed, cut at " + std::to_string(cut));
  }
}

TEST_F(MrptRawlogSena, TruncatedOrCorruptUncompressedCopiesAreRefused) {
  const std::string bytes = uncompressed(kSena);
  ASSERT_GT(bytes.size(), 400000u);
  for (const std::size_t cut :
       {std::size_t{1}, std::size_t{3}, std::size_t{250000}, bytes.size() - 1}) {
    const std::string path =
        write_text("cut_plain_" + std::to_string(cut) + ".rawlog", bytes.substr(0, cut));
    expect_unreadable(path, "uncompressed, cut at " + std::to_string(cut));
  }
}

// MRPT takes a short read for a whole one and keeps what the rest of the field held (a matrix's
// columns cut after 2 of their 4 bytes took 2 from the stack: a SIGSEGV, from the fuzzer). A log
// cut inside a field is refused as cut: inside the class name of the first scan's mount matrix
// (2 of its 8 letters: MRPT said "Cannot read object class name from stream!"), inside its
// columns, and inside the first sensory frame's count of observations.
TEST_F(MrptRawlogSena, ALogCutInsideAFieldIsRefusedAsCut) {
  const std::string bytes = uncompressed(kSena);
  ASSERT_EQ(bytes.substr(62, 18), std::string("\x88"
                                              "CMatrixD\x00\x04\x00\x00\x00\x04\x00\x00\x00",
                                              18));
  for (const std::size_t cut : {std::size_t{65}, std::size_t{78}, std::size_t{17}}) {
    const std::string path =
        write_text("cut_in_field_" + std::to_string(cut) + ".rawlog", bytes.substr(0, cut));
    EXPECT_EQ(open_error(path),
              path +
                  ": not a readable MRPT rawlog ((EOF?) Cannot read requested number of bytes "
                  "from stream)")
        << cut;
  }
}

// Bytes changed in a compressed log fail gzip's check. (An uncompressed log has no check: a
// changed range is read as that range.)
TEST_F(MrptRawlogSena, CorruptCompressedCopyIsRefused) {
  std::string bytes = file_bytes(kSena);
  for (std::size_t i = bytes.size() / 2; i < bytes.size() / 2 + 64; ++i) bytes[i] = '\xA5';
  expect_unreadable(write_text("corrupt.rawlog", bytes), "corrupt");
}

// A container's count is checked against the bytes left before MRPT reads it: MRPT sizes the
// container first (a CSensoryFrame of 0x746e0001 observations: a deque of 31 GiB, made page by
// page, from the fuzzer). The first sensory frame's count, then the first action collection's
// (after 2049 bytes), set past the end of the log.
TEST_F(MrptRawlogSena, ContainerCountsBeyondTheLogAreRefusedBeforeMrptReadsThem) {
  const std::string bytes = uncompressed(kSena);
  // Each object's header: 0x80 | the name's length, the name, the version; then the count.
  ASSERT_EQ(bytes.substr(0, 19), std::string("\x8D"
                                             "CSensoryFrame\x02\x01\x00\x00\x00",
                                             19));
  ASSERT_EQ(bytes.substr(2049, 23), std::string("\x91"
                                                "CActionCollection\x00\x01\x00\x00\x00",
                                                23));
  std::string frame = bytes;
  frame.replace(15, 4, std::string("\x01\x00\x6e\x74", 4));
  EXPECT_EQ(open_error(write_text("frame_count.rawlog", frame)),
            temp_path("frame_count.rawlog") +
                ": not a readable MRPT rawlog (a CSensoryFrame of 1953366017 observations in the " +
                std::to_string(bytes.size() - 19) + " bytes left)");
  std::string actions = bytes;
  actions.replace(2049 + 19, 4, "\xff\xff\xff\xff");
  EXPECT_EQ(open_error(write_text("action_count.rawlog", actions)),
            temp_path("action_count.rawlog") +
                ": not a readable MRPT rawlog (corrupt after 1 objects: a CActionCollection of "
                "4294967295 actions in the " +
                std::to_string(bytes.size() - 2049 - 23) + " bytes left)");
  // A count the log can hold is MRPT's to read (here the frame's one observation).
  EXPECT_EQ(open_error(write_text("fine.rawlog", bytes)), "");
}

// MRPT makes a matrix's storage before it reads its values and writes through the null pointer
// it gets when the allocation fails (SIGSEGV). The first CMatrixD of the log (the scan's mount
// pose, 4 x 4 doubles after the header at byte 62) stated as 262144 x 1291845636.
TEST_F(MrptRawlogSena, MatricesLargerThanTheLogAreRefusedBeforeMrptReadsThem) {
  const std::string bytes = uncompressed(kSena);
  ASSERT_EQ(bytes.substr(62, 18), std::string("\x88"
                                              "CMatrixD\x00\x04\x00\x00\x00\x04\x00\x00\x00",
                                              18));
  std::string matrix = bytes;
  matrix.replace(72, 8, std::string("\x00\x00\x04\x00\x04\x00\x00\x4d", 8));
  EXPECT_EQ(open_error(write_text("matrix.rawlog", matrix)),
            temp_path("matrix.rawlog") +
                ": not a readable MRPT rawlog (a CMatrixD of 262144 x 1291845636 values at byte "
                "62, more than the " +
                std::to_string(bytes.size() - 80) + " bytes after it)");
  // The same matrix under a stored name of 12 bytes, "CMatrixD" and 4 NULs: MRPT reads the name
  // up to its first NUL and the matrix after the 12 (the fuzzer: a 40-byte name, a SIGSEGV the
  // check above missed while it took the name's length for the class's).
  std::string padded = bytes;
  padded[62] = '\x8c';
  padded.insert(71, std::string(4, '\0'));
  padded.replace(76, 8, std::string("\x00\x00\x04\x00\x04\x00\x00\x4d", 8));
  EXPECT_EQ(open_error(write_text("matrix_padded_name.rawlog", padded)),
            temp_path("matrix_padded_name.rawlog") +
                ": not a readable MRPT rawlog (a CMatrixD of 262144 x 1291845636 values at byte "
                "62, more than the " +
                std::to_string(padded.size() - 84) + " bytes after it)");
  // 4 x 5 doubles: more than the bytes after it only at the log's end, so MRPT reads it (and
  // finds the log corrupt).
  matrix.replace(72, 8, std::string("\x04\x00\x00\x00\x05\x00\x00\x00", 8));
  const std::string error = open_error(write_text("matrix_4x5.rawlog", matrix));
  EXPECT_NE(error, "");
  EXPECT_EQ(error.find("CMatrixD of"), std::string::npos) << error;
}

// The first action (a CActionRobotMovement2D of version 6 at byte 2072: the estimation method at
// 2096, the raw increment, a CPose2D, at 2100, the motion model at 2134, its particles at 2162).
// Another method than odometry makes MRPT read the CPose2D as the pose change, a CPosePDF: it
// gets null and copies through it (SIGSEGV). Thrun's model with 2^32 - 1 particles makes MRPT
// draw them all.
TEST_F(MrptRawlogSena, MovementsMrptCannotReadAreRefusedBeforeMrptReadsThem) {
  const std::string bytes = uncompressed(kSena);
  ASSERT_EQ(bytes.substr(2072, 24),
            "\x96"
            "CActionRobotMovement2D\x06");
  ASSERT_EQ(bytes.substr(2100, 9),
            "\x87"
            "CPose2D\x01");
  ASSERT_EQ(bytes.substr(2162, 4), std::string("\x2c\x01\x00\x00", 4));  // 300 particles.
  std::string method = bytes;
  method[2096] = '\x01';  // Scan matching.
  EXPECT_EQ(open_error(write_text("method.rawlog", method)),
            temp_path("method.rawlog") +
                ": not a readable MRPT rawlog (a CActionRobotMovement2D at byte 2072 of estimation "
                "method 1 whose pose change is 'CPose2D', not a CPosePDF MRPT can make)");
  std::string thrun = bytes;
  thrun[2134] = '\x01';  // Thrun's model, with its 300 particles: read.
  EXPECT_EQ(open_error(write_text("thrun_300.rawlog", thrun)), "");
  thrun.replace(2162, 4, "\xff\xff\xff\xff");
  EXPECT_EQ(open_error(write_text("thrun.rawlog", thrun)),
            temp_path("thrun.rawlog") +
                ": not a readable MRPT rawlog (a CActionRobotMovement2D at byte 2072 asking for "
                "4294967295 particles of Thrun's motion model (more than 100000))");
}

}  // namespace
}  // namespace dispel::io
