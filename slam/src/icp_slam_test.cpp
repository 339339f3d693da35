#include "dispel/slam/icp_slam.hpp"

#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_msgs/TFMessage.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <random>

#include "dispel/eval/trajectory_error.hpp"
#include "dispel/io/filter_job.hpp"
#include "dispel/io/ros_convert.hpp"
#include "dispel/sim/raycast.hpp"
#include "test_files.hpp"

namespace dispel::slam {
namespace {

using io::JobError;
using test::temp_path;

constexpr double kDeg = kPi / 180.0;

// The scene: a room of 8 x 6 m (walls 0-3: bottom, right, top, left) with two pillars, the robot
// driving a circle of radius 1.8 m about the room's centre at 0.4 m/s, one loop and a bit (32 s).
constexpr double kRadius = 1.8;
constexpr double kSpeed = 0.4;
constexpr double kDuration = 32.0;
constexpr double kStart = 100.0;
constexpr int kTopWall = 2;
const Pose2 kMount{0.2, 0.05, 0.05};

sim::World room() {
  sim::World w;
  w.segments = {{{0, 0}, {8, 0}}, {{8, 0}, {8, 6}}, {{8, 6}, {0, 6}}, {{0, 6}, {0, 0}}};
  w.circles = {{{1.2, 4.8}, 0.25}, {{6.5, 1.5}, 0.2}};
  return w;
}

Pose2 truth_at(double t) {
  const double w = kSpeed / kRadius;
  const double a = w * t;
  return {4.0 + kRadius * std::sin(a), 3.0 - kRadius * std::cos(a), wrap_angle(a)};
}

struct BagOptions {
  bool nan_top_wall = false;  // Beams that hit the top wall become NaN, as `dispel filter` does.
  bool with_odometry = true;
  bool with_scans = true;
  double angle_min_deg = -135.0;  // 360 beams, 0.75 deg apart from here (symmetric by default).
};

struct SimRun {
  std::string path;
  std::vector<eval::TrajectoryPoint> truth;  // Base frame at each scan.
};

// Odometry at 50 Hz with a 2% scale error and a yaw-rate bias of 0.02 rad/s (1.15 deg/s), starting
// at the true pose; scans at 10 Hz, 360 beams over 270 deg, 1 cm noise; the mount on /tf_static.
SimRun write_bag(const std::string& name, const BagOptions& opt) {
  SimRun run;
  run.path = temp_path(name);
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
  std::mt19937 rng(7);
  std::normal_distribution<float> noise(0.0F, 0.01F);
  constexpr double kOdomDt = 0.02;
  Pose2 odom = truth_at(0.0);
  Pose2 previous_truth = odom;
  const int steps = static_cast<int>(std::lround(kDuration / kOdomDt));
  for (int k = 0; k <= steps; ++k) {
    const double t = kOdomDt * k;
    const Pose2 truth = truth_at(t);
    if (k > 0) {
      const Pose2 step = previous_truth.inverse() * truth;
      odom = odom * Pose2{1.02 * step.x_m, 1.02 * step.y_m, step.yaw_rad + 0.02 * kOdomDt};
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
      if (opt.nan_top_wall && hit[i] == kTopWall) {
        scan.ranges_m[i] = std::numeric_limits<float>::quiet_NaN();
      }
    }
    const sensor_msgs::LaserScan msg = io::to_ros(scan, "laser");
    bag.write("/scan", msg.header.stamp, msg);
    run.truth.push_back({kStart + t, truth.x_m, truth.y_m, truth.yaw_rad});
  }
  return run;
}

// Map points more than 0.2 m outside the room: an invalid beam inserted at its stand-in range (the
// maximum range) would land there.
std::int64_t points_outside_room(const std::vector<MapPoint>& points) {
  std::int64_t n = 0;
  for (const auto& p : points) {
    n += (p.x_m < -0.2 || p.x_m > 8.2 || p.y_m < -0.2 || p.y_m > 6.2);
  }
  return n;
}

// Map points within 0.15 m of the top wall, away from the corners.
std::int64_t points_near_top_wall(const std::vector<MapPoint>& points) {
  std::int64_t n = 0;
  for (const auto& p : points) n += (std::abs(p.y_m - 6.0) < 0.15 && p.x_m > 0.5 && p.x_m < 7.5);
  return n;
}

TEST(SlamIcp, RecoversTheTrueTrajectoryFromDriftingOdometry) {
  const SimRun run = write_bag("slam_loop.bag", {});
  SlamOptions o;
  o.input = run.path;
  const auto start = std::chrono::steady_clock::now();
  const SlamResult r = run_icp_slam_full(o);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_EQ(r.scans, static_cast<std::int64_t>(run.truth.size()));
  ASSERT_EQ(r.scans_used, r.scans);
  ASSERT_EQ(r.trajectory.size(), run.truth.size());
  const eval::TrajectoryErrors slam = eval::compare_trajectories(run.truth, r.trajectory);
  const eval::TrajectoryErrors odom = eval::compare_trajectories(run.truth, r.odometry);
  RecordProperty("slam_rmse_position_m", std::to_string(slam.rmse_position_m));
  RecordProperty("slam_rmse_yaw_deg", std::to_string(slam.rmse_yaw_rad / kDeg));
  RecordProperty("odometry_rmse_position_m", std::to_string(odom.rmse_position_m));
  std::printf(
      "scans %lld in %.2f s; RMSE position: SLAM %.4f m, odometry %.4f m; yaw: SLAM %.3f "
      "deg, odometry %.3f deg; final: SLAM %.4f m, odometry %.4f m; map points %zu\n",
      static_cast<long long>(r.scans), seconds, slam.rmse_position_m, odom.rmse_position_m,
      slam.rmse_yaw_rad / kDeg, odom.rmse_yaw_rad / kDeg, slam.final_position_error_m,
      odom.final_position_error_m, r.map_points.size());
  EXPECT_LT(slam.rmse_position_m, 0.1);
  EXPECT_LT(slam.rmse_yaw_rad, 2.0 * kDeg);
  EXPECT_GT(odom.rmse_position_m, 0.3);                          // The drift is real...
  EXPECT_LT(slam.rmse_position_m, 0.25 * odom.rmse_position_m);  // ...and SLAM removes it.
  std::printf("map points near the top wall: %lld\n",
              static_cast<long long>(points_near_top_wall(r.map_points)));
  EXPECT_GT(points_near_top_wall(r.map_points), 50);
  EXPECT_EQ(points_outside_room(r.map_points), 0);
  std::remove(run.path.c_str());
}

TEST(SlamIcp, InvalidBeamsNeverEnterTheMap) {
  const SimRun with_nan = write_bag("slam_nan.bag", {true, true, true, -135.0});
  SlamOptions o;
  o.input = with_nan.path;
  const SlamResult r = run_icp_slam_full(o);
  EXPECT_GT(r.beams_invalid, 1000);
  EXPECT_EQ(points_near_top_wall(r.map_points), 0);
  EXPECT_EQ(points_outside_room(r.map_points), 0);
  EXPECT_GT(r.map_points.size(), 1000u);
  const eval::TrajectoryErrors slam = eval::compare_trajectories(with_nan.truth, r.trajectory);
  std::printf("NaN top wall: %lld invalid beams, %zu map points, RMSE position %.4f m\n",
              static_cast<long long>(r.beams_invalid), r.map_points.size(), slam.rmse_position_m);
  EXPECT_LT(slam.rmse_position_m, 0.15);  // The other three walls and the pillars suffice.
  std::remove(with_nan.path.c_str());
}

// MRPT's scans are symmetric about the sensor's x axis: an asymmetric ROS scan (here -60 to +210
// deg) must still put every beam where it belongs.
TEST(SlamIcp, AsymmetricScanner) {
  BagOptions opt;
  opt.angle_min_deg = -60.0;
  const SimRun run = write_bag("slam_asymmetric.bag", opt);
  SlamOptions o;
  o.input = run.path;
  const SlamResult r = run_icp_slam_full(o);
  const eval::TrajectoryErrors slam = eval::compare_trajectories(run.truth, r.trajectory);
  std::printf("asymmetric scanner: RMSE position %.4f m, yaw %.3f deg\n", slam.rmse_position_m,
              slam.rmse_yaw_rad / kDeg);
  EXPECT_LT(slam.rmse_position_m, 0.1);
  EXPECT_EQ(points_outside_room(r.map_points), 0);
  std::remove(run.path.c_str());
}

TEST(SlamIcp, OccupancyGridsNeverTakeInvalidBeamsAsFreeSpace) {
  const std::string ini = temp_path("grid.ini");
  {
    std::ofstream f(ini);
    f << "[MappingApplication]\noccupancyGrid_count = 1  // a grid too\nrawlog_file = x.rawlog\n"
         "[MappingApplication_occupancyGrid_00_insertOpts]\n"
         "considerInvalidRangesAsFreeSpace = true\n";
  }
  const std::string text = engine_config(ini);
  EXPECT_NE(text.find("considerInvalidRangesAsFreeSpace = false"), std::string::npos) << text;
  EXPECT_EQ(text.find("considerInvalidRangesAsFreeSpace = true"), std::string::npos) << text;
  EXPECT_NE(text.find("occupancyGrid_count = 1"), std::string::npos) << text;
  EXPECT_NO_THROW(IcpSlamEngine engine(text));
  std::remove(ini.c_str());
}

TEST(SlamIcp, EngineConfigOverridesDefaults) {
  const std::string ini = temp_path("override.ini");
  {
    std::ofstream f(ini);
    f << "# icp-slam style\n[MappingApplication]\ninsertionLinDistance = 0.8 // metres\n"
         "[ICP]\nmaxIterations = 40\n";
  }
  const std::string text = engine_config(ini);
  EXPECT_NE(text.find("insertionLinDistance = 0.8\n"), std::string::npos) << text;
  EXPECT_NE(text.find("maxIterations = 40\n"), std::string::npos) << text;
  EXPECT_NE(text.find("pointsMap_count = 1\n"), std::string::npos) << text;
  EXPECT_EQ(engine_config(std::nullopt), default_engine_config());
  std::remove(ini.c_str());
}

// --- Bad input ----------------------------------------------------------------------------------

void expect_error(const SlamOptions& o, const std::string& expected) {
  try {
    run_icp_slam(o);
    ADD_FAILURE() << "accepted " << o.input;
  } catch (const JobError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(expected), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

std::string write_text(const std::string& name, const std::string& text) {
  const std::string path = temp_path(name);
  std::ofstream(path) << text;
  return path;
}

TEST(SlamIcpBadInput, MissingFileNotABagMissingTopics) {
  SlamOptions o;
  o.input = temp_path("does_not_exist.bag");
  expect_error(o, "No such file or directory");
  o.input = write_text("not_a_bag.bag", "hello\n");
  expect_error(o, "not a readable ROS 1 bag");
  std::remove(o.input.c_str());

  const SimRun no_odom = write_bag("slam_no_odom.bag", {false, false, true, -135.0});
  o.input = no_odom.path;
  expect_error(o, "no nav_msgs/Odometry topic /odom");
  o.odom_topic = "/wheel_odom";
  expect_error(o, "no nav_msgs/Odometry topic /wheel_odom");
  std::remove(no_odom.path.c_str());

  const SimRun no_scans = write_bag("slam_no_scans.bag", {false, true, false, -135.0});
  o.input = no_scans.path;
  o.odom_topic = "/odom";
  expect_error(o, "no sensor_msgs/LaserScan topic /scan");
  std::remove(no_scans.path.c_str());
}

TEST(SlamIcpBadInput, BadEngineConfiguration) {
  const SimRun run = write_bag("slam_bad_ini.bag", {false, true, true, -135.0});
  SlamOptions o;
  o.input = run.path;
  o.engine_config_ini = temp_path("missing.ini");
  expect_error(o, "missing.ini: No such file or directory");
  o.engine_config_ini = write_text("garbage.ini", "[ICP]\nthis is not an ini line\n");
  expect_error(o, "garbage.ini:2: not 'key = value'");
  o.engine_config_ini = write_text("nan.ini", "[MappingApplication]\ninsertionLinDistance = far\n");
  expect_error(o, "insertionLinDistance = far: expected a number");
  o.engine_config_ini = write_text("neg.ini", "[MappingApplication]\ninsertionLinDistance = -1\n");
  expect_error(o, "must be finite and >= 0");
  o.engine_config_ini = write_text("nomap.ini", "[MappingApplication]\npointsMap_count = 0\n");
  expect_error(o, "no points map");
  o.engine_config_ini = write_text("algo.ini", "[ICP]\nICP_algorithm = icpNoSuchThing\n");
  expect_error(o, "SLAM engine configuration");
  std::remove(run.path.c_str());
}

}  // namespace
}  // namespace dispel::slam
