#include "dispel/sim/simulator.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <set>

namespace dispel::sim {
namespace {

constexpr double kDeg = kPi / 180.0;

Scenario room_with_walker() {
  Scenario s;
  s.duration_s = 6.0;
  s.world.walls = {{{-5, -5}, {5, -5}}, {{5, -5}, {5, 5}}, {{5, 5}, {-5, 5}}, {{-5, 5}, {-5, -5}}};
  s.world.circles = {{{-3.0, 3.0}, 0.3}};
  s.robot.speed_mps = 0.0;
  s.lidar.range_noise_m = 0.0;
  s.lidar.dropout = 0.0;
  Actor walker;
  walker.waypoints = {{2.0, -3.0}, {2.0, 1.0}};  // 4 s of walking, then standing.
  walker.speed_mps = 1.0;
  walker.loop = false;
  s.actors = {walker};
  return s;
}

Eigen::Vector2d beam_point(const ScanFrame& f, const Pose2& laser, std::size_t i) {
  const double b = f.scan.bearing_rad(i);
  const double r = f.scan.ranges_m[i];
  return laser.apply({r * std::cos(b), r * std::sin(b)});
}

TEST(Simulator, LabelsMatchTheGeometryAndLegsOccludeTheWall) {
  const Scenario s = room_with_walker();
  const SimulationOutput out = simulate(s, 3);
  ASSERT_EQ(out.scans.size(), 121u);  // 6 s at 20 Hz, both ends included.
  ASSERT_EQ(out.actor_count, 1);
  const Pose2 laser = s.robot.laser_mount;
  int leg_beams = 0;
  for (const ScanFrame& f : out.scans) {
    for (std::size_t i = 0; i < f.truth.size(); ++i) {
      const Eigen::Vector2d p = beam_point(f, laser, i);
      switch (f.truth[i]) {
        case Truth::kStatic: {
          // On a wall or the pillar.
          const bool wall =
              std::abs(std::abs(p.x()) - 5.0) < 1e-3 || std::abs(std::abs(p.y()) - 5.0) < 1e-3;
          const bool pillar = std::abs((p - Eigen::Vector2d(-3.0, 3.0)).norm() - 0.3) < 1e-3;
          EXPECT_TRUE(wall || pillar) << p.transpose();
          EXPECT_EQ(f.actor[i], 0);
          break;
        }
        case Truth::kMoving:
        case Truth::kStill:
          EXPECT_EQ(f.actor[i], 1);
          EXPECT_NEAR(p.x(), 2.0, 0.3);  // A leg of the walker at x = 2.
          EXPECT_LT(f.scan.ranges_m[i],
                    (Eigen::Vector2d(5.0, p.y() * 5.0 / p.x()) - laser.translation()).norm());
          ++leg_beams;
          break;
        case Truth::kNoReturn:
          EXPECT_FALSE(std::isfinite(f.scan.ranges_m[i]) && f.scan.ranges_m[i] > 0.0F);
          break;
      }
    }
  }
  EXPECT_GT(leg_beams, 500);
  // While walking the walker is moving; at the end of its path it stands still.
  EXPECT_EQ(std::count(out.scans[20].truth.begin(), out.scans[20].truth.end(), Truth::kStill), 0);
  const ScanFrame& last = out.scans.back();
  EXPECT_GT(std::count(last.truth.begin(), last.truth.end(), Truth::kStill), 0);
  EXPECT_EQ(std::count(last.truth.begin(), last.truth.end(), Truth::kMoving), 0);
}

TEST(Simulator, SameSeedSameOutputAndOtherSeedsDiffer) {
  Scenario s = room_with_walker();
  s.lidar.range_noise_m = 0.01;
  s.lidar.dropout = 0.01;
  s.random_people = {3, {-4, -4}, {4, 4}, 0.5, 1.5, 2.0, 4};
  const SimulationOutput a = simulate(s, 42);
  const SimulationOutput b = simulate(s, 42);
  const SimulationOutput c = simulate(s, 43);
  ASSERT_EQ(a.scans.size(), b.scans.size());
  for (std::size_t k = 0; k < a.scans.size(); ++k) {
    ASSERT_EQ(0, std::memcmp(a.scans[k].scan.ranges_m.data(), b.scans[k].scan.ranges_m.data(),
                             a.scans[k].scan.ranges_m.size() * sizeof(float)));
    ASSERT_EQ(a.scans[k].truth, b.scans[k].truth);
  }
  for (std::size_t k = 0; k < a.sensors.size(); ++k) {
    ASSERT_EQ(a.sensors[k].imu_yaw_rate_radps, b.sensors[k].imu_yaw_rate_radps);
  }
  bool differ = false;
  for (std::size_t k = 0; k < a.scans.size() && !differ; ++k) {
    differ = a.scans[k].truth != c.scans[k].truth;
  }
  EXPECT_TRUE(differ);
}

TEST(Simulator, MaskedSectorsAndTheRangeLimitReturnNothing) {
  Scenario s = room_with_walker();
  s.lidar.masked_sectors_deg = {{-52.5, -9.5}, {9.5, 52.5}};
  s.lidar.range_limit_m = 4.0;
  const SimulationOutput out = simulate(s, 1, 0.5);
  for (const ScanFrame& f : out.scans) {
    for (std::size_t i = 0; i < f.truth.size(); ++i) {
      const double deg = f.scan.bearing_rad(i) / kDeg;
      const bool masked = (deg >= -52.5 && deg <= -9.5) || (deg >= 9.5 && deg <= 52.5);
      if (masked) {
        EXPECT_TRUE(std::isnan(f.scan.ranges_m[i])) << deg;
        EXPECT_EQ(f.truth[i], Truth::kNoReturn);
      }
      if (f.truth[i] != Truth::kNoReturn) {
        EXPECT_LE(f.scan.ranges_m[i], 4.05F);
      }
    }
  }
}

TEST(Simulator, RobotFollowsTheLawnmowerAndOdometryDriftsFromTheTruth) {
  Scenario s;
  s.duration_s = 60.0;
  s.robot.speed_mps = 0.5;
  s.robot.lawnmower = Lawnmower{{0.0, 0.0}, 6.0, 2.0, 3};
  s.world.walls = {{{-10, -10}, {20, -10}}};
  const SimulationOutput out = simulate(s, 5);
  double max_y = 0.0, max_x = 0.0;
  for (const SensorSample& k : out.sensors) {
    max_y = std::max(max_y, k.true_pose.y_m);
    max_x = std::max(max_x, k.true_pose.x_m);
  }
  EXPECT_NEAR(max_x, 6.0 + 1.0, 0.3);  // Lanes of 6 m plus the U-turn's radius.
  EXPECT_NEAR(max_y, 4.0, 0.4);  // Three lanes 2 m apart; limited acceleration overshoots a bit.
  const SensorSample& end = out.sensors.back();
  const double drift = (end.odom_pose.translation() - end.true_pose.translation()).norm();
  EXPECT_GT(drift, 0.001);  // The wheels have scale error and noise...
  EXPECT_LT(drift, 2.0);    // ...but odometry stays usable.
}

TEST(Scenario, BadValuesAreRejectedByName) {
  Scenario s;
  s.lidar.resolution_deg = 0.0;
  EXPECT_THROW(s.validate(), std::invalid_argument);
  s = Scenario{};
  s.actors = {Actor{}};
  try {
    s.validate();
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("actors[0]"), std::string::npos);
  }
}

}  // namespace
}  // namespace dispel::sim
