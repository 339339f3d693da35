#include "dispel/io/rosbag2.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "dispel/io/errors.hpp"
#include "dispel/io/ros2_messages.hpp"

namespace dispel::io {
namespace {

namespace fs = std::filesystem;

class Rosbag2 : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("dispel_rosbag2_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string at(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

ScanMessage scan_at(int i) {
  ScanMessage m;
  m.header.stamp = {1700000000 + i / 10, static_cast<std::uint32_t>((i % 10) * 100000000)};
  m.header.frame_id = "laser";
  m.scan.stamp_s = m.header.stamp.seconds();
  m.scan.angle_min_rad = -1.0;
  m.scan.angle_increment_rad = 0.01;
  m.scan.range_min_m = 0.1F;
  m.scan.range_max_m = 20.0F;
  for (int b = 0; b < 200; ++b) m.scan.ranges_m.push_back(1.0F + 0.01F * static_cast<float>(b + i));
  m.angle_max = -1.0F + 0.01F * 199;
  return m;
}

// Writes 300 scans, odometry between them and one static transform.
void write_recording(RecordingWriter& w) {
  TransformsMessage tf;
  tf.transforms.push_back({{1700000000, 0}, "base_link", "laser", {0.2, -0.1, 0.3}});
  w.write("/tf_static", {1700000000, 0}, tf);
  for (int i = 0; i < 300; ++i) {
    const ScanMessage s = scan_at(i);
    w.write("/scan", s.header.stamp, s);
    const OdometryMessage o =
        odometry_message(s.header.stamp.seconds() + 0.05, "odom", "base_link", {0.01 * i, 0, 0});
    w.write("/odom", o.header.stamp, o);
  }
  w.finish();
}

std::vector<std::pair<std::string, Stamp>> messages_of(RecordingReader& r) {
  std::vector<std::pair<std::string, Stamp>> out;
  r.read({}, [&](const RecordedMessage& m) { out.emplace_back(m.topic(), m.time()); });
  return out;
}

TEST_F(Rosbag2, WhatIsWrittenIsReadBackInEveryCompressionAndLayout) {
  for (const auto& [name, c] : std::vector<std::pair<std::string, Rosbag2Compression>>{
           {"plain.mcap", Rosbag2Compression::kNone},
           {"zstd.mcap", Rosbag2Compression::kZstd},
           {"lz4.mcap", Rosbag2Compression::kLz4},
           {"folder", Rosbag2Compression::kZstd}}) {
    SCOPED_TRACE(name);
    {
      Rosbag2Writer w(at(name), c);
      write_recording(w);
      EXPECT_EQ(w.messages_written(), 601);
    }
    EXPECT_FALSE(fs::exists(at(name) + ".partial"));
    Rosbag2Reader r(at(name));
    EXPECT_EQ(r.topics().messages("/scan"), 300);
    EXPECT_EQ(r.topics().messages("/odom"), 300);
    EXPECT_TRUE(r.topics().has("/tf_static", MessageKind::kTransforms));
    EXPECT_EQ(r.topics().all().at("/scan").type, "sensor_msgs/msg/LaserScan");
    EXPECT_EQ(r.begin_time(), (Stamp{1700000000, 0}));
    EXPECT_NEAR(r.end_time().seconds(), 1700000029.95, 1e-6);  // The last odometry.
    const auto all = messages_of(r);
    ASSERT_EQ(all.size(), 601U);
    for (std::size_t i = 1; i < all.size(); ++i) EXPECT_FALSE(all[i].second < all[i - 1].second);
    int scans = 0;
    r.read({"/scan"}, [&](const RecordedMessage& m) {
      const auto s = m.scan();
      ASSERT_TRUE(s.has_value());
      const ScanMessage e = scan_at(scans);
      EXPECT_EQ(s->header.stamp, e.header.stamp);
      EXPECT_EQ(s->scan.ranges_m, e.scan.ranges_m);
      EXPECT_FALSE(m.odometry().has_value());
      ++scans;
    });
    EXPECT_EQ(scans, 300);
  }
  EXPECT_TRUE(fs::exists(at("folder") + "/metadata.yaml"));
  EXPECT_TRUE(fs::exists(at("folder") + "/folder_0.mcap"));
}

TEST_F(Rosbag2, ACopyKeepsTheBytesTheTypeAndTheQos) {
  {
    Rosbag2Writer w(at("in.mcap"), Rosbag2Compression::kNone);
    write_recording(w);
  }
  Rosbag2Reader in(at("in.mcap"));
  {
    Rosbag2Writer out(at("out"), Rosbag2Compression::kLz4);
    in.read({}, [&](const RecordedMessage& m) { out.copy(m); });
    out.finish();
  }
  Rosbag2Reader back(at("out"));
  ASSERT_EQ(back.topics().all().size(), in.topics().all().size());
  for (const auto& [name, t] : in.topics().all()) {
    EXPECT_EQ(back.topics().all().at(name).type, t.type);
    EXPECT_EQ(back.topics().all().at(name).kind, t.kind);
    EXPECT_EQ(back.topics().all().at(name).messages, t.messages);
  }
  std::vector<std::vector<std::uint8_t>> a, b;
  in.read({"/scan"}, [&](const RecordedMessage& m) { a.push_back(encode_ros2(*m.scan())); });
  back.read({"/scan"}, [&](const RecordedMessage& m) { b.push_back(encode_ros2(*m.scan())); });
  EXPECT_EQ(a, b);
  std::ifstream meta(at("out") + "/metadata.yaml");
  const std::string text((std::istreambuf_iterator<char>(meta)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("storage_identifier: mcap"), std::string::npos) << text;
  EXPECT_NE(text.find("durability: 1"), std::string::npos) << "/tf_static is transient local";
}

std::vector<char> bytes_of(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}
void put(const std::string& path, const std::vector<char>& b) {
  std::ofstream f(path, std::ios::binary);
  f.write(b.data(), static_cast<std::streamsize>(b.size()));
}

std::string error_of(const std::string& path) {
  try {
    Rosbag2Reader r(path);
    r.read({}, [](const RecordedMessage& m) { (void)m.scan(); });
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST_F(Rosbag2, ACorruptOrCutFileIsOneLineNamingTheProblem) {
  {
    Rosbag2Writer w(at("good.mcap"), Rosbag2Compression::kZstd);
    write_recording(w);
  }
  const std::vector<char> good = bytes_of(at("good.mcap"));
  std::vector<char> b = good;
  b[1] = 'X';
  put(at("magic.mcap"), b);
  EXPECT_NE(error_of(at("magic.mcap")).find("not an MCAP file"), std::string::npos);
  put(at("cut.mcap"),
      std::vector<char>(good.begin(), good.begin() + static_cast<long>(good.size() / 2)));
  EXPECT_NE(error_of(at("cut.mcap")).find("truncated"), std::string::npos);
  // Every single flipped byte: an error or a good read, never a crash (the sanitizers watch).
  int errors = 0;
  for (std::size_t i = 8; i < good.size(); i += 97) {
    b = good;
    b[i] = static_cast<char>(b[i] ^ 0x5a);
    put(at("flip.mcap"), b);
    const std::string e = error_of(at("flip.mcap"));
    if (!e.empty()) {
      ++errors;
      EXPECT_EQ(e.find('\n'), std::string::npos) << e;
      EXPECT_LE(e.size(), 500U) << e;
      EXPECT_EQ(e.rfind(at("flip.mcap"), 0), 0U) << e;
    }
  }
  EXPECT_GT(errors, 0);
  fs::create_directories(at("nometa"));
  EXPECT_NE(error_of(at("nometa")).find("without metadata.yaml"), std::string::npos);
  fs::create_directories(at("sqlite"));
  put(at("sqlite/metadata.yaml"),
      {std::begin("rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n"
                  "  relative_file_paths: [x.db3]\n"),
       std::end("rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n"
                "  relative_file_paths: [x.db3]\n") -
           1});
  EXPECT_NE(error_of(at("sqlite")).find("storage 'sqlite3'"), std::string::npos)
      << error_of(at("sqlite"));
}

TEST_F(Rosbag2, AFolderThatExistsIsNeverReplacedAndAnUnfinishedOneLeavesNothing) {
  fs::create_directories(at("there"));
  EXPECT_THROW(Rosbag2Writer(at("there"), Rosbag2Compression::kNone), OutputError);
  {
    Rosbag2Writer w(at("unfinished"), Rosbag2Compression::kNone);
    w.write("/scan", {1, 0}, scan_at(0));
  }
  EXPECT_FALSE(fs::exists(at("unfinished")));
  EXPECT_FALSE(fs::exists(at("unfinished.partial")));
}

}  // namespace
}  // namespace dispel::io
