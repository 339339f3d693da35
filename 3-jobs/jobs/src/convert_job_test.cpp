// dispel convert and the formats by name: ROS 1 bags and rosbag2 MCAP, each way; what cannot
// change format is left out and counted; outputs are refused before any work when they cannot
// be written.
#include "dispel/jobs/convert_job.hpp"

#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <sensor_msgs/LaserScan.h>
#include <std_msgs/String.h>

#include <filesystem>
#include <fstream>
#include <vector>

#include "dispel/io/ros1_messages.hpp"
#include "test_files.hpp"

namespace dispel::jobs {
namespace {

namespace fs = std::filesystem;
using test::temp_path;

// A ROS 1 bag with 20 scans on /scan and 5 std_msgs/String messages on /chatter.
std::string ros1_bag(const std::string& name) {
  const std::string path = temp_path(name);
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  for (int i = 0; i < 20; ++i) {
    sensor_msgs::LaserScan s;
    s.header.stamp = ros::Time(100 + i / 10, static_cast<std::uint32_t>((i % 10) * 100000000));
    s.header.frame_id = "laser";
    s.angle_min = -1.0F;
    s.angle_increment = 0.01F;
    s.angle_max = -1.0F + 0.01F * 99;
    s.range_min = 0.1F;
    s.range_max = 10.0F;
    s.scan_time = 0.1F;
    for (int b = 0; b < 100; ++b) s.ranges.push_back(1.0F + 0.001F * static_cast<float>(b * i));
    bag.write("/scan", s.header.stamp, s);
    if (i % 4 == 0) {
      std_msgs::String text;
      text.data = "hello " + std::to_string(i);
      bag.write("/chatter", s.header.stamp, text);
    }
  }
  bag.close();
  return path;
}

std::vector<io::ScanMessage> scans_of(const std::string& path) {
  std::vector<io::ScanMessage> out;
  open_recording(path)->read({"/scan"},
                             [&](const io::RecordedMessage& m) { out.push_back(*m.scan()); });
  return out;
}

TEST(ConvertJob, Ros1ToMcapAndBackKeepsEveryScanAndLeavesOutWhatCannotChangeFormat) {
  const std::string in = ros1_bag("convert_in.bag");
  const std::string mcap = temp_path("convert_out.mcap");
  const std::string back = temp_path("convert_back.bag");
  fs::remove(mcap);
  const ConvertJobStats to = run_convert_job({in, mcap, Compression::kZstd});
  EXPECT_EQ(to.input_format, "rosbag");
  EXPECT_EQ(to.messages_in, 25);
  EXPECT_EQ(to.messages_out, 20);
  ASSERT_EQ(to.left_out.size(), 1U);
  EXPECT_EQ(to.left_out.at("/chatter"), 5);
  EXPECT_NE(left_out_summary(to.left_out).find("5 messages left out on '/chatter'"),
            std::string::npos);
  EXPECT_EQ(open_recording(mcap)->format_name().rfind("rosbag2", 0), 0U);
  const ConvertJobStats from = run_convert_job({mcap, back, Compression::kNone});
  EXPECT_TRUE(from.left_out.empty());
  const auto a = scans_of(in);
  const auto b = scans_of(back);
  ASSERT_EQ(a.size(), 20U);
  ASSERT_EQ(b.size(), a.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(b[i].header.stamp, a[i].header.stamp);
    EXPECT_EQ(b[i].header.frame_id, a[i].header.frame_id);
    EXPECT_EQ(b[i].scan.ranges_m, a[i].scan.ranges_m);
    EXPECT_EQ(b[i].scan_time, a[i].scan_time);
    EXPECT_EQ(b[i].angle_max, a[i].angle_max);
  }
}

TEST(ConvertJob, TheFormatFollowsTheName) {
  EXPECT_TRUE(writes_rosbag2("out.mcap"));
  EXPECT_TRUE(writes_rosbag2("dir/out"));
  EXPECT_TRUE(writes_rosbag2("out/"));
  EXPECT_FALSE(writes_rosbag2("out.bag"));
  EXPECT_FALSE(writes_rosbag2("out.orig.bag"));
  EXPECT_FALSE(writes_rosbag2("/dev/null"));  // A device, not a folder: written in place.
}

std::string error_of(const ConvertJobOptions& o) {
  try {
    run_convert_job(o);
  } catch (const JobError& e) {
    return e.what();
  }
  return "";
}

TEST(ConvertJob, ACompressionTheFormatHasNotAndAFolderThatExistsAreRefused) {
  const std::string in = ros1_bag("convert_refused.bag");
  EXPECT_NE(error_of({in, temp_path("x.mcap"), Compression::kBz2}).find("not bz2"),
            std::string::npos);
  EXPECT_NE(error_of({in, temp_path("x.bag"), Compression::kZstd}).find("not zstd"),
            std::string::npos);
  const std::string folder = temp_path("existing_folder");
  fs::create_directories(folder);
  EXPECT_NE(error_of({in, folder, Compression::kNone}).find("a bag folder is never replaced"),
            std::string::npos);
  EXPECT_FALSE(fs::exists(temp_path("x.mcap")));
  EXPECT_FALSE(fs::exists(temp_path("x.bag")));
}

TEST(ConvertJob, Sqlite3ByNameOrAskedForAndANameThatSaysOtherwiseIsRefused) {
  const std::string in = ros1_bag("convert_sqlite3_in.bag");
  const std::string db3 = temp_path("convert.db3");
  const std::string folder = temp_path("convert_sqlite3_folder");
  fs::remove(db3);
  fs::remove_all(folder);
  EXPECT_EQ(run_convert_job({in, db3, Compression::kNone}).messages_out, 20);
  EXPECT_EQ(open_recording(db3)->format_name(), "rosbag2 (sqlite3)");
  EXPECT_EQ(scans_of(db3).size(), 20U);
  run_convert_job({db3, folder, Compression::kNone, RecordingFormat::kSqlite3});
  EXPECT_TRUE(fs::exists(fs::path(folder) / "convert_sqlite3_folder_0.db3"));
  EXPECT_EQ(scans_of(folder).size(), 20U);
  EXPECT_NE(error_of({in, temp_path("y.mcap"), Compression::kNone, RecordingFormat::kSqlite3})
                .find("the name says MCAP storage"),
            std::string::npos);
  EXPECT_NE(error_of({in, temp_path("y.db3"), Compression::kLz4}).find("not compressed"),
            std::string::npos);
  // --format ros1 for a name without extension; refused for a rosbag2 name, and rosbag2 for .bag.
  const std::string ros1 = temp_path("really_ros1");
  fs::remove_all(ros1);
  run_convert_job({db3, ros1, Compression::kNone, RecordingFormat::kRos1});
  std::ifstream f(ros1, std::ios::binary);
  std::string first_line;
  std::getline(f, first_line);
  EXPECT_EQ(first_line, "#ROSBAG V2.0");
  EXPECT_NE(error_of({db3, temp_path("z.mcap"), Compression::kNone, RecordingFormat::kRos1})
                .find("the name says rosbag2"),
            std::string::npos);
  EXPECT_NE(error_of({db3, temp_path("z.bag"), Compression::kNone, RecordingFormat::kMcap})
                .find("the name says a ROS 1 bag"),
            std::string::npos);
}

TEST(ConvertJob, ABagFolderIsAnInputWhereOtherFoldersAreNot) {
  const std::string in = ros1_bag("convert_folder_in.bag");
  const std::string folder = temp_path("convert_folder");
  fs::remove_all(folder);
  run_convert_job({in, folder, Compression::kLz4});
  EXPECT_NO_THROW(check_files({{"", folder}}, {{"-o", temp_path("y.bag")}}));
  EXPECT_NO_THROW(check_input_file(folder));
  EXPECT_EQ(scans_of(folder).size(), 20U);
  const std::string m = [&] {
    try {
      check_files({{"", folder}}, {{"-o", folder + "/" + "convert_folder_0.mcap"}});
    } catch (const JobError& e) {
      return std::string(e.what());
    }
    return std::string();
  }();
  EXPECT_NE(m.find("is inside the input bag folder"), std::string::npos) << m;
  EXPECT_THROW(check_files({{"", folder}}, {{"--stats", folder + "/./metadata.yaml"}}), JobError);
  fs::remove(fs::path(folder) / "metadata.yaml");
  EXPECT_THROW(check_files({{"", folder}}, {{"-o", temp_path("y.bag")}}), JobError);
  EXPECT_THROW(check_input_file(folder), JobError);
}

}  // namespace
}  // namespace dispel::jobs
