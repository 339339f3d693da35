#include "dispel/core/scan_registration.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>

#include "dispel/core/pose_buffer.hpp"
#include "dispel/sim/simulator.hpp"

namespace dispel {
namespace {

constexpr double kDeg = kPi / 180.0;

// The office floor of config/scenarios/office_corridors.yaml without people: a loop of 2.2 m
// corridors with rough walls, the robot at 1 m/s, a 768-beam 270-degree scanner at 7.5 Hz mounted
// off-centre and yawed 42 degrees, beams over the sweep, wheel odometry that drifts.
sim::Scenario office_loop(double duration_s) {
  sim::Scenario s;
  s.duration_s = duration_s;
  s.world.walls = {{{-1.1, -1.1}, {31.1, -1.1}}, {{31.1, -1.1}, {31.1, 15.1}},
                   {{31.1, 15.1}, {-1.1, 15.1}}, {{-1.1, 15.1}, {-1.1, -1.1}},
                   {{1.1, 1.1}, {28.9, 1.1}},    {{28.9, 1.1}, {28.9, 12.9}},
                   {{28.9, 12.9}, {1.1, 12.9}},  {{1.1, 12.9}, {1.1, 1.1}}};
  s.world.rough_walls = sim::RoughWalls{};
  s.robot.speed_mps = 1.0;
  s.robot.waypoints = {{30, 0}, {30, 14}, {0, 14}, {0, 0}};
  s.robot.laser_mount = {0.25, 0.12, 42.0 * kDeg};
  s.lidar.range_max_m = 11.0;
  s.lidar.fov_deg = 270.0;
  s.lidar.resolution_deg = 0.352;
  s.lidar.rate_hz = 7.5;
  s.lidar.range_noise_per_m = 0.002;
  s.lidar.incidence_noise = 0.5;
  s.lidar.mixed_pixels = 0.5;
  s.lidar.dropout = 0.005;
  s.lidar.sweep = true;
  s.sensors.wheel_scale_error = 0.02;
  s.sensors.wheel_difference_error = 0.003;
  return s;
}

struct Errors {
  double relative_1s_m = 0.0;  // RMS over all 1 s windows.
  double relative_1s_rad = 0.0;
  double along_1s_m = 0.0;       // Its part along the true motion over the window (RMS),
  double across_1s_m = 0.0;      // and across it.
  double max_1s_rad = 0.0;       // The largest over all 1 s windows.
  double relative_scan_m = 0.0;  // RMS over windows of one scan.
  double final_m = 0.0;          // Position error at the end.
  int registered = 0;
};

// Registers every scan (with or without the wheel odometry as the seed) and compares the poses
// with the truth (both expressed from their first pose); the map learns every beam (no people).
Errors run(const sim::SimulationOutput& out, const sim::Scenario& s, bool with_odometry,
           const RegistrationConfig& config = {}) {
  ScanRegistration reg{config};
  std::vector<Pose2> estimate, truth;
  Errors e;
  // The odometry at each scan's stamp, interpolated between its samples as the recordings' road
  // does (the simulator's 50 Hz samples fall up to 10 ms before a scan: 1 cm at 1 m/s).
  PoseBuffer odometry;
  for (const sim::SensorSample& m : out.sensors) odometry.add(m.stamp_s, m.odom_pose);
  for (const sim::ScanFrame& f : out.scans) {
    std::optional<Pose2> odom;
    if (with_odometry) {
      Pose2 at;
      EXPECT_TRUE(odometry.lookup(f.scan.stamp_s, at) == PoseLookup::kOk) << f.scan.stamp_s;
      odom = at * s.robot.laser_mount;
    }
    RegistrationReport report;
    estimate.push_back(reg.register_scan(f.scan, odom, report));
    truth.push_back(f.base_pose * s.robot.laser_mount);
    reg.add(std::vector<char>(f.scan.size(), 1), {});
    e.registered += report.registered ? 1 : 0;
  }
  const auto window = static_cast<std::size_t>(std::lround(s.lidar.rate_hz));  // 1 s.
  double sum_m = 0.0, sum_rad = 0.0, sum_along = 0.0, sum_scan = 0.0;
  std::size_t n = 0;
  for (std::size_t k = 0; k + window < estimate.size(); ++k, ++n) {
    const Pose2 de = estimate[k].inverse() * estimate[k + window];
    const Pose2 dt = truth[k].inverse() * truth[k + window];
    const Pose2 err = dt.inverse() * de;
    sum_m += err.translation().squaredNorm();
    sum_rad += err.yaw_rad * err.yaw_rad;
    e.max_1s_rad = std::max(e.max_1s_rad, std::abs(err.yaw_rad));
    // Along the true motion, in the frame of the window's start.
    const Eigen::Vector2d moved = dt.translation();
    const Eigen::Vector2d off = de.translation() - moved;
    if (moved.norm() > 1e-6) sum_along += std::pow(off.dot(moved) / moved.norm(), 2);
    const Pose2 step =
        (truth[k].inverse() * truth[k + 1]).inverse() * (estimate[k].inverse() * estimate[k + 1]);
    sum_scan += step.translation().squaredNorm();
  }
  const double windows = static_cast<double>(std::max<std::size_t>(1, n));
  e.relative_1s_m = std::sqrt(sum_m / windows);
  e.relative_1s_rad = std::sqrt(sum_rad / windows);
  e.along_1s_m = std::sqrt(sum_along / windows);
  e.across_1s_m = std::sqrt(std::max(0.0, sum_m - sum_along) / windows);
  e.relative_scan_m = std::sqrt(sum_scan / windows);
  const Pose2 end_e = estimate.front().inverse() * estimate.back();
  const Pose2 end_t = truth.front().inverse() * truth.back();
  e.final_m = (end_e.translation() - end_t.translation()).norm();
  return e;
}

// The registration on the simulator, 100 s around the office loop (100 m at 1 m/s). The issue's
// targets: relative pose error over 1 s below 1 cm and 0.2 degrees, less drift than the wheel
// odometry's, laser-only within twice the odometry-seeded error. Measured on seed 1, seeded: 1.2
// cm and 0.10 degrees over 1 s, 0.05 m after 100 m (wheel odometry: 13.2 m). Seed 1 is the
// luckiest of eight: over seeds 1-8 (DISPEL_REGISTRATION_SEEDS=8) 1.43 cm (1.17-2.01) and 0.110
// degrees (0.100-0.153), laser-only 7.1 cm (3.7-12.6) and 0.61 degrees, 5.0 times the seeded
// error. The 1 cm target is not reached; the error is along the corridors (docs/results.md,
// "Registration"). Laser-only on seed 1: 3.4 cm and 0.62 degrees over 1 s (its scans are not
// de-skewed), 0.14 m after 100 m (4.0 cm, 0.61 degrees and 0.12 m before the laser-only rules of
// RegistrationConfig::lateral_noise_mps: the first scans, whose map is young, hold sideways).
// (Seeded, before the map's own normals for far walls: 1.6 cm, 0.11 degrees, 0.09 m; with the
// odometry's last sample before each scan instead of its value at the scan's stamp: 1.6 cm, 0.12
// degrees, 0.007 m; before the simulated robot rounded its corners: 1.7 cm, 0.17 degrees, 0.03 m;
// laser-only 6.4 cm, 0.61 degrees, 0.05 m.)
TEST(ScanRegistration, DrivingAlongRoughCorridorsBeatsTheWheelOdometry) {
  // DISPEL_REGISTRATION_SEEDS=N runs seeds 1 to N (docs/results.md: seed 1 alone is not the
  // registration's error) and prints each seed's figures and their means; CI runs seed 1.
  const char* seeds_env = std::getenv("DISPEL_REGISTRATION_SEEDS");
  const int seeds = seeds_env != nullptr ? std::max(1, std::atoi(seeds_env)) : 1;
  // DISPEL_DESKEW_LASER_ONLY_TURN=1 runs laser-only with registration.deskew_laser_only_turn
  // (docs/results.md, "De-skewing laser-only scans by their turn").
  RegistrationConfig laser_only_config;
  laser_only_config.deskew_laser_only_turn =
      std::getenv("DISPEL_DESKEW_LASER_ONLY_TURN") != nullptr;
  const sim::Scenario s = office_loop(100.0);
  double sum_seeded_m = 0.0, sum_seeded_rad = 0.0, sum_laser_only_m = 0.0, sum_laser_only_rad = 0.0;
  for (int seed = 1; seed <= seeds; ++seed) {
    const sim::SimulationOutput out = sim::simulate(s, static_cast<std::uint64_t>(seed));
    const Errors seeded = run(out, s, true);
    const Errors laser_only_loop = run(out, s, false, laser_only_config);
    // The wheel odometry's own drift over the same path.
    const Pose2 o0 = out.sensors.front().odom_pose, o1 = out.sensors.back().odom_pose;
    const Pose2 t0 = out.sensors.front().true_pose, t1 = out.sensors.back().true_pose;
    const double odometry_final_m =
        ((o0.inverse() * o1).translation() - (t0.inverse() * t1).translation()).norm();
    const auto scans = static_cast<int>(out.scans.size());
    EXPECT_GE(seeded.registered, scans - scans / 50) << seed;
    // Seed 1: 0.0163 m with every far wall point to point; seeds 1-8 1.1-1.5 cm (docs/results.md).
    EXPECT_LT(seeded.relative_1s_m, seed == 1 ? 0.014 : 0.025) << seed;
    // 0.28 degrees on seed 3 while a slip bent the scans (AScanDeSkewedByASlippingWheelIsBentBack).
    EXPECT_LT(seeded.relative_1s_rad, 0.2 * kDeg) << seed;
    EXPECT_LT(seeded.final_m, 0.1 * odometry_final_m) << seed;
    // Laser-only: it ran away along the first corridor (37 m off after 100 m) while its scans
    // were de-skewed by the guessed motion, and oscillated and diverged while the guess was the
    // last scan's motion alone (2.8 m over 1 s in the first 20 s); with either, these bounds
    // fail. With room for another build's rounding (with 0.3 or 0.7 for velocity_smoothing: 6 cm,
    // 0.4-0.7 m).
    EXPECT_GE(laser_only_loop.registered, scans - scans / 50) << seed;
    EXPECT_LT(laser_only_loop.relative_1s_m, 0.15) << seed;
    EXPECT_LT(laser_only_loop.relative_1s_rad, 1.0 * kDeg) << seed;
    EXPECT_LT(laser_only_loop.final_m, 0.2 * odometry_final_m) << seed;
    std::printf(
        "seed %d, loop, relative 1 s: seeded %.4f m %.3f deg (along the motion %.4f m, across "
        "%.4f m; one scan %.4f m; at most %.3f deg), laser-only %.4f m %.3f deg (along %.4f m, "
        "across %.4f m); after %.0f s seeded %.3f m, laser-only %.3f m, wheel odometry %.3f m\n",
        seed, seeded.relative_1s_m, seeded.relative_1s_rad / kDeg, seeded.along_1s_m,
        seeded.across_1s_m, seeded.relative_scan_m, seeded.max_1s_rad / kDeg,
        laser_only_loop.relative_1s_m, laser_only_loop.relative_1s_rad / kDeg,
        laser_only_loop.along_1s_m, laser_only_loop.across_1s_m, s.duration_s, seeded.final_m,
        laser_only_loop.final_m, odometry_final_m);
    sum_seeded_m += seeded.relative_1s_m;
    sum_seeded_rad += seeded.relative_1s_rad;
    sum_laser_only_m += laser_only_loop.relative_1s_m;
    sum_laser_only_rad += laser_only_loop.relative_1s_rad;
  }
  std::printf(
      "mean of %d seeds, relative 1 s: seeded %.4f m %.3f deg, laser-only %.4f m %.3f deg "
      "(%.1f x)\n",
      seeds, sum_seeded_m / seeds, sum_seeded_rad / seeds / kDeg, sum_laser_only_m / seeds,
      sum_laser_only_rad / seeds / kDeg, sum_laser_only_m / sum_seeded_m);

  const sim::Scenario straight = office_loop(20.0);
  const sim::SimulationOutput first = sim::simulate(straight, 1);
  const Errors seeded_straight = run(first, straight, true);
  const Errors laser_only = run(first, straight, false);
  EXPECT_GE(seeded_straight.registered, static_cast<int>(first.scans.size()) - 5);
  EXPECT_LT(laser_only.relative_1s_m, 0.15);
  std::printf(
      "First 20 s, seed 1: seeded %.4f m %.3f deg, laser-only %.4f m %.3f deg, end %.3f / %.3f "
      "m\n",
      seeded_straight.relative_1s_m, seeded_straight.relative_1s_rad / kDeg,
      laser_only.relative_1s_m, laser_only.relative_1s_rad / kDeg, seeded_straight.final_m,
      laser_only.final_m);
}

// registration.deskew_laser_only_turn (off by default): laser-only scans de-skewed by their
// turn. The office loop's 768-beam scans sweep 270 degrees in 0.1 s; at a corner a scan turned
// by 2-3 degrees while it swept, and aligned as measured its turn came out wrong. Over 1 s:
// 0.62 degrees without, 0.11 with (seed 1; seeds 1-20: 0.60 and 0.10, the seeded registration's
// 0.11). Along the corridors the error stays what it was (seed 1: 3.4 cm without, 5.2 cm with;
// seeds 1-20: 6.9 and 4.5 cm on average, 4.0 and 3.7 cm median).
TEST(ScanRegistration, LaserOnlyScansDeSkewedByTheirTurnAlignTheirTurn) {
  const sim::Scenario s = office_loop(100.0);
  const sim::SimulationOutput out = sim::simulate(s, 1);
  RegistrationConfig turned;
  turned.deskew_laser_only_turn = true;
  const Errors as_measured = run(out, s, false);
  const Errors deskewed = run(out, s, false, turned);
  const auto scans = static_cast<int>(out.scans.size());
  EXPECT_GE(deskewed.registered, scans - scans / 50);
  EXPECT_GT(as_measured.relative_1s_rad, 0.4 * kDeg);
  EXPECT_LT(deskewed.relative_1s_rad, 0.2 * kDeg);
  EXPECT_LT(deskewed.max_1s_rad, as_measured.max_1s_rad);
  EXPECT_LT(deskewed.relative_1s_m, 0.15);
  std::printf(
      "laser-only over 1 s: as measured %.4f m %.3f deg, de-skewed by the turn %.4f m %.3f deg\n",
      as_measured.relative_1s_m, as_measured.relative_1s_rad / kDeg, deskewed.relative_1s_m,
      deskewed.relative_1s_rad / kDeg);
}

// The nearest map point of each sample point is found through shortcuts: from the second
// iteration on, among a short list of the candidates near where the point was (while it cannot
// have a nearer one elsewhere), and not at all for a point that stays farther from every
// candidate than the threshold. They must change nothing: every pose and report, seeded by the
// wheel odometry and laser-only, is the same bit for bit as with every candidate walked at every
// iteration (ScanRegistration::search_exhaustively).
TEST(ScanRegistration, TheNearestSearchsShortcutsChangeNoPose) {
  const sim::Scenario s = office_loop(20.0);
  const sim::SimulationOutput out = sim::simulate(s, 2);
  PoseBuffer odometry;
  for (const sim::SensorSample& m : out.sensors) odometry.add(m.stamp_s, m.odom_pose);
  for (const bool with_odometry : {true, false}) {
    ScanRegistration fast{RegistrationConfig{}}, exhaustive{RegistrationConfig{}};
    exhaustive.search_exhaustively(true);
    int iterations = 0, compared = 0;
    for (const sim::ScanFrame& f : out.scans) {
      std::optional<Pose2> odom;
      if (with_odometry) {
        Pose2 at;
        ASSERT_TRUE(odometry.lookup(f.scan.stamp_s, at) == PoseLookup::kOk);
        odom = at * s.robot.laser_mount;
      }
      RegistrationReport a, b;
      const Pose2 pa = fast.register_scan(f.scan, odom, a);
      const Pose2 pb = exhaustive.register_scan(f.scan, odom, b);
      ASSERT_EQ(pa.x_m, pb.x_m) << "scan " << compared << " odometry " << with_odometry;
      ASSERT_EQ(pa.y_m, pb.y_m) << "scan " << compared;
      ASSERT_EQ(pa.yaw_rad, pb.yaw_rad) << "scan " << compared;
      ASSERT_EQ(a.inlier_share, b.inlier_share) << "scan " << compared;
      ASSERT_EQ(a.residual_m, b.residual_m) << "scan " << compared;
      ASSERT_EQ(a.total_iterations, b.total_iterations) << "scan " << compared;
      iterations += a.total_iterations;
      ++compared;
      fast.add(std::vector<char>(f.scan.size(), 1), {});
      exhaustive.add(std::vector<char>(f.scan.size(), 1), {});
    }
    EXPECT_GT(compared, 140);
    EXPECT_GT(iterations, 2 * compared);  // The later iterations, where the shortcuts are, ran.
  }
}

// A wheel that slips: the odometry turns 10 degrees in each of four scans (40 degrees in half a
// second) while the robot drives straight on, then goes on from that heading (the simulator's
// slips at 1.5 m/s turned it 27 degrees: a warehouse run whose map turned by 17 degrees with the
// slip lost 4 % of its walls). The odometry's motion parts from the constant-velocity guess; the
// guess is tried too and matches the scan, and the registered heading holds. Without the guess
// (measured): 40 degrees and 5.7 m off at the end; with 7 degrees a scan the office's walls
// still pulled the odometry's seed back.
TEST(ScanRegistration, AWheelThatSlipsDoesNotTurnTheMap) {
  const sim::Scenario s = office_loop(16.0);
  const sim::SimulationOutput out = sim::simulate(s, 1);
  ScanRegistration reg{RegistrationConfig{}};
  std::size_t sensor = 0;
  Pose2 previous_odometry, slipped;
  int overruled = 0, k = 0, more_alignments = 0;
  Pose2 first_estimate, first_truth, estimate, truth;
  for (const sim::ScanFrame& f : out.scans) {
    while (sensor + 1 < out.sensors.size() && out.sensors[sensor + 1].stamp_s <= f.scan.stamp_s)
      ++sensor;
    const Pose2 odometry = out.sensors[sensor].odom_pose;
    const Pose2 delta = previous_odometry.inverse() * odometry;
    slipped = slipped * delta * Pose2{0.0, 0.0, k >= 60 && k < 64 ? 10.0 * kDeg : 0.0};
    previous_odometry = odometry;
    RegistrationReport report;
    estimate = reg.register_scan(f.scan, slipped * s.robot.laser_mount, report);
    truth = f.base_pose * s.robot.laser_mount;
    if (k == 0) {
      first_estimate = estimate;
      first_truth = truth;
    }
    reg.add(std::vector<char>(f.scan.size(), 1), {});
    overruled += report.odometry_overruled ? 1 : 0;
    if (report.odometry_overruled) {
      EXPECT_GE(report.alignments, 2);  // The odometry's seed and the guess's, at least.
      EXPECT_GT(report.total_iterations, report.iterations);
    }
    more_alignments += report.alignments > 1 ? 1 : 0;
    ++k;
  }
  const Pose2 moved_estimate = first_estimate.inverse() * estimate;
  const Pose2 moved_truth = first_truth.inverse() * truth;
  EXPECT_GE(overruled, 1);
  EXPECT_GE(more_alignments, overruled);
  EXPECT_LT(more_alignments, k / 4);  // Most scans are aligned once.
  EXPECT_LT(std::abs(wrap_angle(moved_estimate.yaw_rad - moved_truth.yaw_rad)), 1.0 * kDeg);
  EXPECT_LT((moved_estimate.translation() - moved_truth.translation()).norm(), 0.3);
  const Pose2 odometry_moved = Pose2{}.inverse() * slipped;  // The odometry starts at the origin.
  EXPECT_GT(std::abs(wrap_angle(odometry_moved.yaw_rad - moved_truth.yaw_rad)), 20.0 * kDeg);
}

// The simulator's wheel slips (one wheel reads 30 % fast for 0.5 s: the odometry turns by 3-6
// degrees a scan), one every 10 s along the office loop for 40 s. The scan is de-skewed by the
// odometry's motion since the previous scan, and a slip that starts or ends between two scans
// bends it; the alignment of a bent scan from a seed turned by the slip came out 1-2 degrees off
// (on the office loop with its usual slips, 0.5 a minute, seed 3 had 0.28 degrees over 1 s
// against the target's 0.2). Now the constant-velocity guess tried against a slip is aligned on
// the scan de-skewed by the guess, and a scan whose registered turn bends it against the turn it
// was de-skewed by is de-skewed by the registered turn and aligned again. Measured, seeds 1 / 2 /
// 3: RMS over 1 s 0.087 / 0.083 / 0.111 degrees, at most 0.43 / 0.46 / 0.50 (before: 0.343 /
// 0.255 / 0.486, at most 2.2 / 1.6 / 2.4).
TEST(ScanRegistration, AScanDeSkewedByASlippingWheelIsBentBack) {
  sim::Scenario s = office_loop(40.0);
  s.sensors.slips_per_minute = 6.0;
  for (const std::uint64_t seed : {1, 2, 3}) {
    const sim::SimulationOutput out = sim::simulate(s, seed);
    const Errors e = run(out, s, true);
    EXPECT_LT(e.relative_1s_rad, 0.2 * kDeg) << seed;
    EXPECT_LT(e.max_1s_rad, 0.6 * kDeg) << seed;
    std::printf("seed %d: relative 1 s %.3f deg (at most %.3f), %.4f m\n", static_cast<int>(seed),
                e.relative_1s_rad / kDeg, e.max_1s_rad / kDeg, e.relative_1s_m);
  }
}

// A corridor with nothing ahead: the scans say nothing about the motion along it. The
// registration holds the seed along it instead of sliding, and its degeneracy measure flags such
// scans: 20 of 46 measured. It flagged none while the far walls, seen at grazing angles and
// without normals from their scans, were matched point to point: those matches gave information
// along the corridor that the walls do not have (the map's own normals for them, map_normal()).
TEST(ScanRegistration, ACorridorWithNothingAheadKeepsTheSeedAlongIt) {
  sim::Scenario s = office_loop(6.0);
  s.world.walls = {{{-50, -1.1}, {50, -1.1}}, {{-50, 1.1}, {50, 1.1}}};
  s.world.rough_walls.reset();
  s.robot.waypoints = {{40, 0}};
  s.robot.speed_mps = 1.0;
  const sim::SimulationOutput out = sim::simulate(s, 3);
  ScanRegistration reg{RegistrationConfig{}};
  int degenerate = 0, registered = 0;
  for (const sim::ScanFrame& f : out.scans) {
    RegistrationReport report;
    // The seed: the truth, so any slide along the corridor is the registration's.
    const Pose2 seed = f.base_pose * s.robot.laser_mount;
    const Pose2 p = reg.register_scan(f.scan, seed, report);
    reg.add(std::vector<char>(f.scan.size(), 1), {});
    if (!report.registered) continue;
    ++registered;
    degenerate += report.degenerate ? 1 : 0;
    EXPECT_LT((p.translation() - seed.translation()).norm(), 0.1) << f.scan.stamp_s;
  }
  EXPECT_GT(registered, 30);
  EXPECT_GE(degenerate, registered / 4);
  std::printf("%d of %d registered scans degenerate\n", degenerate, registered);
}

// A scan of a hall with nothing in range but 16 thin posts (0.1 m across, 2-5 m away; table or
// shelf legs) by a 720-beam scanner at @p pose: 2-4 returns per post.
LaserScan posts_scan(const Pose2& pose, double stamp_s) {
  LaserScan scan;
  scan.stamp_s = stamp_s;
  scan.angle_min_rad = -kPi;
  scan.angle_increment_rad = 0.5 * kDeg;
  scan.range_min_m = 0.1F;
  scan.range_max_m = 20.0F;
  constexpr double kRadius_m = 0.05;
  std::vector<Eigen::Vector2d> posts;
  for (int k = 0; k < 16; ++k) {
    const double range = 2.0 + 0.2 * static_cast<double>(k), bearing = 0.39 * k;
    posts.emplace_back(range * std::cos(bearing), range * std::sin(bearing));
  }
  for (int b = 0; b < 720; ++b) {
    const double bearing = pose.yaw_rad + scan.bearing_rad(static_cast<std::size_t>(b));
    const Eigen::Vector2d o = pose.translation(), d(std::cos(bearing), std::sin(bearing));
    float nearest = std::numeric_limits<float>::infinity();
    for (const Eigen::Vector2d& c : posts) {
      const double along = (c - o).dot(d);
      const double across2 = (c - o).squaredNorm() - along * along;
      if (along <= 0.0 || across2 > kRadius_m * kRadius_m) continue;
      nearest =
          std::min(nearest, static_cast<float>(along - std::sqrt(kRadius_m * kRadius_m - across2)));
    }
    scan.ranges_m.push_back(nearest);
  }
  return scan;
}

// Returns far from any map point: a seed 0.42 m off puts every point of the scan that far from
// its post's points in the map, and no map point lies within the 0.2 m the registration first
// looks in; the correspondences lie within the threshold (still its initial 0.5 m). Laser-only,
// the scanner still for six scans (a young map: the first of them match any voxel, not only
// structure), then moved by (0.3, -0.3) m and 2 degrees, which the constant-velocity guess does
// not know. The registration finds the moved pose; with correspondences sought only within
// 0.2 m it finds none and falls back to the seed.
TEST(ScanRegistration, ReturnsFarFromTheSeedStillFindTheirCorrespondences) {
  // A sideways jump: as an omnidirectional robot moves, so the sideways hold is off (this scene
  // matches fewer points than min_points_with_odometry, where it would hold).
  RegistrationConfig config;
  config.lateral_noise_mps = 0.0;
  ScanRegistration reg{config};
  RegistrationReport report;
  for (int k = 0; k < 6; ++k) {
    const Pose2 p = reg.register_scan(posts_scan(Pose2{}, 0.1 * k), std::nullopt, report);
    EXPECT_LT(p.translation().norm(), 0.01) << k;
    reg.add(std::vector<char>(720, 1), {});
  }
  const Pose2 moved{0.3, -0.3, 2.0 * kDeg};
  const Pose2 p = reg.register_scan(posts_scan(moved, 0.6), std::nullopt, report);
  EXPECT_TRUE(report.registered);
  EXPECT_LT((p.translation() - moved.translation()).norm(), 0.02);
  EXPECT_LT(std::abs(wrap_angle(p.yaw_rad - moved.yaw_rad)), 0.5 * kDeg);
  std::printf("registered %.4f %.4f %.3f deg (truth %.2f %.2f %.1f deg), %d points, inliers %.2f\n",
              p.x_m, p.y_m, p.yaw_rad / kDeg, moved.x_m, moved.y_m, moved.yaw_rad / kDeg,
              report.points, report.inlier_share);
}

// A sensor known not to move (align false): each scan stays at the pose given, even when the
// scan itself says otherwise, and the map is still built for what it explains. The posts seen
// from 5 cm and 1 degree away, with the odometry at the identity: aligned, the pose moves toward
// the scan's; not aligned, it is the identity, exactly.
TEST(ScanRegistration, AScanOfASensorThatDoesNotMoveStaysAtThePoseGiven) {
  for (const bool align : {true, false}) {
    RegistrationConfig config;
    config.align = align;
    config.min_points_with_odometry = config.min_points;  // The posts are few points.
    ScanRegistration reg{config};
    RegistrationReport report;
    for (int k = 0; k < 6; ++k) {
      reg.register_scan(posts_scan(Pose2{}, 0.1 * k), Pose2{}, report);
      reg.add(std::vector<char>(720, 1), {});
    }
    EXPECT_GT(reg.voxel_count(), 10u);
    const Pose2 off{0.05, 0.0, 1.0 * kDeg};
    const Pose2 p = reg.register_scan(posts_scan(off, 0.6), Pose2{}, report);
    if (align) {
      EXPECT_TRUE(report.registered);
      // Toward the scan's pose (the odometry's low noise holds some of it back).
      EXPECT_GT(p.translation().dot(off.translation().normalized()), 0.01);
      EXPECT_GT(p.yaw_rad, 0.2 * kDeg);
    } else {
      EXPECT_FALSE(report.registered);
      EXPECT_FALSE(report.fallback);
      EXPECT_EQ(p.x_m, 0.0);
      EXPECT_EQ(p.y_m, 0.0);
      EXPECT_EQ(p.yaw_rad, 0.0);
    }
  }
}

// The scanner still for six scans, then driving 0.3 m a scan of 0.1 s (3 m/s) past the posts,
// then a scan with nothing in it (it falls back to the constant-velocity guess). On a robot that
// can drive 1 m/s the guess never exceeds that (counted), so the empty scan moves the pose by at
// most 0.1 m; on one that can drive 5 m/s the guess follows the registered motion. Without the
// limit, a poorly registered scene taught the guess up to 34 m/s, and every fallback carried it on.
TEST(ScanRegistration, TheConstantVelocityGuessStaysWithinWhatTheRobotCanDo) {
  for (const double limit_mps : {1.0, 5.0}) {
    ScanRegistration reg{RegistrationConfig{}, SpeedLimits{limit_mps, 3.0}};
    RegistrationReport report;
    double t = 0.0;
    for (int k = 0; k < 6; ++k, t += 0.1) {
      reg.register_scan(posts_scan(Pose2{}, t), std::nullopt, report);
      reg.add(std::vector<char>(720, 1), {});
    }
    int limited = 0;
    Pose2 p;
    for (int k = 1; k <= 4; ++k, t += 0.1) {
      const Pose2 truth{0.3 * k, 0.0, 0.0};
      p = reg.register_scan(posts_scan(truth, t), std::nullopt, report);
      EXPECT_TRUE(report.registered) << limit_mps << " " << k;
      EXPECT_LT((p.translation() - truth.translation()).norm(), 0.02) << limit_mps << " " << k;
      limited += report.guess_limited ? 1 : 0;
      reg.add(std::vector<char>(720, 1), {});
    }
    LaserScan empty = posts_scan(Pose2{}, t);
    std::fill(empty.ranges_m.begin(), empty.ranges_m.end(), std::numeric_limits<float>::infinity());
    const Pose2 q = reg.register_scan(empty, std::nullopt, report);
    EXPECT_TRUE(report.fallback);
    const double step_m = (q.translation() - p.translation()).norm();
    if (limit_mps < 3.0) {
      EXPECT_GE(limited, 3);
      EXPECT_LE(step_m, 0.1 + 1e-9);
    } else {
      EXPECT_EQ(limited, 0);
      EXPECT_GT(step_m, 0.2);
    }
  }
}

// Laser-only, the scanner turning in place at 0.5 rad/s among the posts for 1 s (registered),
// then ten scans with nothing in them (fallbacks, 1 s). The guessed turn decays over them
// (fallback_turn_decay_s, 0.25 s): the first fallback turns by the whole 0.05 rad of a scan, each
// next one by exp(-0.1 / 0.25) of the one before, 0.15 rad in all. Carried on (0: off) it turns
// 0.5 rad. A guessed turn carried through a run of fallbacks spun a sparse
// laser-only recording's pose a full circle.
TEST(ScanRegistration, AGuessedTurnDecaysOverScansThatDoNotRegister) {
  for (const double decay_s : {0.25, 0.0}) {
    RegistrationConfig config;
    config.fallback_turn_decay_s = decay_s;
    ScanRegistration reg{config};
    RegistrationReport report;
    double t = 0.0;
    Pose2 p;
    for (int k = 0; k <= 10; ++k, t += 0.1) {
      const Pose2 truth{0.0, 0.0, 0.05 * k};
      p = reg.register_scan(posts_scan(truth, t), std::nullopt, report);
      if (k > 0) {
        EXPECT_TRUE(report.registered) << k;
      }
      EXPECT_LT(std::abs(wrap_angle(p.yaw_rad - truth.yaw_rad)), 0.5 * kDeg) << k;
      reg.add(std::vector<char>(720, 1), {});
    }
    const double before = p.yaw_rad;
    LaserScan empty = posts_scan(Pose2{}, t);
    std::fill(empty.ranges_m.begin(), empty.ranges_m.end(), std::numeric_limits<float>::infinity());
    for (int k = 0; k < 10; ++k, t += 0.1) {
      empty.stamp_s = t;
      p = reg.register_scan(empty, std::nullopt, report);
      EXPECT_TRUE(report.fallback) << k;
    }
    const double turned = wrap_angle(p.yaw_rad - before);
    if (decay_s > 0.0) {
      EXPECT_NEAR(turned, 0.15, 0.03);
    } else {
      EXPECT_NEAR(turned, 0.5, 0.05);
    }
  }
}

// Laser-only around the office loop (its scanner yawed 42 degrees on the robot): the direction the
// sensor drives along, learnt from the scans that registered, is the robot's forward direction in
// the sensor frame, -42 degrees (either way along it). The map is rich here (hundreds of points
// matched), so the sideways motion is never held (that is for a scan that matched fewer than
// min_points_with_odometry).
TEST(ScanRegistration, ALaserOnlySensorLearnsWhichWayItDrives) {
  const sim::Scenario s = office_loop(30.0);
  const sim::SimulationOutput out = sim::simulate(s, 1);
  ScanRegistration reg{RegistrationConfig{}};
  int held = 0;
  for (const sim::ScanFrame& f : out.scans) {
    RegistrationReport report;
    reg.register_scan(f.scan, std::nullopt, report);
    reg.add(std::vector<char>(f.scan.size(), 1), {});
    held += report.held_sideways ? 1 : 0;
  }
  // Either way along the axis: the angle modulo 180 degrees.
  const double off = std::remainder(reg.learnt_heading_rad() - (-42.0 * kDeg), kPi);
  EXPECT_LT(std::abs(off), 3.0 * kDeg) << reg.learnt_heading_rad() / kDeg;
  EXPECT_LE(held, 3);
  std::printf("learnt heading %.1f deg (mount -42.0), held sideways in %d scans\n",
              reg.learnt_heading_rad() / kDeg, held);
}

// Something seen for a second is structure that explains its own beams. Unseen for 2 s, it is
// seen again: when the scanner has long seen through its place meanwhile (long_free), what stood
// there left, and what is there now (a cart back on its track) is a newcomer, its voxels started
// afresh and explaining nothing until it has been there explained_min_span_s. Without that
// evidence the old voxels explain it at once.
TEST(ScanRegistration, AVoxelHitAgainWhereTheScannerLongSawThroughIsStartedAfresh) {
  for (const bool seen_through : {false, true}) {
    ScanRegistration reg{RegistrationConfig{}};
    RegistrationReport report;
    const auto explained_beams = [&reg]() {
      int n = 0;
      for (std::size_t b = 0; b < 720; ++b) n += reg.explained(b) ? 1 : 0;
      return n;
    };
    for (int k = 0; k < 10; ++k) {
      reg.register_scan(posts_scan(Pose2{}, 0.1 * k), std::nullopt, report);
      reg.add(std::vector<char>(720, 1), {});
    }
    const LaserScan scan = posts_scan(Pose2{}, 1.0);
    const auto returns = static_cast<int>(std::count_if(scan.ranges_m.begin(), scan.ranges_m.end(),
                                                        [](float r) { return r < 20.0F; }));
    ASSERT_GE(returns, 32);  // 2-4 per post.
    reg.register_scan(scan, std::nullopt, report);
    EXPECT_GE(explained_beams(), returns - 2);  // Structure, seen now and then.
    reg.add(std::vector<char>(720, 1), {});
    reg.register_scan(posts_scan(Pose2{}, 3.0), std::nullopt, report);  // Unseen for 2 s.
    EXPECT_EQ(explained_beams(), 0);  // Not hit within explained_max_age_s.
    const auto long_free = [seen_through](const Eigen::Vector2d&) { return seen_through; };
    reg.add(std::vector<char>(720, 1), {}, long_free);
    EXPECT_EQ(reg.voxels_restarted() > 0, seen_through);
    reg.register_scan(posts_scan(Pose2{}, 3.1), std::nullopt, report);
    if (seen_through) {
      EXPECT_EQ(explained_beams(), 0);
    } else {
      EXPECT_GE(explained_beams(), returns - 2);
    }
  }
}

TEST(ScanRegistration, BadConfigurationsNameTheField) {
  RegistrationConfig c;
  c.voxel_size_m = 0.0;
  try {
    ScanRegistration r{c};
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("registration.voxel_size_m"), std::string::npos);
  }
  c = RegistrationConfig{};
  c.explained_distance_m = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(ScanRegistration{c}, std::invalid_argument);
  c = RegistrationConfig{};
  c.lateral_noise_mps = -0.1;
  try {
    ScanRegistration r{c};
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("registration.lateral_noise_mps"), std::string::npos);
  }
  c.lateral_noise_mps = 1e-300;  // Would pin the sideways motion with an infinite weight.
  EXPECT_THROW(ScanRegistration{c}, std::invalid_argument);
  c = RegistrationConfig{};
  c.fallback_turn_decay_s = std::numeric_limits<double>::infinity();
  EXPECT_THROW(ScanRegistration{c}, std::invalid_argument);
  c = RegistrationConfig{};
  for (const double bad : {-0.5, std::numeric_limits<double>::quiet_NaN()}) {
    c.slide_tolerance_mps = bad;
    try {
      ScanRegistration r{c};
      ADD_FAILURE() << bad;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("registration.slide_tolerance_mps"), std::string::npos);
    }
  }
}

}  // namespace
}  // namespace dispel
