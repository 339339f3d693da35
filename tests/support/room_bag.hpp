#pragma once
// Test support for dispel::slam (never installed): a synthetic bag of a robot driving a circle in
// a room, written with rosbag, with its true trajectory.

#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_msgs/TFMessage.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "dispel/core/pose2.hpp"
#include "dispel/eval/trajectory_error.hpp"
#include "dispel/io/ros1_messages.hpp"
#include "dispel/jobs/job.hpp"
#include "dispel/sim/raycast.hpp"
#include "test_files.hpp"

namespace dispel::slam::room {

inline constexpr double kDeg = kPi / 180.0;

// The scene: a room of 8 x 6 m (walls 0-3: bottom, right, top, left) with two pillars, the robot
// driving a circle of radius 1.8 m about the room's centre at 0.4 m/s, one loop and a bit (32 s).
inline constexpr double kRadius = 1.8;
inline constexpr double kSpeed = 0.4;
inline constexpr double kDuration = 32.0;
inline constexpr double kStart = 100.0;
inline constexpr int kTopWall = 2;
inline const Pose2 kMount{0.2, 0.05, 0.05};

inline sim::World room() {
  sim::World w;
  w.segments = {{{0, 0}, {8, 0}}, {{8, 0}, {8, 6}}, {{8, 6}, {0, 6}}, {{0, 6}, {0, 0}}};
  w.circles = {{{1.2, 4.8}, 0.25}, {{6.5, 1.5}, 0.2}};
  return w;
}

// The robot at time t (s) after the start, having started @p start_angle_rad along the circle.
inline Pose2 truth_at(double t, double start_angle_rad = 0.0) {
  const double a = start_angle_rad + kSpeed / kRadius * t;
  return {4.0 + kRadius * std::sin(a), 3.0 - kRadius * std::cos(a), wrap_angle(a)};
}

struct BagOptions {
  bool nan_top_wall = false;  // Beams that hit the top wall become NaN, as `dispel filter` does.
  bool with_odometry = true;
  bool with_scans = true;
  double angle_min_deg = -135.0;  // 360 beams, 0.75 deg apart from here (symmetric by default).
  double start_angle_rad = 0.0;   // Where on the circle the robot starts.
  std::uint32_t range_noise_seed = 7;
  // Random odometry error on top of the drift: each 20 ms increment scaled by 1 + N(0, this).
  double odom_noise = 0.0;
  std::uint32_t odom_noise_seed = 1;
  // Odometry starts at (0, 0, 0) as a deployed robot's does, not at the true pose.
  bool odom_from_origin = false;
  // The first this many scans NaN but for every 40th beam (a filter with presumption of guilt
  // removes every object it has not yet seen still: the first scans keep a few stray beams).
  int nan_first_scans = 0;
};

struct SimRun {
  std::string path;
  std::vector<eval::TrajectoryPoint> truth;  // Base frame at each scan.
};

// Odometry at 50 Hz with a 2% scale error and a yaw-rate bias of 0.02 rad/s (1.15 deg/s); scans at
// 10 Hz, 360 beams over 270 deg, 1 cm noise; the mount on /tf_static.
inline SimRun write_bag(const std::string& name, const BagOptions& opt) {
  SimRun run;
  run.path = dispel::test::temp_path(name);
  rosbag::Bag bag(run.path, rosbag::bagmode::Write);
  {
    tf2_msgs::TFMessage tf;
    geometry_msgs::TransformStamped t;
    t.header.stamp = io::to_ros_time(kStart);
    t.header.frame_id = "base_link";
    t.child_frame_id = "laser";
    t.transform.translation.x = kMount.x_m;
    t.transform.translation.y = kMount.y_m;
    t.transform.rotation = io::quaternion_from_yaw(kMount.yaw_rad);
    tf.transforms = {t};
    bag.write("/tf_static", t.header.stamp, tf);
  }
  const sim::World world = room();
  const sim::ScanGeometry g{opt.angle_min_deg * kDeg, 270.0 * kDeg / 359.0, 360, 0.05F, 20.0F};
  std::mt19937 rng(opt.range_noise_seed);
  std::normal_distribution<float> noise(0.0F, 0.01F);
  std::mt19937 odom_rng(opt.odom_noise_seed);
  std::normal_distribution<double> odom_noise(0.0, 1.0);
  constexpr double kOdomDt = 0.02;
  Pose2 odom = opt.odom_from_origin ? Pose2{} : truth_at(0.0, opt.start_angle_rad);
  Pose2 previous_truth = truth_at(0.0, opt.start_angle_rad);
  const int steps = static_cast<int>(std::lround(kDuration / kOdomDt));
  for (int k = 0; k <= steps; ++k) {
    const double t = kOdomDt * k;
    const Pose2 truth = truth_at(t, opt.start_angle_rad);
    if (k > 0) {
      const Pose2 step = previous_truth.inverse() * truth;
      const double scale =
          1.02 + (opt.odom_noise > 0.0 ? opt.odom_noise * odom_noise(odom_rng) : 0.0);
      const double turn =
          1.0 + (opt.odom_noise > 0.0 ? opt.odom_noise * odom_noise(odom_rng) : 0.0);
      odom = odom * Pose2{scale * step.x_m, scale * step.y_m, turn * step.yaw_rad + 0.02 * kOdomDt};
    }
    previous_truth = truth;
    if (opt.with_odometry) {
      const nav_msgs::Odometry msg = io::to_ros_odometry(kStart + t, "odom", "base_link", odom,
                                                         1.02 * kSpeed, kSpeed / kRadius + 0.02);
      bag.write("/odom", msg.header.stamp, msg);
    }
    if (k % 5 != 0 || !opt.with_scans) continue;
    std::vector<std::int32_t> hit;
    LaserScan scan = sim::raycast(world, truth * kMount, g, &hit);
    scan.stamp_s = kStart + t;
    for (std::size_t i = 0; i < scan.size(); ++i) {
      if (std::isfinite(scan.ranges_m[i])) scan.ranges_m[i] += noise(rng);
      if ((opt.nan_top_wall && hit[i] == kTopWall) ||
          (static_cast<int>(run.truth.size()) < opt.nan_first_scans && i % 40 != 0)) {
        scan.ranges_m[i] = std::numeric_limits<float>::quiet_NaN();
      }
    }
    const sensor_msgs::LaserScan msg = io::to_ros(scan, "laser");
    bag.write("/scan", msg.header.stamp, msg);
    run.truth.push_back({kStart + t, truth.x_m, truth.y_m, truth.yaw_rad});
  }
  return run;
}

// @p run must throw jobs::JobError with a one-line message containing @p expected; @p given names
// the input in the failure message.
template <typename Run>
void expect_job_error(const Run& run, const std::string& expected, const std::string& given) {
  try {
    run();
    ADD_FAILURE() << "accepted " << given;
  } catch (const jobs::JobError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(expected), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

}  // namespace dispel::slam::room
