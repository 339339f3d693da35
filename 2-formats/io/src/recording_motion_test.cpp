// The first pass over a recording, on recordings built in memory: the /tf rules, the mount, the
// poses, the scan period, and the errors. (Every command's first pass is this one; the bag
// commands' tests run it on real bags.)
#include "dispel/io/recording_motion.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "dispel/io/errors.hpp"

namespace dispel::io {
namespace {

// A recording held in memory, in the order given.
class MemoryRecording final : public RecordingReader {
 public:
  void add(const std::string& topic, double t, DecodedPayload p) {
    messages_.emplace_back(topic, Stamp::from_seconds(t), std::move(p));
    std::map<std::string, TopicInfo> topics = topics_.all();
    TopicInfo& info = topics[topic];
    info.kind = messages_.back().kind();
    info.type = message_kind_name(info.kind);
    ++info.messages;
    topics_ = Topics(std::move(topics));
  }
  const std::string& path() const override { return path_; }
  std::string format_name() const override { return "memory"; }
  const Topics& topics() const override { return topics_; }
  Stamp begin_time() const override { return messages_.front().time(); }
  Stamp end_time() const override { return messages_.back().time(); }
  void read(const std::vector<std::string>& topics,
            const std::function<void(const RecordedMessage&)>& visit) override {
    for (const DecodedMessage& m : messages_) {
      if (!topics.empty() && std::find(topics.begin(), topics.end(), m.topic()) == topics.end()) {
        continue;
      }
      try {
        visit(m);
      } catch (const StopReading&) {
        return;
      }
    }
  }

 private:
  std::string path_ = "memory.bag";
  std::vector<DecodedMessage> messages_;
  Topics topics_;
};

ScanMessage scan(double t, float scan_time = 0.0F, const std::string& frame = "laser") {
  ScanMessage m;
  m.header.stamp = Stamp::from_seconds(t);
  m.header.frame_id = frame;
  m.scan.stamp_s = t;
  m.scan.angle_increment_rad = 0.01;
  m.scan.range_max_m = 10.0F;
  m.scan.ranges_m.assign(10, 2.0F);
  m.scan_time = scan_time;
  return m;
}

OdometryMessage odom(double t, const Pose2& pose, const std::string& frame = "odom",
                     const std::string& child = "base_link") {
  OdometryMessage m;
  m.header.stamp = Stamp::from_seconds(t);
  m.header.frame_id = frame;
  m.child_frame_id = child;
  m.pose = pose;
  return m;
}

TransformsMessage tf(const std::string& parent, const std::string& child, const Pose2& pose) {
  return {{{Stamp{}, parent, child, pose}}};
}

std::string error_of(MemoryRecording& r, const MotionQuery& q) {
  try {
    read_motion(r, q);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(RecordingMotion, TheMountComesFromFixedTransformsWhicheverOrderTheyCameIn) {
  MemoryRecording r;
  // Before any odometry: the robot's motion in odom (and in map) is not a mount, wherever it is.
  r.add("/tf", 0.0, tf("odom", "base_link", {5.0, 5.0, 1.0}));
  r.add("/tf", 0.0, tf("map", "odom", {1.0, 0.0, 0.0}));
  r.add("/tf_static", 0.0, tf("/base_link", "laser_mount", {0.2, 0.0, 0.0}));
  r.add("/tf_static", 0.0, tf("laser_mount", "laser", {0.0, 0.1, 0.5}));
  for (int k = 0; k < 10; ++k) {
    r.add("/odom", 0.1 * k, odom(0.1 * k, {0.1 * k, 0.0, 0.0}));
    r.add("/scan", 0.1 * k + 0.05, scan(0.1 * k + 0.05));
  }
  const RecordingMotion m = read_motion(r, MotionQuery{});
  EXPECT_EQ(m.scans, 10);
  EXPECT_EQ(m.laser_frame, "laser");
  EXPECT_EQ(m.base_frame, "base_link");
  EXPECT_EQ(m.fixed_frame, "odom");
  EXPECT_NEAR(m.mount.x_m, 0.2, 1e-12);
  EXPECT_NEAR(m.mount.y_m, 0.1, 1e-12);
  EXPECT_NEAR(m.mount.yaw_rad, 0.5, 1e-12);
  // The laser's pose: the interpolated odometry times the mount.
  const std::optional<Pose2> p = m.sensor_pose(0.45);
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR(p->x_m, 0.45 + 0.2, 1e-9);
  PoseLookup why = PoseLookup::kOk;
  EXPECT_FALSE(m.sensor_pose(5.0, &why).has_value());
  EXPECT_EQ(why, PoseLookup::kAfterLast);
}

TEST(RecordingMotion, TheFixedFrameIsTheOdometrysOwnAndNeverAMount) {
  MemoryRecording r;
  r.add("/tf", 0.0, tf("world", "base", {3.0, 0.0, 0.0}));  // The robot in "world": motion.
  r.add("/tf_static", 0.0, tf("base", "lidar", {0.3, 0.0, 0.0}));
  r.add("/truth", 0.0, odom(0.0, {}, "/world", "/base"));
  r.add("/scan", 0.0, scan(0.0, 0.0F, "/lidar"));
  MotionQuery q;
  q.pose_topic = "/truth";
  const RecordingMotion m = read_motion(r, q);
  EXPECT_EQ(m.fixed_frame, "world");
  EXPECT_EQ(m.base_frame, "base");
  EXPECT_EQ(m.laser_frame, "lidar");
  EXPECT_NEAR(m.mount.x_m, 0.3, 1e-12);
}

TEST(RecordingMotion, TheScanPeriodIsTheFiltersRule) {
  MemoryRecording stated;
  for (int k = 0; k < 5; ++k) stated.add("/scan", 0.1 * k, scan(0.1 * k, 0.025F));
  MotionQuery q;
  q.pose_topic.reset();
  EXPECT_NEAR(*read_motion(stated, q).scan_period_s, 0.025, 1e-7);
  MemoryRecording stamps;  // No stated period: the median interval, one dropped scan or not.
  for (double t : {0.0, 0.1, 0.3, 0.4, 0.5}) stamps.add("/scan", t, scan(t));
  EXPECT_NEAR(*read_motion(stamps, q).scan_period_s, 0.1, 1e-9);
  MemoryRecording still;  // The same stamp over and over: unknown.
  for (int k = 0; k < 5; ++k) still.add("/scan", 1.0, scan(1.0));
  EXPECT_FALSE(read_motion(still, q).scan_period_s.has_value());
}

TEST(RecordingMotion, AStaticSensorNeedsNoPosesAndNoMount) {
  MemoryRecording r;
  r.add("/scan", 1.0, scan(1.0));
  MotionQuery q;
  q.pose_topic.reset();
  const RecordingMotion m = read_motion(r, q);
  EXPECT_TRUE(m.static_sensor);
  const std::optional<Pose2> p = m.sensor_pose(1e9);
  ASSERT_TRUE(p.has_value());
  EXPECT_EQ(p->x_m, 0.0);
}

TEST(RecordingMotion, WhatIsMissingIsOneLineNamingTheRecordingAndTheTopic) {
  MemoryRecording r;
  r.add("/scan", 0.0, scan(0.0));
  r.add("/odom_other", 0.0, odom(0.0, {}));
  MotionQuery q;
  q.missing_pose_hint = "; use --odom-topic";
  EXPECT_EQ(error_of(r, q),
            "memory.bag: no nav_msgs/Odometry topic /odom (Odometry topics: /odom_other); use "
            "--odom-topic");
  q.scan_topic = "/front";
  EXPECT_EQ(error_of(r, q),
            "memory.bag: no sensor_msgs/LaserScan topic /front (LaserScan topics: /scan)");
  q.scan_topic = "/scan";
  q.pose_topic = "/odom_other";
  q.missing_mount_hint = "; record it";
  EXPECT_EQ(error_of(r, q),
            "memory.bag: no transform from base_link to laser in /tf_static or /tf; record it");
  MemoryRecording bad_poses;
  bad_poses.add("/scan", 0.0, scan(0.0, 0.0F, "base_link"));
  bad_poses.add("/odom", 0.0, odom(0.0, {std::nan(""), 0.0, 0.0}));
  EXPECT_EQ(error_of(bad_poses, MotionQuery{}), "memory.bag: no usable poses on /odom");
}

TEST(RecordingMotion, WithoutAScanTopicFilteredScansAreReadWhenThereAreAny) {
  MemoryRecording r;
  r.add("/scan", 0.0, scan(0.0));
  r.add("/scan_filtered", 0.0, scan(0.0));
  MotionQuery q;
  q.scan_topic.clear();
  q.pose_topic.reset();
  EXPECT_EQ(read_motion(r, q).scan_topic, "/scan_filtered");
}

}  // namespace
}  // namespace dispel::io
