// Messages written with the real ROS bag library come back unchanged, with every compression.
#include "dispel/io/ros1_bag.hpp"

#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/JointState.h>
#include <sensor_msgs/LaserScan.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <tf2_msgs/TFMessage.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "dispel/io/errors.hpp"
#include "dispel/io/ros1_messages.hpp"

namespace dispel::io {
namespace {

struct Recorded {
  sensor_msgs::LaserScan scan;
  nav_msgs::Odometry odom;
  sensor_msgs::Imu imu;
  sensor_msgs::JointState wheels;
  tf2_msgs::TFMessage tf;
};

Recorded sample(int k) {
  Recorded r;
  LaserScan s;
  s.stamp_s = 10.0 + 0.05 * k;
  s.angle_min_rad = -2.0;
  s.angle_increment_rad = 0.01;
  s.range_min_m = 0.05F;
  s.range_max_m = 30.0F;
  for (int i = 0; i < 400; ++i)
    s.ranges_m.push_back(1.0F + 0.01F * static_cast<float>((i + k) % 50));
  s.ranges_m[3] = std::numeric_limits<float>::quiet_NaN();
  r.scan = to_ros(s, "laser");
  r.odom.header.stamp = to_ros_time(s.stamp_s);
  r.odom.header.frame_id = "odom";
  r.odom.child_frame_id = "base_link";
  r.odom.pose.pose.position.x = 0.1 * k;
  r.odom.pose.pose.orientation = quaternion_from_yaw(0.02 * k);
  r.odom.twist.twist.linear.x = 0.5;
  r.imu.header = r.odom.header;
  r.imu.angular_velocity.z = 0.3;
  r.imu.linear_acceleration.x = 0.01 * k;
  r.wheels.header = r.odom.header;
  r.wheels.name = {"left", "right"};
  r.wheels.velocity = {0.4, 0.6};
  geometry_msgs::TransformStamped t;
  t.header.stamp = r.odom.header.stamp;
  t.header.frame_id = "base_link";
  t.child_frame_id = "laser";
  t.transform.translation.x = 0.3;
  t.transform.rotation = quaternion_from_yaw(0.0);
  r.tf.transforms = {t};
  return r;
}

class BagRoundTrip : public ::testing::TestWithParam<rosbag::compression::CompressionType> {};

// Writes samples 0..n-1 of every topic, the first TF on /tf_static.
void write_samples(rosbag::Bag& bag, int n) {
  for (int k = 0; k < n; ++k) {
    const Recorded r = sample(k);
    const ros::Time t = r.scan.header.stamp;
    bag.write("/scan", t, r.scan);
    bag.write("/odom", t, r.odom);
    bag.write("/imu", t, r.imu);
    bag.write("/wheels", t, r.wheels);
    bag.write(k == 0 ? "/tf_static" : "/tf", t, r.tf);
  }
}

TEST_P(BagRoundTrip, EveryMessageComesBackUnchanged) {
  const std::string path =
      ::testing::TempDir() + "/round_trip_" + std::to_string(static_cast<int>(GetParam())) + ".bag";
  {
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    bag.setCompression(GetParam());
    write_samples(bag, 50);
  }
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  rosbag::View view(bag);
  EXPECT_EQ(view.size(), 250u);
  std::map<std::string, int> seen;
  for (const rosbag::MessageInstance& m : view) {
    const int k = seen[m.getTopic() == "/tf_static" ? "/tf" : m.getTopic()]++;
    Recorded r = sample(k);
    if (m.getTopic() == "/scan") {
      const auto s = m.instantiate<sensor_msgs::LaserScan>();
      ASSERT_TRUE(s);
      EXPECT_EQ(s->header.stamp, r.scan.header.stamp);
      EXPECT_EQ(s->header.frame_id, "laser");
      ASSERT_EQ(s->ranges.size(), r.scan.ranges.size());
      EXPECT_TRUE(std::isnan(s->ranges[3]));
      s->ranges[3] = r.scan.ranges[3] = 0.0F;
      EXPECT_EQ(s->ranges, r.scan.ranges);
      EXPECT_EQ(from_ros(*s).angle_increment_rad, from_ros(r.scan).angle_increment_rad);
    } else if (m.getTopic() == "/odom") {
      const auto o = m.instantiate<nav_msgs::Odometry>();
      ASSERT_TRUE(o);
      EXPECT_EQ(o->child_frame_id, "base_link");
      EXPECT_NEAR(from_ros(o->pose.pose).yaw_rad, 0.02 * k, 1e-12);
      EXPECT_EQ(o->twist.twist.linear.x, 0.5);
    } else if (m.getTopic() == "/imu") {
      const auto i = m.instantiate<sensor_msgs::Imu>();
      ASSERT_TRUE(i);
      EXPECT_EQ(i->angular_velocity.z, 0.3);
      EXPECT_EQ(i->linear_acceleration.x, r.imu.linear_acceleration.x);
    } else if (m.getTopic() == "/wheels") {
      const auto w = m.instantiate<sensor_msgs::JointState>();
      ASSERT_TRUE(w);
      EXPECT_EQ(w->name, r.wheels.name);
      EXPECT_EQ(w->velocity, r.wheels.velocity);
    } else {
      const auto tf = m.instantiate<tf2_msgs::TFMessage>();
      ASSERT_TRUE(tf);
      ASSERT_EQ(tf->transforms.size(), 1u);
      EXPECT_EQ(tf->transforms[0].child_frame_id, "laser");
      EXPECT_EQ(from_ros(tf->transforms[0].transform).x_m, 0.3);
    }
  }
  EXPECT_EQ(seen["/scan"], 50);
  EXPECT_EQ(seen["/tf"], 50);
  std::remove(path.c_str());
}

INSTANTIATE_TEST_SUITE_P(Compressions, BagRoundTrip,
                         ::testing::Values(rosbag::compression::Uncompressed,
                                           rosbag::compression::BZ2, rosbag::compression::LZ4));

// --- Messages of another format, copied decoded (write_decoded) ------------------------------

// A message of a format that is not a ROS 1 bag (as an MRPT rawlog's are), decoded already.
class ForeignMessage final : public RecordedMessage {
 public:
  ForeignMessage(std::string topic, MessageKind kind, Stamp time)
      : topic_(std::move(topic)), kind_(kind), time_(time) {}
  std::optional<ScanMessage> scan_message;
  std::optional<OdometryMessage> odometry_message;
  std::optional<TransformsMessage> transforms_message;

  const std::string& topic() const override { return topic_; }
  MessageKind kind() const override { return kind_; }
  Stamp time() const override { return time_; }
  std::optional<ScanMessage> scan() const override { return scan_message; }
  std::optional<OdometryMessage> odometry() const override { return odometry_message; }
  std::optional<TransformsMessage> transforms() const override { return transforms_message; }
  std::optional<JointStateMessage> joint_state() const override { return std::nullopt; }
  std::optional<ImuMessage> imu() const override { return std::nullopt; }
  std::optional<NavSatFixMessage> nav_sat_fix() const override { return std::nullopt; }

 private:
  std::string topic_;
  MessageKind kind_;
  Stamp time_;
};

TEST(Ros1BagWriter, CopiesAnotherFormatsMessagesDecoded) {
  const std::string path = ::testing::TempDir() + "/foreign_copied.bag";
  const Recorded r = sample(3);
  {
    Ros1BagWriter writer(path, BagCompression::kNone);
    ForeignMessage scan("/front", MessageKind::kLaserScan, Stamp{20, 500});
    scan.scan_message = to_message(r.scan);
    ForeignMessage odom("/odom", MessageKind::kOdometry, Stamp{21, 0});
    odom.odometry_message = to_message(r.odom);
    ForeignMessage mount("/tf_static", MessageKind::kTransforms, Stamp{19, 0});
    mount.transforms_message = to_message(r.tf);
    writer.copy(mount);
    writer.copy(scan);
    writer.copy(odom);
    EXPECT_EQ(writer.messages_written(), 3);
    writer.finish();
  }
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  std::map<std::string, int> seen;
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    ++seen[m.getTopic()];
    if (m.getTopic() == "/front") {
      const auto s = m.instantiate<sensor_msgs::LaserScan>();
      ASSERT_TRUE(s);
      EXPECT_EQ(m.getTime(), ros::Time(20, 500));  // The message's receive time.
      EXPECT_EQ(s->ranges.size(), r.scan.ranges.size());
      EXPECT_EQ(s->ranges[10], r.scan.ranges[10]);
    } else if (m.getTopic() == "/odom") {
      const auto o = m.instantiate<nav_msgs::Odometry>();
      ASSERT_TRUE(o);
      EXPECT_EQ(o->child_frame_id, "base_link");
      EXPECT_NEAR(o->pose.pose.position.x, 0.3, 1e-12);
    } else {
      const auto tf = m.instantiate<tf2_msgs::TFMessage>();
      ASSERT_TRUE(tf);
      ASSERT_EQ(tf->transforms.size(), 1u);
      EXPECT_EQ(tf->transforms[0].child_frame_id, "laser");
    }
  }
  EXPECT_EQ(seen.size(), 3u);
  std::remove(path.c_str());
}

TEST(Ros1BagWriter, RefusesAnotherFormatsMessageItCannotDecodeNamingTheTopic) {
  const std::string path = ::testing::TempDir() + "/foreign_refused.bag";
  Ros1BagWriter writer(path, BagCompression::kNone);
  const ForeignMessage other("/camera", MessageKind::kOther, Stamp{1, 0});
  try {
    writer.copy(other);
    ADD_FAILURE() << "copied";
  } catch (const OutputError& e) {
    EXPECT_STREQ(e.what(),
                 (path + ": /camera: cannot copy a message of type other from another format "
                         "(only the recording model's types can be converted)")
                     .c_str());
  }
  EXPECT_EQ(writer.messages_written(), 0);
}

// Writes @p scans scans of sample() to @p path and finishes; the error's message, or "" when
// the bag was written.
std::string write_scans(const std::string& path, int scans, BagCompression compression) {
  try {
    Ros1BagWriter writer(path, compression);
    for (int k = 0; k < scans; ++k) {
      writer.write("/scan", Stamp{10 + k, 0}, to_message(sample(k).scan));
    }
    writer.finish();
  } catch (const OutputError& e) {
    return e.what();
  }
  return "";
}

bool exists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

// Issue 16: a write error (a full disk) used to abort the program: rosbag::Bag's destructor
// closed the bag again and threw while the first error unwound.
TEST(Ros1BagWriter, AFullDiskIsAnErrorNamingTheFileNotAnAbort) {
  for (const BagCompression c :
       {BagCompression::kNone, BagCompression::kBz2, BagCompression::kLz4}) {
    const std::string m = write_scans("/dev/full", 200, c);
    EXPECT_NE(m.find("/dev/full: cannot write"), std::string::npos) << m;
    EXPECT_NE(m.find("No space left on device"), std::string::npos) << m;
  }
}

// The same under a file-size limit (ulimit -f), in a child process: the write fails with EFBIG
// (SIGXFSZ ignored, as dispel does), the error names the file, and no partial file is left.
TEST(Ros1BagWriter, AFileSizeLimitIsAnErrorAndLeavesNoPartialFile) {
  const std::string path = ::testing::TempDir() + "/size_limited.bag";
  std::remove(path.c_str());
  std::remove((path + ".partial").c_str());
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{200000, 200000};
    ::setrlimit(RLIMIT_FSIZE, &limit);
    const std::string m = write_scans(path, 400, BagCompression::kNone);
    const bool named = m.find(path + ": cannot write the bag") != std::string::npos &&
                       m.find("File too large") != std::string::npos;
    std::_Exit(m.empty() ? 2 : named ? 0 : 3);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status)) << "the child ended by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 0) << "2: written despite the limit; 3: another message";
  EXPECT_FALSE(exists(path));
  EXPECT_FALSE(exists(path + ".partial"));
}

// Issue 16: time 0 failed deep in the bag library, 5e9 s was written wrapped (705032704.5 s),
// 1e300 s became 0. Each is refused before it reaches the bag, and the bag stays writable.
TEST(Ros1BagWriter, RefusesTimesABagCannotHold) {
  const std::string path = ::testing::TempDir() + "/times.bag";
  Ros1BagWriter writer(path, BagCompression::kNone);
  const ScanMessage scan = to_message(sample(0).scan);
  for (const double t : {0.0, -1.0, 5e9, 1e300, std::nan("")}) {
    try {
      writer.write("/scan", Stamp::from_seconds(t), scan);
      ADD_FAILURE() << "wrote a scan at " << t << " s";
    } catch (const OutputError& e) {
      EXPECT_NE(std::string(e.what()).find("cannot write /scan at"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("a ROS 1 bag holds times from 1 ns to 4294967295 s"),
                std::string::npos)
          << e.what();
    }
  }
  writer.write("/scan", Stamp{4294967295, 0}, scan);
  writer.write("/scan", Stamp{0, 1}, scan);
  writer.finish();
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  EXPECT_EQ(rosbag::View(bag).size(), 2u);
  std::remove(path.c_str());
}

// --- Corrupt bags (issue 16): checked before the bag library reads them -----------------------

std::string slurp(const std::string& path) {
  std::string bytes;
  if (std::FILE* f = std::fopen(path.c_str(), "rb")) {
    char buffer[65536];
    for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, f)) > 0;) bytes.append(buffer, n);
    std::fclose(f);
  }
  return bytes;
}

void spill(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

// A bag of 40 steps of five topics in chunks of about 20 kB (several chunks, each followed by
// its index data); its bytes.
std::string small_bag(rosbag::compression::CompressionType compression) {
  const std::string path = ::testing::TempDir() + "/small_" + std::to_string(::getpid()) + "_" +
                           std::to_string(static_cast<int>(compression)) + ".bag";
  {
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    bag.setCompression(compression);
    bag.setChunkThreshold(20000);
    write_samples(bag, 40);
  }
  std::string bytes = slurp(path);
  std::remove(path.c_str());
  return bytes;
}

std::uint32_t u32_at(const std::string& b, std::size_t pos) {
  std::uint32_t v = 0;
  std::memcpy(&v, b.data() + pos, 4);
  return v;
}

struct RecordAt {
  std::size_t pos, data_len_pos;
  char op;
};

// The file's records (not a chunk's), from a well-formed bag.
std::vector<RecordAt> records_of(const std::string& b) {
  std::vector<RecordAt> out;
  for (std::size_t pos = 13; pos + 8 <= b.size();) {
    const std::uint32_t header_len = u32_at(b, pos);
    const std::string header = b.substr(pos + 4, header_len);
    const std::size_t op = header.find("op=");
    out.push_back({pos, pos + 4 + header_len, header.at(op + 3)});
    pos += 8 + header_len + u32_at(b, pos + 4 + header_len);
  }
  return out;
}

RecordAt first(const std::string& b, char op) {
  for (const RecordAt& r : records_of(b))
    if (r.op == op) return r;
  throw std::runtime_error("no such record");
}

// What reading the bag at @p path says: "" if it reads whole.
std::string read_error(const std::string& path) {
  try {
    Ros1BagReader reader(path);
    reader.read({}, [](const RecordedMessage& m) { (void)m.scan(); });
    return "";
  } catch (const InputError& e) {
    return e.what();
  }
}

// Issue 16, item 3: 8 bytes of the first index data record set to 0x7f crashed dispel (SIGSEGV
// in rosbag::Bag::readHeaderFromBuffer), or were read as a bag that is fine.
TEST(Ros1BagReader, RefusesACorruptIndexNamingTheRecord) {
  const std::string good = small_bag(rosbag::compression::Uncompressed);
  const RecordAt index = first(good, 0x04);
  const std::string path = ::testing::TempDir() + "/corrupt_index_" + std::to_string(::getpid());
  const std::string size = std::to_string(good.size());
  const std::string at = path + ": corrupt bag: record at byte " + std::to_string(index.pos);

  std::string bad = good;  // Its length and first entry's time.
  std::memset(&bad[index.data_len_pos], 0x7f, 8);
  spill(path, bad);
  EXPECT_EQ(read_error(path),
            at + ": data of 2139062143 bytes runs past the end (the file has " + size + " bytes)");

  bad = good;  // Its first entry's time and offset (the crash).
  std::memset(&bad[index.data_len_pos + 8], 0x7f, 8);
  spill(path, bad);
  EXPECT_EQ(read_error(path), at + ": index entry 0 points at byte 2139062143 of its chunk, not "
                                   "at a message of connection 0");

  bad = good;  // An offset inside the chunk, into a message's middle.
  bad[index.data_len_pos + 12] = static_cast<char>(bad[index.data_len_pos + 12] + 8);
  spill(path, bad);
  EXPECT_NE(read_error(path).find(at + ": index entry 0 points at byte "), std::string::npos);

  spill(path, good);
  EXPECT_EQ(read_error(path), "");
  std::remove(path.c_str());
}

// Issue 16, item 3: a length field of 0x7fffffff made the bag library allocate without bound.
TEST(Ros1BagReader, RefusesLengthsThatDoNotFit) {
  const std::string good = small_bag(rosbag::compression::Uncompressed);
  const std::string path = ::testing::TempDir() + "/corrupt_length_" + std::to_string(::getpid());
  const std::string size = std::to_string(good.size());
  const RecordAt chunk = first(good, 0x05);
  const auto set = [&](std::size_t pos) {
    std::string bad = good;
    const std::uint32_t v = 0x7fffffff;
    std::memcpy(&bad[pos], &v, 4);
    spill(path, bad);
    return read_error(path);
  };
  const std::string at = path + ": corrupt bag: record at byte " + std::to_string(chunk.pos);
  EXPECT_EQ(set(chunk.pos), at + ": a header of 2147483647 bytes runs past the end (the file has " +
                                size + " bytes)");
  EXPECT_EQ(set(chunk.data_len_pos),
            at + ": data of 2147483647 bytes runs past the end (the file has " + size + " bytes)");
  // The chunk's uncompressed size: its header's last field (size=<4 bytes>).
  EXPECT_EQ(set(chunk.data_len_pos - 4),
            at + ": chunk of 2147483647 bytes uncompressed (a chunk is at most 1 GiB; rosbag "
                 "writes 768 KiB)");
  // A header field's length (the chunk's first field).
  EXPECT_EQ(set(chunk.pos + 4), at + ": header: a field of 2147483647 bytes is longer than the " +
                                    std::to_string(u32_at(good, chunk.pos) - 4) +
                                    " bytes left of it");
  // The bag header's index position (index_pos=<8 bytes>, its first field here).
  const std::size_t index_pos = good.find("index_pos=") + 10;
  ASSERT_LT(index_pos, 100u);
  EXPECT_EQ(set(index_pos), path +
                                ": corrupt bag: record at byte 13: the index at byte 2147483647 "
                                "is outside the file's records (4117 to " +
                                size + ")");
  std::remove(path.c_str());
}

// Issue 16, fuzzing: an array length of 2^32 - 1 inside a message made the ROS deserialiser
// allocate 16 GiB or more (it sizes an array by its length field before it checks that the
// message holds it). The lengths are checked first: one line naming the message.
TEST(Ros1BagReader, RefusesMessageArraysLongerThanTheMessage) {
  const std::string path =
      ::testing::TempDir() + "/corrupt_array_" + std::to_string(::getpid()) + ".bag";
  sensor_msgs::LaserScan scan;
  scan.header.stamp = ros::Time(10, 0);
  scan.header.frame_id = "laser";
  scan.ranges.assign(7, 1.5F);
  sensor_msgs::JointState wheels;
  wheels.header.stamp = ros::Time(10, 0);
  wheels.name = {"left", "right"};
  wheels.velocity = {0.25, 0.75};
  {
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    bag.write("/scan", ros::Time(10, 0), scan);
    bag.write("/wheels", ros::Time(10, 0), wheels);
  }
  const std::string good = slurp(path);
  const auto read_all = [&] {
    try {
      Ros1BagReader reader(path);
      reader.read({}, [](const RecordedMessage& m) {
        (void)m.scan();
        (void)m.joint_state();
      });
      return std::string();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
  };
  const auto with_huge_length = [&](const std::string& pattern) {
    std::string bad = good;
    const auto at = bad.find(pattern);
    EXPECT_NE(at, std::string::npos);
    if (at == std::string::npos) return std::string("pattern not found");
    const std::uint32_t huge = 0xffffffff;
    std::memcpy(&bad[at], &huge, 4);
    spill(path, bad);
    return read_all();
  };
  EXPECT_EQ(read_all(), "");
  // The scan's ranges: 7, then 1.5F.
  const std::string ranges = with_huge_length(std::string("\x07\0\0\0\0\0\xc0\x3f", 8));
  EXPECT_NE(ranges.find(path + ": corrupt bag: message at 10.000000000 s on '/scan' "
                               "(sensor_msgs/LaserScan): an array of 4294967295 4-byte values "
                               "(ranges) runs past the end of the message ("),
            std::string::npos)
      << ranges;
  // The wheels' velocities: 2, then 0.25.
  const std::string velocity = with_huge_length(std::string("\x02\0\0\0\0\0\0\0\0\0\xd0\x3f", 12));
  EXPECT_NE(velocity.find("on '/wheels' (sensor_msgs/JointState): an array of 4294967295 8-byte "
                          "values (velocity) runs past the end of the message ("),
            std::string::npos)
      << velocity;
  // The joints' names: 2, then "left".
  const std::string names = with_huge_length(std::string("\x02\0\0\0\x04\0\0\0left", 12));
  EXPECT_NE(names.find("an array of 4294967295 joint names (at least 4 bytes each) runs past the "
                       "end of the message ("),
            std::string::npos)
      << names;
  std::remove(path.c_str());
}

// Issue 16, fuzzing: the bag library takes any first line that sscanf reads as "#ROS%s V%d.%d"
// for the version line ("#ROSBAGZZZ V2.0"); the check wanted "#ROSBAG V2.0" exactly, left such a
// bag to the bag library unchecked, and it read past a buffer (a header field's length).
TEST(Ros1BagReader, ChecksEveryBagTheBagLibraryReadsAsFormat2) {
  const std::string good = small_bag(rosbag::compression::Uncompressed);
  const std::string path = ::testing::TempDir() + "/version_" + std::to_string(::getpid());
  spill(path, "#ROSBAGZZZ V2.0\n" + good.substr(13));  // Every offset now 3 bytes off.
  const std::string error = read_error(path);
  EXPECT_EQ(error.rfind(path + ": corrupt bag: record at byte 16: the index at byte ", 0), 0u)
      << error;
  spill(path, "#ROSBAGZZZ V2.0\n" + good.substr(13, 4) + std::string("\xff\xff", 2));
  EXPECT_NE(read_error(path).find(path + ": corrupt bag: record at byte 16: "), std::string::npos)
      << read_error(path);
  spill(path, "#ROSBAG V1.2\n");  // Format 1.2 by the same reading.
  EXPECT_NE(read_error(path).find("format 1.2"), std::string::npos) << read_error(path);
  std::remove(path.c_str());
}

// An encrypted bag (its bag header names an encryptor) is refused before the bag library would
// run GnuPG for its key.
TEST(Ros1BagReader, RefusesAnEncryptedBag) {
  const std::string good = small_bag(rosbag::compression::Uncompressed);
  const std::string path = ::testing::TempDir() + "/encrypted_" + std::to_string(::getpid());
  // The field goes at the end of the bag header; its padding shrinks by as much: every offset
  // stays.
  const std::string field = "encryptor=rosbag/AesCbcEncryptor";
  std::string length(4, '\0');
  const auto n = static_cast<std::uint32_t>(field.size());
  std::memcpy(&length[0], &n, 4);
  const std::uint32_t header_len = u32_at(good, 13);
  const std::uint32_t data_len = u32_at(good, 17 + header_len);
  std::string bad = good.substr(0, 13);
  const auto u32 = [](std::uint32_t v) {
    std::string b(4, '\0');
    std::memcpy(&b[0], &v, 4);
    return b;
  };
  bad += u32(header_len + 4 + n) + good.substr(17, header_len) + length + field;
  bad += u32(data_len - 4 - n) + good.substr(21 + header_len, data_len - 4 - n);
  bad += good.substr(21 + header_len + data_len);
  ASSERT_EQ(bad.size(), good.size());
  spill(path, bad);
  EXPECT_EQ(read_error(path), path +
                                  ": an encrypted bag (encryptor 'rosbag/AesCbcEncryptor') is not "
                                  "read; decrypt it first: rosbag decrypt " +
                                  path);
  std::remove(path.c_str());
}

// An lz4 chunk that states more than lz4 can expand its data to is refused before its stated size
// is allocated.
TEST(Ros1BagReader, RefusesAnLz4ChunkStatingMoreThanItCanHold) {
  const std::string good = small_bag(rosbag::compression::LZ4);
  const std::string path = ::testing::TempDir() + "/lz4_size_" + std::to_string(::getpid());
  const RecordAt chunk = first(good, 0x05);
  std::string bad = good;
  const std::uint32_t size = 1U << 29;
  std::memcpy(&bad[chunk.data_len_pos - 4], &size, 4);
  spill(path, bad);
  EXPECT_EQ(read_error(path), path + ": corrupt bag: record at byte " + std::to_string(chunk.pos) +
                                  ": lz4 chunk of " +
                                  std::to_string(u32_at(good, chunk.data_len_pos)) +
                                  " bytes states 536870912 bytes uncompressed (lz4 expands at "
                                  "most 255 times)");
  std::remove(path.c_str());
}

// Issue 16, fuzzing: the bag library reads a bag of format 1.2 without checking a length (a header
// length of 0xf0000000 was allocated, 3.75 GiB): such a bag is refused, with what to do.
TEST(Ros1BagReader, RefusesFormat1Point2) {
  const std::string path = ::testing::TempDir() + "/v12_" + std::to_string(::getpid()) + ".bag";
  spill(path, std::string("#ROSBAG V1.2\n\0\0\0\xf0op=\x03", 21));
  EXPECT_EQ(read_error(path), path +
                                  ": a ROS bag of format 1.2 (before 2010) is not read; convert "
                                  "it to format 2.0: rosbag filter " +
                                  path + " new.bag True");
  std::remove(path.c_str());
}

// Seeded corruptions of bags of each compression (bytes flipped, 8 bytes set to 0x7f, a record's
// length overwritten, the file cut short), each read and copied into a new bag in a child
// process: it reads whole or fails with a one-line error naming the file; no signal, no output
// or partial output left after a failure.
TEST(Ros1BagReader, SeededCorruptionsReadOrFailCleanly) {
  const std::vector<std::string> bags = {small_bag(rosbag::compression::Uncompressed),
                                         small_bag(rosbag::compression::LZ4),
                                         small_bag(rosbag::compression::BZ2)};
  const std::string dir = ::testing::TempDir() + "/fuzz_" + std::to_string(::getpid());
  ::mkdir(dir.c_str(), 0700);
  const std::string in = dir + "/in.bag";
  const std::string out = dir + "/out.bag";
  int read = 0, refused = 0;
  for (std::uint32_t seed = 1; seed <= 400; ++seed) {
    std::mt19937 rng(seed);
    std::string b = bags[seed % 3];
    const auto below = [&](std::size_t n) {
      return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng);
    };
    const std::vector<RecordAt> records = records_of(b);
    switch (seed / 3 % 4) {
      case 0:  // A few bytes flipped.
        for (std::size_t i = 0, n = 1 + below(4); i < n; ++i)
          b[below(b.size())] ^= static_cast<char>(1 << below(8));
        break;
      case 1:  // Cut short.
        b.resize(below(b.size()));
        break;
      case 2: {  // A record's header or data length, or a header field's length, overwritten.
        const RecordAt& r = records[below(records.size())];
        const std::size_t pos = below(3) == 0 ? r.pos : below(2) ? r.data_len_pos : r.pos + 4;
        const std::uint32_t values[] = {0,
                                        1,
                                        0x7fffffff,
                                        0xffffffff,
                                        u32_at(b, pos) + static_cast<std::uint32_t>(below(16)) - 8,
                                        static_cast<std::uint32_t>(below(b.size()))};
        std::memcpy(&b[pos], &values[below(6)], 4);
        break;
      }
      default: {  // 8 bytes set to 0x7f, anywhere.
        const std::size_t pos = below(b.size() - 8);
        std::memset(&b[pos], 0x7f, 8);
      }
    }
    spill(in, b);
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
#ifndef __SANITIZE_ADDRESS__
      // A bound on what a corrupt length can make it allocate. (Not under AddressSanitizer: its
      // shadow memory alone is terabytes of address space; it bounds allocations itself.)
      const rlimit memory{std::uint64_t{4} << 30, std::uint64_t{4} << 30};
      ::setrlimit(RLIMIT_AS, &memory);
#endif
      try {
        Ros1BagReader reader(in);
        Ros1BagWriter writer(out, BagCompression::kNone);
        reader.read({}, [&](const RecordedMessage& m) {
          (void)m.scan();
          (void)m.odometry();
          writer.copy(m);
        });
        writer.finish();
        std::_Exit(0);
      } catch (const InputError& e) {
        const std::string m = e.what();
        std::_Exit(m.rfind(in + ": ", 0) == 0 && m.find('\n') == std::string::npos ? 1 : 2);
      } catch (...) {
        std::_Exit(3);
      }
    }
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFEXITED(status)) << "seed " << seed << ": signal " << WTERMSIG(status);
    const int code = WEXITSTATUS(status);
    ASSERT_LE(code, 1) << "seed " << seed << ": 2: not one line naming the file, 3: not an "
                       << "InputError";
    (code == 0 ? read : refused)++;
    EXPECT_EQ(exists(out), code == 0) << "seed " << seed;
    EXPECT_FALSE(exists(out + ".partial")) << "seed " << seed;
    std::remove(out.c_str());
  }
  std::printf("seeded corruptions: %d read whole, %d refused with one line\n", read, refused);
  std::remove(in.c_str());
  ::rmdir(dir.c_str());
}

}  // namespace
}  // namespace dispel::io
