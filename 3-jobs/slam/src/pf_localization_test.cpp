#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "dispel/eval/trajectory_error.hpp"
#include "dispel/jobs/job.hpp"
#include "dispel/slam/icp_slam.hpp"
#include "dispel/slam/localization.hpp"
#include "room_bag.hpp"
#include "test_files.hpp"

namespace dispel::slam {
namespace {

using jobs::JobError;
using room::BagOptions;
using room::kDeg;
using room::SimRun;
using room::write_bag;
using test::temp_path;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The map of the room as ICP-SLAM builds it from the default bag (the robot starts at the bottom
// of the circle; its odometry starts at the true pose, so the odometry frame is the room's).
GridMap slam_map() {
  const SimRun mapping = write_bag("pf_mapping.bag", {});
  SlamOptions o;
  o.input = mapping.path;
  const SlamResult r = run_icp_slam_full(o);
  std::remove(mapping.path.c_str());
  return r.grid;
}

// A deployed robot's run in the same room: it starts elsewhere on the circle (2 rad on), its
// odometry starts at (0, 0, 0) and has random error on top of the drift, other range noise.
BagOptions second_run() {
  BagOptions b;
  b.start_angle_rad = 2.0;
  b.range_noise_seed = 11;
  b.odom_noise = 0.02;
  b.odom_noise_seed = 5;
  b.odom_from_origin = true;
  return b;
}

// The true start off by 0.2 m and 5 degrees.
Pose2 rough_start(const SimRun& run) {
  const eval::TrajectoryPoint& t = run.truth.front();
  return {t.x_m + 0.2 * std::cos(1.0), t.y_m + 0.2 * std::sin(1.0), t.yaw_rad + 5.0 * kDeg};
}

// Dead reckoning from @p start: what odometry alone says, in the map frame.
std::vector<eval::TrajectoryPoint> dead_reckoning(const LocalizationResult& r, const Pose2& start) {
  std::vector<eval::TrajectoryPoint> out;
  const auto& o = r.odometry.front();
  const Pose2 first_inverse = Pose2{o.x_m, o.y_m, o.yaw_rad}.inverse();
  for (const auto& p : r.odometry) {
    const Pose2 q = start * (first_inverse * Pose2{p.x_m, p.y_m, p.yaw_rad});
    out.push_back({p.t_s, q.x_m, q.y_m, q.yaw_rad});
  }
  return out;
}

// Largest position error after the first @p skip scans (the filter's convergence).
double max_error_after(const SimRun& run, const LocalizationResult& r, std::size_t skip) {
  double worst = 0.0;
  for (std::size_t i = skip; i < r.trajectory.size(); ++i) {
    worst = std::max(worst, std::hypot(r.trajectory[i].x_m - run.truth[i].x_m,
                                       r.trajectory[i].y_m - run.truth[i].y_m));
  }
  return worst;
}

TEST(SlamPfLocalization, LocalisesInAMapBuiltBySlamAndSavedAsMapServerFiles) {
  const GridMap built = slam_map();
  const std::string yaml = temp_path("pf_room.yaml");
  write_map_yaml(built, yaml);
  const GridMap map = read_map_yaml(yaml);
  ASSERT_EQ(map, built);
  EXPECT_GT(map.occupied_cells(), 600);

  const SimRun run = write_bag("pf_second_run.bag", second_run());
  LocalizationOptions o;
  o.input = run.path;
  o.map_yaml = yaml;
  o.initial_pose = rough_start(run);
  const auto start = std::chrono::steady_clock::now();
  const LocalizationResult r = run_pf_localization(o);
  const double seconds = seconds_since(start);
  ASSERT_EQ(r.scans, static_cast<std::int64_t>(run.truth.size()));
  ASSERT_EQ(r.scans_used, r.scans);
  ASSERT_EQ(r.trajectory.size(), run.truth.size());
  ASSERT_EQ(r.position_std_m.size(), run.truth.size());
  EXPECT_EQ(r.beams_invalid, 0);

  const eval::TrajectoryErrors pf = eval::compare_trajectories(run.truth, r.trajectory);
  const eval::TrajectoryErrors odom =
      eval::compare_trajectories(run.truth, dead_reckoning(r, *o.initial_pose));
  const double worst = max_error_after(run, r, 10);
  RecordProperty("pf_rmse_position_m", std::to_string(pf.rmse_position_m));
  RecordProperty("pf_rmse_yaw_deg", std::to_string(pf.rmse_yaw_rad / kDeg));
  RecordProperty("odometry_rmse_position_m", std::to_string(odom.rmse_position_m));
  std::printf(
      "%lld scans, %d particles in %.2f s; RMSE position: PF %.4f m, odometry %.4f m; yaw: PF "
      "%.3f deg, odometry %.2f deg; worst after 1 s %.4f m; final spread %.4f m\n",
      static_cast<long long>(r.scans), o.filter.particles, seconds, pf.rmse_position_m,
      odom.rmse_position_m, pf.rmse_yaw_rad / kDeg, odom.rmse_yaw_rad / kDeg, worst,
      r.position_std_m.back());
  EXPECT_LT(pf.rmse_position_m, 0.1);
  EXPECT_LT(pf.rmse_yaw_rad, 1.0 * kDeg);
  EXPECT_LT(worst, 0.1);
  EXPECT_GT(odom.rmse_position_m, 0.3);                       // The drift is real...
  EXPECT_LT(pf.rmse_position_m, 0.1 * odom.rmse_position_m);  // ...and the map removes it.
  // The first scan shrinks the initial spread (0.42 m) onto the pose.
  EXPECT_LT(r.position_std_m.front(), 0.1);
  EXPECT_LT(r.position_std_m.back(), 0.1);
  std::remove(run.path.c_str());
  std::remove(yaml.c_str());
  std::remove(temp_path("pf_room.pgm").c_str());
}

TEST(SlamPfLocalization, SameSeedSameTrajectoryOtherSeedOtherTrajectory) {
  const SimRun run = write_bag("pf_seeds.bag", second_run());
  LocalizationOptions o;
  o.input = run.path;
  o.map = slam_map();
  o.initial_pose = rough_start(run);
  o.filter.particles = 250;  // Three runs: keep them short.
  const LocalizationResult first = run_pf_localization(o);
  const LocalizationResult again = run_pf_localization(o);
  o.filter.seed = 2;
  const LocalizationResult other = run_pf_localization(o);
  ASSERT_EQ(first.trajectory.size(), again.trajectory.size());
  ASSERT_EQ(first.trajectory.size(), other.trajectory.size());
  std::size_t same = 0, differ = 0;
  for (std::size_t i = 0; i < first.trajectory.size(); ++i) {
    const auto& a = first.trajectory[i];
    const auto& b = again.trajectory[i];
    const auto& c = other.trajectory[i];
    same += a.x_m == b.x_m && a.y_m == b.y_m && a.yaw_rad == b.yaw_rad &&
            first.position_std_m[i] == again.position_std_m[i];
    differ += a.x_m != c.x_m || a.y_m != c.y_m || a.yaw_rad != c.yaw_rad;
  }
  EXPECT_EQ(same, first.trajectory.size());  // Bit for bit.
  EXPECT_GT(differ, first.trajectory.size() / 2);
  const double rmse_first = eval::compare_trajectories(run.truth, first.trajectory).rmse_position_m;
  const double rmse_other = eval::compare_trajectories(run.truth, other.trajectory).rmse_position_m;
  std::printf("RMSE position: seed 1 %.4f m, seed 2 %.4f m\n", rmse_first, rmse_other);
  EXPECT_LT(rmse_other, 0.1);
  EXPECT_NE(rmse_first, rmse_other);
  std::remove(run.path.c_str());
}

// Two localizers stepped in turn draw from their own random numbers: interleaving them changes
// neither (MRPT's filter uses a process-wide generator).
TEST(SlamPfLocalization, InterleavedLocalizersKeepTheirOwnRandomNumbers) {
  const GridMap map = slam_map();
  LaserScan scan;  // A scan of the room from the true start, as the bag's first.
  {
    const sim::ScanGeometry g{-135.0 * kDeg, 270.0 * kDeg / 359.0, 360, 0.05F, 20.0F};
    scan = sim::raycast(room::room(), room::truth_at(0.0) * room::kMount, g, nullptr);
    scan.stamp_s = room::kStart;
  }
  const Pose2 start = room::truth_at(0.0);
  const ParticleFilterOptions options;
  PfLocalizer alone(map, options, start);
  std::vector<PoseEstimate> expected;
  for (int k = 0; k < 5; ++k) {
    scan.stamp_s = room::kStart + 0.1 * k;
    expected.push_back(*alone.process(scan, start, room::kMount));
  }
  PfLocalizer a(map, options, start);
  PfLocalizer b(map, options, Pose2{start.x_m + 0.5, start.y_m, start.yaw_rad});
  for (int k = 0; k < 5; ++k) {
    scan.stamp_s = room::kStart + 0.1 * k;
    b.process(scan, start, room::kMount);
    const PoseEstimate e = *a.process(scan, start, room::kMount);
    EXPECT_EQ(e.pose.x_m, expected[k].pose.x_m);
    EXPECT_EQ(e.pose.y_m, expected[k].pose.y_m);
    EXPECT_EQ(e.pose.yaw_rad, expected[k].pose.yaw_rad);
  }
}

// The top wall's beams are NaN (as `dispel filter` writes removed beams): they are not scored,
// and the other walls and the pillars hold the estimate. The odometry starts at the true pose here
// and no initial pose is given: the filter starts from the odometry.
TEST(SlamPfLocalization, InvalidBeamsDoNotBreakLocalisation) {
  BagOptions b = second_run();
  b.nan_top_wall = true;
  b.odom_from_origin = false;
  const SimRun run = write_bag("pf_nan.bag", b);
  LocalizationOptions o;
  o.input = run.path;
  o.map = slam_map();
  const LocalizationResult r = run_pf_localization(o);
  EXPECT_GT(r.beams_invalid, 30000);
  ASSERT_EQ(r.scans_used, static_cast<std::int64_t>(run.truth.size()));
  const eval::TrajectoryErrors pf = eval::compare_trajectories(run.truth, r.trajectory);
  std::printf("NaN top wall: %lld invalid beams, RMSE position %.4f m, yaw %.3f deg\n",
              static_cast<long long>(r.beams_invalid), pf.rmse_position_m, pf.rmse_yaw_rad / kDeg);
  EXPECT_LT(pf.rmse_position_m, 0.1);
  EXPECT_LT(max_error_after(run, r, 10), 0.1);
  std::remove(run.path.c_str());
}

// The room drawn into a grid whose frame is turned by 30 degrees and moved against the map
// frame: the estimates must come out in the map frame all the same.
TEST(SlamPfLocalization, GridOriginTurnedAgainstTheMapFrame) {
  GridMap map;
  map.resolution_m = 0.05;
  map.origin = {2.0, -3.5, 30.0 * kDeg};
  map.width = 220;
  map.height = 220;
  map.cells.assign(static_cast<std::size_t>(map.width * map.height), kUnknownCell);
  for (int row = 0; row < map.height; ++row) {
    for (int col = 0; col < map.width; ++col) {
      const Eigen::Vector2d p = map.origin.apply({(col + 0.5) * 0.05, (row + 0.5) * 0.05});
      const double x = p.x(), y = p.y();
      const double wall =
          std::min({std::abs(x), std::abs(x - 8.0), std::abs(y), std::abs(y - 6.0)});
      const double pillars = std::min(std::abs(std::hypot(x - 1.2, y - 4.8) - 0.25),
                                      std::abs(std::hypot(x - 6.5, y - 1.5) - 0.2));
      const bool inside = x > 0.0 && x < 8.0 && y > 0.0 && y < 6.0;
      std::int8_t& cell = map.cells[static_cast<std::size_t>(row * map.width + col)];
      if (std::min(wall, pillars) < 0.03) {
        cell = kOccupiedCell;
      } else if (inside) {
        cell = kFreeCell;
      }
    }
  }
  const SimRun run = write_bag("pf_turned.bag", second_run());
  LocalizationOptions o;
  o.input = run.path;
  o.map = map;
  o.initial_pose = rough_start(run);
  const LocalizationResult r = run_pf_localization(o);
  const eval::TrajectoryErrors pf = eval::compare_trajectories(run.truth, r.trajectory);
  std::printf("turned grid: RMSE position %.4f m, yaw %.3f deg\n", pf.rmse_position_m,
              pf.rmse_yaw_rad / kDeg);
  EXPECT_LT(pf.rmse_position_m, 0.1);
  EXPECT_LT(pf.rmse_yaw_rad, 1.0 * kDeg);
  std::remove(run.path.c_str());
}

// --- Bad input ----------------------------------------------------------------------------------

void expect_error(const LocalizationOptions& o, const std::string& expected) {
  room::expect_job_error([&] { run_pf_localization(o); }, expected,
                         o.input + " with map " + o.map_yaml);
}

using test::write_text;

TEST(SlamPfLocalizationBadInput, BadMapsBagsAndOptions) {
  const SimRun run = write_bag("pf_bad.bag", {});
  LocalizationOptions o;
  o.input = run.path;
  expect_error(o, "no map: set map_yaml");
  o.map_yaml = temp_path("no_such_map.yaml");
  expect_error(o, "no_such_map.yaml: No such file or directory");

  const std::string header =
      "resolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
  write_text("corrupt.pgm", "P5\n100 100\n255\n" + std::string(9990, '\xfe'));
  o.map_yaml = write_text("corrupt.yaml", "image: corrupt.pgm\n" + header);
  expect_error(o, "corrupt.pgm: image is 100 x 100 pixels but holds only 9990");
  // Fewer bytes than the header states pixels: refused before the pixels are allocated.
  write_text("short.pgm", "P5\n100 100\n255\n" + std::string(1000, '\xfe'));
  o.map_yaml = write_text("short.yaml", "image: short.pgm\n" + header);
  expect_error(o, "short.pgm: image is 100 x 100 pixels, more than the file's 1015 bytes");
  write_text("good.pgm", "P5\n2 2\n255\n" + std::string(4, '\xfe'));
  o.map_yaml = write_text("zero.yaml",
                          "image: good.pgm\nresolution: 0\norigin: [0, 0, 0]\n"
                          "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n");
  expect_error(o, "zero.yaml: resolution 0: must be a positive number");

  GridMap map;
  map.resolution_m = 0.0;
  map.width = map.height = 2;
  map.cells.assign(4, kFreeCell);
  o.map = map;
  expect_error(o, "map resolution 0 m: must be a positive number");
  map.resolution_m = 0.05;
  map.cells.pop_back();
  o.map = map;
  expect_error(o, "map of 2 x 2 cells holds 3 values");

  map.cells.assign(4, kFreeCell);
  o.map = map;
  o.filter.particles = 0;
  expect_error(o, "particles = 0: must be 1 to 10000000");
  o.filter = {};
  o.filter.likelihood_std_m = 0.0;
  expect_error(o, "likelihood_std_m = 0: must be > 0");
  o.filter = {};
  o.filter.initial_std_yaw_rad = std::nan("");
  expect_error(o, "initial_std_yaw_rad = nan: must be >= 0");
  o.filter = {};
  o.initial_pose = Pose2{std::nan(""), 0.0, 0.0};
  expect_error(o, "initial pose is not finite");
  o.initial_pose.reset();

  o.input = temp_path("does_not_exist.bag");
  expect_error(o, "does_not_exist.bag: No such file or directory");
  o.input = write_text("not_a_bag.bag", "hello\n");
  expect_error(o, "not a readable ROS 1 bag");
  const SimRun no_scans = write_bag("pf_no_scans.bag", {false, true, false, -135.0});
  o.input = no_scans.path;
  expect_error(o, "no sensor_msgs/LaserScan topic /scan");
  const SimRun no_odom = write_bag("pf_no_odom.bag", {false, false, true, -135.0});
  o.input = no_odom.path;
  expect_error(o, "no nav_msgs/Odometry topic /odom");
  std::remove(run.path.c_str());
  std::remove(no_scans.path.c_str());
  std::remove(no_odom.path.c_str());
}

}  // namespace
}  // namespace dispel::slam
