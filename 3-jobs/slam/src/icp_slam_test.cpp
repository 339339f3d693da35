#include "dispel/slam/icp_slam.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "dispel/eval/trajectory_error.hpp"
#include "dispel/jobs/job.hpp"
#include "room_bag.hpp"
#include "test_files.hpp"

namespace dispel::slam {
namespace {

using jobs::JobError;
using test::temp_path;

using room::BagOptions;
using room::kDeg;
using room::SimRun;
using room::write_bag;

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

// MRPT's ICP-SLAM never recovers from a first map of a few stray points (no match is ever
// accepted again: it follows odometry to the end, with one map point). A filter with presumption
// of guilt gives such first scans. The engine starts with the first scan that has enough valid
// beams, and follows odometry until then.
TEST(SlamIcp, StartsWithTheFirstScanThatHasEnoughBeams) {
  BagOptions opt;
  opt.nan_first_scans = 10;  // One second of scans with 9 valid beams each.
  const SimRun run = write_bag("slam_empty_start.bag", opt);
  SlamOptions o;
  o.input = run.path;
  const SlamResult r = run_icp_slam_full(o);
  ASSERT_EQ(r.trajectory.size(), run.truth.size());
  // Before the start the estimate is the odometry.
  for (int k = 0; k < 10; ++k) {
    EXPECT_EQ(r.trajectory[static_cast<std::size_t>(k)].x_m,
              r.odometry[static_cast<std::size_t>(k)].x_m);
  }
  const eval::TrajectoryErrors slam = eval::compare_trajectories(run.truth, r.trajectory);
  const eval::TrajectoryErrors odometry = eval::compare_trajectories(run.truth, r.odometry);
  std::printf("sparse first scans: RMSE position %.4f m (odometry %.4f m), %zu map points\n",
              slam.rmse_position_m, odometry.rmse_position_m, r.map_points.size());
  EXPECT_LT(slam.rmse_position_m, 0.1);
  EXPECT_LT(slam.rmse_position_m, odometry.rmse_position_m / 4.0);
  EXPECT_GT(r.map_points.size(), 1000u);
  std::remove(run.path.c_str());
}

// A scan with fewer valid beams than [dispel] min_valid_beams (120) is not matched: the estimate
// is the last matched one moved by the odometry since, exactly. (On the SLAM scenario's U-turn,
// scans of 12-130 beams pulled MRPT's ICP-SLAM by 0.3-6 m: docs/slam.md.)
TEST(SlamIcp, AScanWithTooFewBeamsIsCarriedByTheOdometry) {
  LaserScan room_scan;  // Inside a circle of 3 m: 360 beams.
  room_scan.angle_min_rad = -kPi;
  room_scan.angle_increment_rad = kPi / 180.0;
  room_scan.range_max_m = 10.0F;
  room_scan.ranges_m.assign(360, 3.0F);
  IcpSlamEngine engine(default_engine_config());
  const Pose2 start{1.0, 2.0, 0.3};
  const std::optional<Pose2> first = engine.process(room_scan, start, Pose2{});
  ASSERT_TRUE(first.has_value());
  EXPECT_NEAR(first->x_m, start.x_m, 1e-9);
  EXPECT_NEAR(first->y_m, start.y_m, 1e-9);

  LaserScan sparse = room_scan;  // 119 valid beams.
  for (std::size_t b = 119; b < sparse.ranges_m.size(); ++b) sparse.ranges_m[b] = NAN;
  sparse.stamp_s = 0.1;
  const Pose2 moved = start * Pose2{0.3, -0.1, 0.05};
  const std::optional<Pose2> carried = engine.process(sparse, moved, Pose2{});
  ASSERT_TRUE(carried.has_value());
  const Pose2 expected = *first * (start.inverse() * moved);
  EXPECT_NEAR(carried->x_m, expected.x_m, 1e-9);
  EXPECT_NEAR(carried->y_m, expected.y_m, 1e-9);
  EXPECT_NEAR(carried->yaw_rad, expected.yaw_rad, 1e-9);
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

// The occupied cells of @p g within 0.15 m of one of the room's walls (0-3: bottom, right, top,
// left), away from the corners, and the line fitted through their centres.
struct WallFit {
  std::int64_t cells = 0;
  double offset_m = 0.0;   // Mean distance across the wall (its x or y).
  double angle_rad = 0.0;  // Of the fitted line against the wall.
};

WallFit fit_wall(const GridMap& g, int wall) {
  const bool horizontal = wall == 0 || wall == 2;
  const double at = wall == 0 ? 0.0 : wall == 1 ? 8.0 : wall == 2 ? 6.0 : 0.0;
  double sa = 0.0, sb = 0.0, saa = 0.0, sab = 0.0;
  WallFit fit;
  for (int row = 0; row < g.height; ++row) {
    for (int col = 0; col < g.width; ++col) {
      if (g.at(col, row) != kOccupiedCell) continue;
      const double x = g.origin.x_m + (col + 0.5) * g.resolution_m;
      const double y = g.origin.y_m + (row + 0.5) * g.resolution_m;
      const double along = horizontal ? x : y;
      const double across = horizontal ? y : x;
      const double length = horizontal ? 8.0 : 6.0;
      if (std::abs(across - at) > 0.15 || along < 0.5 || along > length - 0.5) continue;
      sa += along;
      sb += across;
      saa += along * along;
      sab += along * across;
      ++fit.cells;
    }
  }
  if (fit.cells < 2) return fit;
  const double n = static_cast<double>(fit.cells);
  fit.offset_m = sb / n - at;
  fit.angle_rad = std::atan((n * sab - sa * sb) / (n * saa - sa * sa));
  return fit;
}

// Free cells in a band just below the top wall.
std::int64_t free_cells_below_top_wall(const GridMap& g) {
  std::int64_t n = 0;
  for (int row = 0; row < g.height; ++row) {
    for (int col = 0; col < g.width; ++col) {
      const double x = g.origin.x_m + (col + 0.5) * g.resolution_m;
      const double y = g.origin.y_m + (row + 0.5) * g.resolution_m;
      n += y > 5.7 && y < 5.9 && x > 1.0 && x < 7.0 && g.at(col, row) == kFreeCell;
    }
  }
  return n;
}

TEST(SlamIcp, GridMapPutsTheWallsWhereTheyAre) {
  const SimRun run = write_bag("slam_grid.bag", {});
  SlamOptions o;
  o.input = run.path;
  const SlamResult r = run_icp_slam_full(o);
  const GridMap& g = r.grid;
  ASSERT_NO_THROW(g.validate());
  EXPECT_EQ(g.resolution_m, 0.05);
  EXPECT_EQ(g.origin.yaw_rad, 0.0);
  // The room (8 x 6 m) and no more than a few cells around it.
  EXPECT_LE(g.origin.x_m, -0.05);
  EXPECT_LE(g.origin.y_m, -0.05);
  EXPECT_GE(g.origin.x_m + g.width * g.resolution_m, 8.05);
  EXPECT_GE(g.origin.y_m + g.height * g.resolution_m, 6.05);
  EXPECT_LT(g.width * g.resolution_m, 9.0);
  EXPECT_LT(g.height * g.resolution_m, 7.0);
  std::printf("grid %d x %d cells, %lld occupied, %lld free, %lld free below the top wall\n",
              g.width, g.height, static_cast<long long>(g.occupied_cells()),
              static_cast<long long>(g.free_cells()),
              static_cast<long long>(free_cells_below_top_wall(g)));
  for (int wall = 0; wall < 4; ++wall) {
    const WallFit fit = fit_wall(g, wall);
    std::printf("wall %d: %lld cells, offset %.4f m, angle %.3f deg\n", wall,
                static_cast<long long>(fit.cells), fit.offset_m, fit.angle_rad / kDeg);
    EXPECT_GT(fit.cells, 100) << "wall " << wall;
    EXPECT_LT(std::abs(fit.offset_m), 0.03) << "wall " << wall;
    // SLAM's own yaw error is about 0.2 degrees; beams spread over aperture / n instead of
    // aperture / (n - 1) would add 0.4.
    EXPECT_LT(std::abs(fit.angle_rad), 0.45 * kDeg) << "wall " << wall;
  }
  EXPECT_GT(free_cells_below_top_wall(g), 400);
  std::remove(run.path.c_str());
}

TEST(SlamIcp, InvalidBeamsNeitherFillNorClearGridCells) {
  const SimRun run = write_bag("slam_grid_nan.bag", {true, true, true, -135.0});
  SlamOptions o;
  o.input = run.path;
  const SlamResult r = run_icp_slam_full(o);
  const WallFit top = fit_wall(r.grid, room::kTopWall);
  std::printf("NaN top wall: %lld occupied cells on it, %lld free cells below it\n",
              static_cast<long long>(top.cells),
              static_cast<long long>(free_cells_below_top_wall(r.grid)));
  EXPECT_EQ(top.cells, 0);
  EXPECT_LT(free_cells_below_top_wall(r.grid), 100);
  EXPECT_GT(fit_wall(r.grid, 0).cells, 100);
  std::remove(run.path.c_str());
}

// --- Bad input ----------------------------------------------------------------------------------

void expect_error(const SlamOptions& o, const std::string& expected) {
  room::expect_job_error([&] { run_icp_slam(o); }, expected, o.input);
}

using test::write_text;

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

TEST(SlamIcpBadInput, MapResolutionMustBePositive) {
  const SimRun run = write_bag("slam_bad_resolution.bag", {false, true, true, -135.0});
  SlamOptions o;
  o.input = run.path;
  o.map_resolution_m = 0.0;
  expect_error(o, "map_resolution_m = 0");
  o.map_resolution_m = -0.05;
  expect_error(o, "must be a positive number of metres per cell");
  std::remove(run.path.c_str());
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
