#include "dispel/sim/simulator.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <set>
#include <stdexcept>
#include <string>
#include <tuple>

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

TEST(Simulator, AStreamedRunIsTheHeldRunInTimeOrder) {
  Scenario s = room_with_walker();
  s.lidar.range_noise_m = 0.01;
  s.lidar.dropout = 0.01;
  s.robot.speed_mps = 0.5;
  s.robot.waypoints = {{1.0, 0.0}, {1.0, 1.0}, {0.0, 1.0}};
  s.random_people = {3, {-4, -4}, {4, 4}, 0.5, 1.5, 2.0, 4};
  const SimulationOutput held = simulate(s, 7);
  // The stream as it comes: (stamp, 0 for a scan or 1 for a sensor sample, index in its kind).
  std::vector<ScanFrame> scans;
  std::vector<SensorSample> sensors;
  std::vector<std::pair<double, int>> order;
  SimulationSink sink;
  sink.scan = [&](ScanFrame&& f) {
    order.emplace_back(f.scan.stamp_s, 0);
    scans.push_back(std::move(f));
  };
  sink.sensor = [&](const SensorSample& x) {
    order.emplace_back(x.stamp_s, 1);
    sensors.push_back(x);
  };
  const std::int32_t actors = simulate(s, 7, 0.0, sink);
  EXPECT_EQ(actors, held.actor_count);
  EXPECT_EQ(actors, 4);
  ASSERT_EQ(scans.size(), held.scans.size());
  ASSERT_EQ(sensors.size(), held.sensors.size());
  ASSERT_EQ(scans.size(), 121u);
  ASSERT_EQ(sensors.size(), 301u);
  // In time order; at the same instant the scan before the sensor sample.
  for (std::size_t k = 1; k < order.size(); ++k) {
    ASSERT_LE(order[k - 1], order[k]) << k;
  }
  bool moving_seen = false;
  for (std::size_t k = 0; k < scans.size(); ++k) {
    const ScanFrame& a = scans[k];
    const ScanFrame& b = held.scans[k];
    ASSERT_EQ(a.scan.ranges_m.size(), b.scan.ranges_m.size());
    ASSERT_EQ(0, std::memcmp(a.scan.ranges_m.data(), b.scan.ranges_m.data(),
                             a.scan.ranges_m.size() * sizeof(float)));
    ASSERT_EQ(a.scan.stamp_s, b.scan.stamp_s);
    ASSERT_EQ(a.truth, b.truth);
    ASSERT_EQ(a.actor, b.actor);
    ASSERT_EQ(a.base_pose.translation(), b.base_pose.translation());
    ASSERT_EQ(a.base_pose.yaw_rad, b.base_pose.yaw_rad);
    moving_seen = moving_seen || std::count(a.truth.begin(), a.truth.end(), Truth::kMoving) > 0;
  }
  EXPECT_TRUE(moving_seen);
  for (std::size_t k = 0; k < sensors.size(); ++k) {
    const SensorSample& a = sensors[k];
    const SensorSample& b = held.sensors[k];
    ASSERT_EQ(a.stamp_s, b.stamp_s);
    ASSERT_EQ(a.wheel_left_mps, b.wheel_left_mps);
    ASSERT_EQ(a.wheel_right_mps, b.wheel_right_mps);
    ASSERT_EQ(a.imu_yaw_rate_radps, b.imu_yaw_rate_radps);
    ASSERT_EQ(a.odom_pose.translation(), b.odom_pose.translation());
    ASSERT_EQ(a.odom_pose.yaw_rad, b.odom_pose.yaw_rad);
    ASSERT_EQ(a.true_pose.translation(), b.true_pose.translation());
    ASSERT_EQ(a.true_v_mps, b.true_v_mps);
    ASSERT_EQ(a.true_w_radps, b.true_w_radps);
  }
}

// A day-long run must not empty the hall: the random people walk their waypoints round and
// round, so that in every minute of a long run people are seen moving.
TEST(Simulator, RandomPeopleKeepComingAndGoing) {
  Scenario s;
  s.world.walls = {{{-10, -10}, {10, -10}},
                   {{10, -10}, {10, 10}},
                   {{10, 10}, {-10, 10}},
                   {{-10, 10}, {-10, -10}}};
  s.robot.speed_mps = 0.0;
  s.lidar.fov_deg = 360.0;
  s.lidar.resolution_deg = 1.0;
  s.lidar.rate_hz = 2.0;
  s.sensors.rate_hz = 1.0;
  s.random_people = {4, {-8, -8}, {8, 8}, 0.5, 1.5, 3.0, 3};
  constexpr int kMinutes = 10;
  std::vector<std::set<std::int32_t>> moving_per_minute(kMinutes);
  SimulationSink sink;
  sink.scan = [&](ScanFrame&& f) {
    const auto minute = static_cast<std::size_t>((f.scan.stamp_s - s.start_time_s) / 60.0);
    if (minute >= moving_per_minute.size()) return;
    for (std::size_t i = 0; i < f.truth.size(); ++i) {
      if (f.truth[i] == Truth::kMoving) moving_per_minute[minute].insert(f.actor[i]);
    }
  };
  ASSERT_EQ(simulate(s, 5, kMinutes * 60.0, sink), 4);
  for (int m = 0; m < kMinutes; ++m) {
    // Every one of the four walked in every minute (a pause is at most 3 s).
    EXPECT_EQ(moving_per_minute[static_cast<std::size_t>(m)].size(), 4u) << "minute " << m;
  }
  // With loop: false each walks its three waypoints once (at most 3 x 16 m): the hall is still
  // by the last minute.
  s.random_people.loop = false;
  for (auto& seen : moving_per_minute) seen.clear();
  ASSERT_EQ(simulate(s, 5, kMinutes * 60.0, sink), 4);
  EXPECT_EQ(moving_per_minute.front().size(), 4u);
  EXPECT_TRUE(moving_per_minute.back().empty());
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

// Stops: the robot brakes to a halt at a stop's start and stands until its end, then drives on;
// a person stands from their stop's start (beams of them are then truth "standing") and walks on
// after it. A person following the robot's path stops with it, as person_following_outdoor_1's
// robot and the person it follows stand together for minutes.
TEST(Simulator, StopsHoldTheRobotAndAPersonStillAndBothGoOnAfter) {
  Scenario s;
  s.duration_s = 30.0;
  s.world.walls = {{{-5, -5}, {40, -5}}, {{-5, 5}, {40, 5}}};
  s.robot.speed_mps = 1.0;
  s.robot.waypoints = {{35.0, 0.0}};
  s.robot.loop = false;
  s.robot.stops = {{5.0, 10.0}};
  s.lidar.fov_deg = 180.0;
  s.lidar.resolution_deg = 1.0;
  s.lidar.rate_hz = 10.0;
  Actor walker;
  walker.waypoints = {{3.0, 0.0}, {38.0, 0.0}};
  walker.speed_mps = 1.0;
  walker.loop = false;
  walker.stops = {{4.8, 10.4}};
  s.actors = {walker};
  const SimulationOutput out = simulate(s, 3);
  const auto pose_at = [&](double run_s) {
    for (const SensorSample& k : out.sensors) {
      if (k.stamp_s - s.start_time_s >= run_s) return k.true_pose;
    }
    return out.sensors.back().true_pose;
  };
  // It brakes within 1.5 m of where it was at 5 s (its motors slow it by at most 0.5 m/s a
  // second) and stands from then until 15 s.
  const Pose2 at_stop = pose_at(5.0), halted = pose_at(8.0), before_end = pose_at(14.9);
  EXPECT_GT(at_stop.x_m, 3.5);
  EXPECT_LT(halted.x_m - at_stop.x_m, 1.5);
  EXPECT_NEAR(before_end.x_m, halted.x_m, 1e-9);
  EXPECT_NEAR(before_end.y_m, halted.y_m, 1e-9);
  EXPECT_GT(pose_at(25.0).x_m, before_end.x_m + 5.0);  // And drove on.
  // The person: standing while stopped, walking before and after.
  std::int32_t standing_during = 0, moving_during = 0, moving_after = 0;
  for (const ScanFrame& f : out.scans) {
    const double run_s = f.scan.stamp_s - s.start_time_s;
    for (std::size_t i = 0; i < f.truth.size(); ++i) {
      if (f.actor[i] != 1) continue;
      const bool during = run_s > 5.0 && run_s < 15.0;
      standing_during += during && f.truth[i] == Truth::kStill;
      moving_during += during && f.truth[i] == Truth::kMoving;
      moving_after += run_s > 15.5 && f.truth[i] == Truth::kMoving;
    }
  }
  EXPECT_GT(standing_during, 500);
  EXPECT_EQ(moving_during, 0);
  EXPECT_GT(moving_after, 100);
}

// gait: planted. A still scanner sees a person walk past 2 m away at 1 m/s. With the planted
// gait each foot stands while the body passes over it: between scans 0.05 s apart a leg's points
// stay put (within 1 cm) in about 60 % of the steps (measured 0.56) and in the others move up to
// 2.5 times the walking speed (12.5 cm a scan; the points' centre moves more where a leg is partly
// hidden: measured at most 18 cm). With the default sway each leg is always moving, at least a
// third of the walking speed (1.7 cm a scan; measured: no step under 1 cm).
TEST(Simulator, APlantedGaitStandsEachFootWhileTheBodyPassesOverIt) {
  Scenario s;
  s.duration_s = 5.0;
  s.robot.speed_mps = 0.0;
  s.lidar.fov_deg = 180.0;
  s.lidar.resolution_deg = 0.1;
  s.lidar.rate_hz = 20.0;
  s.lidar.range_noise_m = 0.0;
  s.lidar.dropout = 0.0;
  Actor walker;
  walker.waypoints = {{-2.0, 2.0}, {3.0, 2.0}};
  walker.speed_mps = 1.0;
  walker.loop = false;
  s.actors = {walker};
  // The centres of the two legs' points per scan (the person's beams split at the widest gap
  // between neighbouring points); seen false when one leg hides the other.
  struct Legs {
    bool seen = false;
    std::array<Eigen::Vector2d, 2> centre{Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()};
  };
  const auto legs = [](const ScanFrame& f) {
    std::vector<Eigen::Vector2d> points;
    for (std::size_t i = 0; i < f.truth.size(); ++i) {
      if (f.actor[i] != 1) continue;
      const double a = f.scan.bearing_rad(i);
      points.emplace_back(f.scan.ranges_m[i] * std::cos(a), f.scan.ranges_m[i] * std::sin(a));
    }
    Legs out;
    if (points.size() < 4) return out;
    std::size_t cut = 1;
    for (std::size_t k = 1; k < points.size(); ++k) {
      if ((points[k] - points[k - 1]).norm() > (points[cut] - points[cut - 1]).norm()) cut = k;
    }
    if ((points[cut] - points[cut - 1]).norm() < 0.05) return out;
    for (std::size_t k = 0; k < points.size(); ++k) out.centre[k < cut ? 0 : 1] += points[k];
    out.centre[0] /= static_cast<double>(cut);
    out.centre[1] /= static_cast<double>(points.size() - cut);
    out.seen = true;
    return out;
  };
  for (const Gait gait : {Gait::kSway, Gait::kPlanted}) {
    s.gait = gait;
    const SimulationOutput out = simulate(s, 1);
    int still = 0, steps = 0;
    double fastest = 0.0;
    Legs before;
    for (const ScanFrame& f : out.scans) {
      const Legs now = legs(f);
      if (now.seen && before.seen) {
        // Which is which swaps as one passes the other: each is matched to the nearer leg of
        // the scan before.
        for (const Eigen::Vector2d& leg : now.centre) {
          const double d =
              std::min((leg - before.centre[0]).norm(), (leg - before.centre[1]).norm());
          ++steps;
          still += d < 0.01 ? 1 : 0;
          fastest = std::max(fastest, d);
        }
      }
      before = now;
    }
    ASSERT_GT(steps, 80) << "the legs were not seen apart often enough to test";
    const double share = static_cast<double>(still) / steps;
    if (gait == Gait::kPlanted) {
      EXPECT_GT(share, 0.45) << steps;
      EXPECT_GT(fastest, 0.09);
      EXPECT_LT(fastest, 0.25);
    } else {
      EXPECT_LT(share, 0.05) << steps;
    }
  }
}

// A path through a wall (or a corner taken too fast) would record what no robot can see: the
// run is refused, naming the time and place.
TEST(Simulator, ARobotThatWouldDriveThroughAWallIsRefused) {
  Scenario s;
  s.duration_s = 10.0;
  s.world.walls = {{{3.0, -2.0}, {3.0, 2.0}}};
  s.robot.speed_mps = 1.0;
  s.robot.waypoints = {{6.0, 0.0}};
  try {
    simulate(s, 1);
    ADD_FAILURE() << "drove through the wall";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("drove through a wall"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("at (3.0"), std::string::npos) << e.what();
  }
  s.robot.waypoints = {{2.0, 0.0}, {2.0, 3.0}, {6.0, 3.0}};  // Around its end: fine.
  EXPECT_NO_THROW(simulate(s, 1));
}

// Scripted people and vehicles go past walls, furniture and pillars, not through them: such a
// scenario is refused before any work, naming the actor and the obstacle. The shipped office had a
// walker brush 0.11 m through a cabinet and the forklift scenario a forklift drive into a pillar.
TEST(Simulator, AnActorWhosePathGoesThroughSomethingIsRefused) {
  const auto refused = [](const Scenario& s, const std::string& what) {
    try {
      run_duration(s, 0.0);
      ADD_FAILURE() << "accepted: " << what;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  Scenario s = room_with_walker();  // A pillar of 0.3 m at (-3, 3); the walker along x = 2.
  EXPECT_NO_THROW(run_duration(s, 0.0));
  s.actors[0].waypoints = {{-3.0, -3.0}, {-3.0, 4.0}};
  refused(s, "actors[0] (a person) goes through the circle at (-3.00, 3.00)");
  s.actors[0].waypoints = {{-3.5, -3.0}, {-3.5, 4.0}};  // Its legs 0.04 m from the pillar: fine.
  EXPECT_NO_THROW(run_duration(s, 0.0));
  s.actors[0].waypoints = {{-3.0, 4.5}, {-1.0, 4.5}, {-3.0, 1.5}};
  s.actors[0].loop = false;  // Walked once: past the pillar.
  EXPECT_NO_THROW(run_duration(s, 0.0));
  s.actors[0].loop = true;  // Back to its start, through the pillar.
  refused(s, "actors[0] (a person) goes through the circle");
  s.actors[0].loop = false;
  Actor cart;
  cart.kind = ActorKind::kCart;
  cart.length_m = 2.0;
  cart.width_m = 1.0;
  cart.waypoints = {{0.0, -3.0}, {3.5, -3.0}};  // Its nose 1 m beyond (3.5, -3): 0.5 m from x = 5.
  s.actors = {cart};
  EXPECT_NO_THROW(run_duration(s, 0.0));
  s.actors[0].waypoints = {{0.0, -3.0}, {4.1, -3.0}};  // The nose 0.1 m into the wall at x = 5.
  refused(s, "actors[0] (a vehicle) goes through the wall");
  s.actors[0].waypoints = {{0.0, -4.7}, {3.0, -4.7}};  // Its side 0.2 m into the wall at y = -5.
  refused(s, "actors[0] (a vehicle) goes through the wall");
  s.world.rectangles = {{{1.0, 1.0}, 1.0, 1.0, 0.0}};
  s.actors[0].waypoints = {{-4.0, 1.0}, {4.0, 1.0}};
  refused(s, "goes through the rectangle at (1.00, 1.00)");
  EXPECT_THROW(simulate(s, 1), std::invalid_argument);  // simulate() asks the same.
}

// A real scanner measures its beams over the sweep: with sweep on, beam i is measured
// i * time_increment after the stamp, from where the turning robot is then.
TEST(Simulator, BeamsAreMeasuredOverTheSweepWhileTheRobotTurns) {
  Scenario s = room_with_walker();
  s.actors.clear();
  s.duration_s = 3.0;
  s.robot.speed_mps = 0.5;
  s.robot.waypoints = {{0.0, 3.0}, {0.0, -3.0}};  // A sharp turn toward the first waypoint.
  s.lidar.rate_hz = 10.0;
  s.lidar.resolution_deg = 0.5;
  const SimulationOutput at_once = simulate(s, 1);
  s.lidar.sweep = true;
  const SimulationOutput swept = simulate(s, 1);
  ASSERT_EQ(at_once.scans.size(), swept.scans.size());
  EXPECT_EQ(at_once.scans[5].scan.time_increment_s, 0.0);
  EXPECT_NEAR(swept.scans[5].scan.time_increment_s, 0.5 / (360.0 * 10.0), 1e-12);
  // The first beams are measured at the stamp and agree; the last ones, 75 ms later in a turn,
  // do not.
  int first_differ = 0, last_differ = 0;
  for (std::size_t k = 1; k < swept.scans.size(); ++k) {
    const auto& a = at_once.scans[k].scan.ranges_m;
    const auto& b = swept.scans[k].scan.ranges_m;
    for (std::size_t i = 0; i < 8; ++i) first_differ += std::abs(a[i] - b[i]) > 0.02F;
    for (std::size_t i = a.size() - 8; i < a.size(); ++i)
      last_differ += std::abs(a[i] - b[i]) > 0.02F;
  }
  EXPECT_EQ(first_differ, 0);
  EXPECT_GT(last_differ, 20);
}

// Rough walls: a wall becomes pieces set back and forth, doors, glass gaps and furniture legs,
// drawn from the seed; the same seed gives the same building, every return stays static.
TEST(Simulator, RoughWallsHaveRecessesGapsAndLegsAndStayStatic) {
  Scenario s = room_with_walker();
  s.actors.clear();
  s.duration_s = 0.5;
  s.world.walls = {{{-10, -3}, {10, -3}}, {{-10, 3}, {10, 3}}};
  const SimulationOutput smooth = simulate(s, 4);
  s.world.rough_walls = RoughWalls{};
  s.world.rough_walls->glass_share = 0.3;
  const SimulationOutput rough = simulate(s, 4);
  const SimulationOutput again = simulate(s, 4);
  const SimulationOutput other = simulate(s, 5);
  EXPECT_EQ(rough.scans[0].scan.ranges_m, again.scans[0].scan.ranges_m);
  EXPECT_NE(rough.scans[0].scan.ranges_m, other.scans[0].scan.ranges_m);
  // The smooth walls are lines at |y| = 3; the rough ones are not, and their glass lets beams out.
  const Pose2 laser = rough.scans[0].base_pose * s.robot.laser_mount;
  int off_line = 0, no_return = 0, smooth_no_return = 0;
  for (std::size_t i = 0; i < rough.scans[0].scan.size(); ++i) {
    const ScanFrame& f = rough.scans[0];
    smooth_no_return += smooth.scans[0].truth[i] == Truth::kNoReturn;
    if (f.truth[i] == Truth::kNoReturn) {
      ++no_return;
      continue;
    }
    EXPECT_EQ(f.truth[i], Truth::kStatic);
    const Eigen::Vector2d p = beam_point(f, laser, i);
    off_line += std::abs(std::abs(p.y()) - 3.0) > 0.02 && std::abs(p.x()) < 9.0;
  }
  EXPECT_GT(off_line, 50);
  EXPECT_GT(no_return, smooth_no_return + 20);
}

// Low things against the walls (a chair seat, a box below a scan plane tilted up) return only to
// beams from nearer than 0.8-2 m; from farther the beams see the wall behind them.
TEST(Simulator, LowThingsAreSeenOnlyFromNearby) {
  Scenario s = room_with_walker();
  s.actors.clear();
  s.duration_s = 0.5;
  s.world.walls = {{{-10, -1.5}, {10, -1.5}}, {{-10, 1.5}, {10, 1.5}}};
  s.world.rough_walls = RoughWalls{};
  s.world.rough_walls->amplitude_m = 0.0;
  s.world.rough_walls->doors_per_10m = 0.0;
  s.world.rough_walls->legs_per_10m = 0.0;
  s.world.rough_walls->glass_share = 0.0;
  s.world.rough_walls->low_things_per_10m = 10.0;
  const SimulationOutput out = simulate(s, 4);
  const ScanFrame& f = out.scans[0];
  const Pose2 laser = f.base_pose * s.robot.laser_mount;
  int low = 0, wall = 0;
  for (std::size_t i = 0; i < f.scan.size(); ++i) {
    if (f.truth[i] == Truth::kNoReturn) continue;
    const Eigen::Vector2d p = beam_point(f, laser, i);
    if (std::abs(p.y()) < 1.45) {
      ++low;
      EXPECT_LE(f.scan.ranges_m[i], 2.0F + 0.1F) << "beam " << i;
    } else {
      ++wall;  // Including behind low things farther along it than they are seen from.
    }
  }
  EXPECT_GT(low, 10);
  EXPECT_GT(wall, 200);
}

// People and carts walk past furniture, not through it: the furniture legs and low things of rough
// walls leave every actor's path room to pass (the legs reach 0.16 m from the path, and a gap of
// 0.05 m). In the simulated office a walker had gone through a low thing for seconds: the map
// explained its leg there, and the filter kept it. The things in nobody's way are drawn the same.
TEST(Simulator, FurnitureLeavesEveryPathRoomToPass) {
  Scenario s = room_with_walker();
  s.duration_s = 0.5;
  s.world.walls = {{{-10, -1.5}, {10, -1.5}}, {{-10, 1.5}, {10, 1.5}}};
  s.world.circles.clear();
  s.world.rough_walls = RoughWalls{};
  RoughWalls& rw = *s.world.rough_walls;
  rw.amplitude_m = 0.0;
  rw.doors_per_10m = 0.0;
  rw.glass_share = 0.0;
  rw.legs_per_10m = 10.0;
  rw.low_things_per_10m = 10.0;
  rw.low_things_min_seen_within_m = rw.low_things_max_seen_within_m = 20.0;
  s.actors[0].waypoints = {{-9.0, -1.0},
                           {9.0, -1.0}};  // 0.5 m from the wall, through the furniture.
  s.actors[0].loop = true;
  const SimulationOutput with_walker = simulate(s, 4);
  s.actors.clear();
  const SimulationOutput without = simulate(s, 4);
  const ScanFrame& f = with_walker.scans[0];
  const ScanFrame& g = without.scans[0];
  const Pose2 laser = f.base_pose * s.robot.laser_mount;
  int in_the_way = 0, in_the_way_without = 0, upper = 0;
  for (std::size_t i = 0; i < f.scan.size(); ++i) {
    if (g.truth[i] == Truth::kStatic) {
      const Eigen::Vector2d q = beam_point(g, laser, i);
      in_the_way_without += std::abs(q.y() + 1.0) < 0.21 && std::abs(q.x()) < 9.0 ? 1 : 0;
      if (q.y() > 0.0) {  // The other side of the corridor: nobody walks there.
        ++upper;
        EXPECT_EQ(f.scan.ranges_m[i], g.scan.ranges_m[i]) << "beam " << i;
      }
    }
    if (f.truth[i] != Truth::kStatic) continue;
    const Eigen::Vector2d p = beam_point(f, laser, i);
    in_the_way += std::abs(p.y() + 1.0) < 0.21 && std::abs(p.x()) < 9.0 ? 1 : 0;
  }
  EXPECT_EQ(in_the_way, 0);
  EXPECT_GT(in_the_way_without, 20);  // Without the walker, things stand where it would walk.
  EXPECT_GT(upper, 200);
}

// Their size and the range they are hit from come from the scenario: larger things hit from
// farther (what negative_2 showed), here 0.4-0.6 m across and hit from within 2.5-3 m. In a
// corridor 6 m wide a thing's near side is 2.05-2.75 m from the robot on its axis: the default
// (hit from within at most 2 m) would show none of them.
TEST(Simulator, LowThingsTakeTheirSizeAndRangeFromTheScenario) {
  Scenario s = room_with_walker();
  s.actors.clear();
  s.world.circles.clear();
  s.duration_s = 0.5;
  s.world.walls = {{{-10, -3.0}, {10, -3.0}}, {{-10, 3.0}, {10, 3.0}}};
  RoughWalls rw;
  rw.amplitude_m = 0.0;
  rw.doors_per_10m = 0.0;
  rw.legs_per_10m = 0.0;
  rw.glass_share = 0.0;
  rw.low_things_per_10m = 10.0;
  rw.low_things_min_radius_m = 0.2;
  rw.low_things_max_radius_m = 0.3;
  rw.low_things_min_seen_within_m = 2.5;
  rw.low_things_max_seen_within_m = 3.0;
  s.world.rough_walls = rw;
  const SimulationOutput out = simulate(s, 4);
  const ScanFrame& f = out.scans[0];
  const Pose2 laser = f.base_pose * s.robot.laser_mount;
  int low = 0;
  for (std::size_t i = 0; i < f.scan.size(); ++i) {
    if (f.truth[i] == Truth::kNoReturn) continue;
    const Eigen::Vector2d p = beam_point(f, laser, i);
    if (std::abs(p.y()) < 2.94) {
      ++low;
      EXPECT_GT(f.scan.ranges_m[i], 2.0F) << "beam " << i;
      EXPECT_LE(f.scan.ranges_m[i], 3.0F + 0.05F) << "beam " << i;
    }
  }
  EXPECT_GT(low, 10);
  s.world.rough_walls->low_things_max_seen_within_m = 2.0;  // Within 2 m: the default.
  s.world.rough_walls->low_things_min_seen_within_m = 0.8;
  const SimulationOutput near_only = simulate(s, 4);
  const ScanFrame& g = near_only.scans[0];
  for (std::size_t i = 0; i < g.scan.size(); ++i) {
    if (g.truth[i] != Truth::kNoReturn) {
      EXPECT_GE(std::abs(beam_point(g, laser, i).y()), 2.94) << "beam " << i;
    }
  }
}

TEST(Simulator, ClutterStandsClearOfEveryPathAndFlickers) {
  Scenario s = room_with_walker();  // A still robot at the origin, a walker along x = 2.
  s.duration_s = 1.0;
  Clutter& c = s.world.clutter;
  c.count = 300;
  c.area_min = {-4.5, -4.5};
  c.area_max = {4.5, 4.5};
  c.min_radius_m = 0.02;
  c.max_radius_m = 0.1;
  c.return_share = 0.5;
  c.keep_clear_m = 1.0;
  const SimulationOutput out = simulate(s, 9);
  ASSERT_GE(out.scans.size(), 10U);
  std::vector<std::vector<char>> clutter_beams;
  int clutter_returns = 0;
  for (const ScanFrame& f : out.scans) {
    const Pose2 laser = f.base_pose * s.robot.laser_mount;
    std::vector<char>& beams = clutter_beams.emplace_back(f.scan.size(), 0);
    for (std::size_t i = 0; i < f.scan.size(); ++i) {
      if (f.truth[i] != Truth::kStatic) continue;
      const Eigen::Vector2d p = beam_point(f, laser, i);
      if (std::max(std::abs(p.x()), std::abs(p.y())) > 4.9) continue;  // A wall.
      if ((p - Eigen::Vector2d(-3.0, 3.0)).norm() < 0.35) continue;    // The pillar.
      beams[i] = 1;
      ++clutter_returns;
      EXPECT_GE(p.norm(), 1.0) << "clutter within keep_clear_m of where the robot stands";
      if (p.y() >= -3.0 && p.y() <= 1.0) {
        EXPECT_GE(std::abs(p.x() - 2.0), 1.0) << "clutter within keep_clear_m of the walker's path";
      }
    }
  }
  EXPECT_GT(clutter_returns, 500);
  // The robot stands still: which beams the clutter returns changes from scan to scan.
  int switched = 0;
  for (std::size_t i = 0; i < clutter_beams[0].size(); ++i) {
    switched += clutter_beams[0][i] != clutter_beams[1][i] ? 1 : 0;
  }
  EXPECT_GT(switched, clutter_returns / static_cast<int>(out.scans.size()) / 4);
}

// Range noise that grows with range, and mixed pixels at depth edges.
TEST(Simulator, NoiseGrowsWithRangeAndMixedPixelsFallBetweenSurfaces) {
  Scenario s = room_with_walker();
  s.actors.clear();
  s.duration_s = 5.0;
  s.world.circles = {{{2.0, 0.0}, 0.3}};  // A pillar 2 m ahead, the wall 5 m behind it.
  s.lidar.range_noise_m = 0.001;
  s.lidar.range_noise_per_m = 0.01;
  s.lidar.mixed_pixels = 1.0;
  const SimulationOutput out = simulate(s, 2);
  Scenario ideal = s;
  ideal.lidar.range_noise_m = 0.0;
  ideal.lidar.range_noise_per_m = 0.0;
  ideal.lidar.mixed_pixels = 0.0;
  const SimulationOutput truth = simulate(ideal, 2);
  double near_sum = 0.0, far_sum = 0.0;
  int near_n = 0, far_n = 0, between = 0;
  for (std::size_t k = 0; k < out.scans.size(); ++k) {
    const auto& r = out.scans[k].scan.ranges_m;
    const auto& t = truth.scans[k].scan.ranges_m;
    for (std::size_t i = 1; i + 1 < r.size(); ++i) {
      if (!std::isfinite(r[i]) || !std::isfinite(t[i])) continue;
      const bool edge = std::abs(t[i - 1] - t[i]) > 0.5F || std::abs(t[i + 1] - t[i]) > 0.5F;
      if (edge) {
        between += r[i] > std::min(t[i - 1], t[i + 1]) + 0.2F &&
                   r[i] < std::max(t[i - 1], t[i + 1]) - 0.2F;
        continue;
      }
      const double e = (r[i] - t[i]) * (r[i] - t[i]);
      if (t[i] < 2.0F) {
        near_sum += e;
        ++near_n;
      } else if (t[i] > 4.5F) {
        far_sum += e;
        ++far_n;
      }
    }
  }
  ASSERT_GT(near_n, 100);
  ASSERT_GT(far_n, 100);
  EXPECT_GT(std::sqrt(far_sum / far_n), 2.0 * std::sqrt(near_sum / near_n));
  EXPECT_GT(between, 20);
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
  const auto expect_named = [](const Scenario& bad, const std::string& field) {
    try {
      bad.validate();
      ADD_FAILURE() << field;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  s = Scenario{};
  s.world.clutter.count = 1000000;
  expect_named(s, "world.clutter.count");
  s.world.clutter.count = 10;
  expect_named(s, "world.clutter.area");  // No area given.
  s.world.clutter.area_max = {10.0, 10.0};
  EXPECT_NO_THROW(s.validate());
  s.world.clutter.return_share = 0.0;
  expect_named(s, "world.clutter.return_share");
  s.world.clutter.return_share = 0.5;
  s.world.clutter.max_radius_m = std::numeric_limits<double>::quiet_NaN();
  expect_named(s, "world.clutter.radius_m");
  // What cannot finish is refused before any work, naming the key and the limit: stamps past
  // 2^32 s, people ray-cast per beam; the held run also by its memory (the thesis's scanner at
  // 20 Hz: about 4 h in 4 GiB), the streamed one not.
  s = Scenario{};
  s.duration_s = 5e9;
  expect_named(s, "duration_s");
  s.duration_s = std::numeric_limits<double>::infinity();
  expect_named(s, "duration_s");
  s.duration_s = 1e9;  // Streamed, any duration whose stamps a bag holds.
  EXPECT_NO_THROW(s.validate());
  const auto expect_refused = [](const std::function<void()>& run, const std::string& field,
                                 const std::string& rule) {
    try {
      run();
      ADD_FAILURE() << field << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind(field + " must be ", 0), 0u) << e.what();
      EXPECT_NE(std::string(e.what()).find(rule), std::string::npos) << e.what();
    }
  };
  expect_refused([&] { simulate(s, 1); }, "duration_s", "held in memory, at most 4 GiB");
  s.duration_s = 60.0;
  expect_refused([&] { simulate(s, 1, 1e9); }, "--duration", "held in memory, at most 4 GiB");
  expect_refused([&] { simulate(s, 1, 5e9, SimulationSink{}); }, "--duration", "< 2^32 s");
  expect_refused([&] { simulate(s, 1, std::nan(""), SimulationSink{}); }, "--duration",
                 "finite and > 0");
  s = Scenario{};
  s.random_people.count = 1000000;
  s.random_people.area_max = {10.0, 10.0};
  expect_named(s, "random_people.count");
  s = Scenario{};
  s.robot.waypoints.assign(200000, Eigen::Vector2d::Zero());
  expect_named(s, "robot.waypoints");
  s = Scenario{};
  s.robot.lawnmower = Lawnmower{};
  s.robot.lawnmower->lanes = 2147483647;
  expect_named(s, "robot.lawnmower.lanes");
  // Rough walls: one bad value at a time, each named by its key.
  const std::tuple<double RoughWalls::*, double, const char*> rough_cases[] = {
      {&RoughWalls::piece_min_m, 0.0, "world.rough_walls.piece_min_m"},
      {&RoughWalls::glass_share, std::nan(""), "world.rough_walls.glass_share"},
      {&RoughWalls::glass_returns_within_deg, 90.0, "world.rough_walls.glass_returns_within_deg"},
      {&RoughWalls::glass_returns_within_deg, -1.0, "world.rough_walls.glass_returns_within_deg"},
      {&RoughWalls::low_things_per_10m, -1.0, "world.rough_walls.low_things_per_10m"},
      {&RoughWalls::low_things_min_radius_m, 0.0, "world.rough_walls.low_things_radius_m"},
      // Below the minimum, 0.075.
      {&RoughWalls::low_things_max_radius_m, 0.05, "world.rough_walls.low_things_radius_m"},
      {&RoughWalls::low_things_max_seen_within_m, std::nan(""),
       "world.rough_walls.low_things_seen_within_m"},
      {&RoughWalls::low_things_min_seen_within_m, -1.0,
       "world.rough_walls.low_things_seen_within_m"}};
  for (const auto& [field, value, key] : rough_cases) {
    s = Scenario{};
    s.world.rough_walls = RoughWalls{};
    (*s.world.rough_walls).*field = value;
    expect_named(s, key);
  }
  s = Scenario{};
  s.world.shelves = {ShelfRow{}};
  s.world.shelves[0].bay_m = 0.0;
  expect_named(s, "world.shelves[0].bay_m");
  s = Scenario{};
  s.lidar.mixed_pixels = 2.0;
  expect_named(s, "lidar.mixed_pixels");
  s = Scenario{};
  s.lidar.range_noise_per_m = -1.0;
  expect_named(s, "lidar.range_noise_per_m");
  s = Scenario{};
  s.lidar.speckle = 0.1;
  s.lidar.speckle_range_m = {4.0, 50.0};  // Beyond range_max_m.
  expect_named(s, "lidar.speckle_range_m[1]");
  s.lidar.speckle_range_m = {4.0, 5.0};
  s.lidar.speckle_beams_max = 0;
  expect_named(s, "lidar.speckle_beams_max");
  s = Scenario{};
  s.lidar.dark_share = 1.5;
  expect_named(s, "lidar.dark_share");
  s.lidar.dark_share = 0.5;  // And no reach.
  expect_named(s, "lidar.dark_reach_m");
  s.lidar.dark_reach_m = 50.0;  // Beyond range_max_m.
  expect_named(s, "lidar.dark_reach_m");
  s = Scenario{};
  s.lidar.bumps_per_min = 100.0;
  expect_named(s, "lidar.bumps_per_min");
  s.lidar.bumps_per_min = 4.0;  // And no height.
  expect_named(s, "lidar.height_m");
  s.lidar.height_m = 0.3;  // And no tilt.
  expect_named(s, "lidar.bump_tilt_deg");
  s.lidar.bump_tilt_deg = 8.0;
  s.lidar.bump_s = 16.0;  // Longer than a bump's slot of 15 s.
  expect_named(s, "lidar.bump_s");
  s = Scenario{};
  s.robot.stops = {{-1.0, 5.0}};
  expect_named(s, "robot.stops[0].at_s");
  s.robot.stops = {{1.0, 0.0}};
  expect_named(s, "robot.stops[0].for_s");
  s.robot.stops = {{1.0, 2.0}};
  s.actors = {Actor{}};
  s.actors[0].waypoints = {{1.0, 1.0}};
  s.actors[0].stops = {{1.0, 2.0}, {std::numeric_limits<double>::quiet_NaN(), 1.0}};
  expect_named(s, "actors[0].stops[1].at_s");
}

// Dark surfaces: a share of the static shapes returns only within dark_reach_m. Every beam that
// differs from the same run without them is a static return beyond the reach that now returns
// nothing; walkers, nearer returns and the bright shapes are as they were, draw for draw. The
// room's walls are cut in two, so that it has nine static shapes, some of them dark.
TEST(Simulator, DarkSurfacesReturnOnlyWithinTheirReachAndNothingElseChanges) {
  Scenario s = room_with_walker();
  s.world.walls = {{{-5, -5}, {0, -5}}, {{0, -5}, {5, -5}}, {{5, -5}, {5, 0}},
                   {{5, 0}, {5, 5}},    {{5, 5}, {0, 5}},   {{0, 5}, {-5, 5}},
                   {{-5, 5}, {-5, 0}},  {{-5, 0}, {-5, -5}}};
  s.lidar.range_max_m = 12.0;
  s.lidar.range_noise_m = 0.01;  // Noise and dropouts draw from the stream: it must stay in step.
  s.lidar.dropout = 0.01;
  const SimulationOutput plain = simulate(s, 3);
  s.lidar.dark_share = 0.5;
  s.lidar.dark_reach_m = 6.0;
  const SimulationOutput dark = simulate(s, 3);
  ASSERT_EQ(plain.scans.size(), dark.scans.size());
  std::int64_t silenced = 0, bright_beyond = 0;
  for (std::size_t k = 0; k < plain.scans.size(); ++k) {
    const ScanFrame& a = plain.scans[k];
    const ScanFrame& b = dark.scans[k];
    for (std::size_t i = 0; i < a.truth.size(); ++i) {
      const float r = a.scan.ranges_m[i];
      if (a.scan.ranges_m[i] == b.scan.ranges_m[i] && a.truth[i] == b.truth[i]) {
        bright_beyond += a.truth[i] == Truth::kStatic && r > 6.0F ? 1 : 0;
        continue;
      }
      ASSERT_EQ(a.truth[i], Truth::kStatic) << "scan " << k << " beam " << i;
      EXPECT_GT(r, 6.0F);
      EXPECT_TRUE(std::isinf(b.scan.ranges_m[i]));
      EXPECT_EQ(b.truth[i], Truth::kNoReturn);
      ++silenced;
    }
  }
  EXPECT_GT(silenced, 0);
  EXPECT_GT(bright_beyond, 0);  // Not every shape is dark.
}

// Bumps: the scan plane tilts and the beams meet the floor. Every beam that differs from the same
// run without bumps returns the floor, static, nearer than what it returned before (or where it
// returned nothing); the rest of the run is as it was, draw for draw. The floor is flat, so in
// each scan its points lie on one line in the laser frame (the scanner does not sweep here, so
// the tilt is one per scan); and it comes and goes: scans without it between the bumps. The room
// is opened (one wall), so that the floor is seen within range where nothing else is.
TEST(Simulator, BumpsShowTheFloorAsALineThatComesAndGoesAndNothingElseChanges) {
  Scenario s = room_with_walker();
  s.duration_s = 40.0;
  s.world.walls = {{{-5, -5}, {5, -5}}};
  s.lidar.range_max_m = 12.0;
  s.lidar.range_noise_m = 0.01;  // Noise and dropouts draw from the stream: it must stay in step.
  s.lidar.dropout = 0.01;
  const SimulationOutput plain = simulate(s, 3);
  s.lidar.height_m = 0.3;
  s.lidar.bumps_per_min = 6.0;
  s.lidar.bump_tilt_deg = 8.0;
  s.lidar.bump_s = 0.6;
  const SimulationOutput bumpy = simulate(s, 3);
  ASSERT_EQ(plain.scans.size(), bumpy.scans.size());
  std::int64_t floor_beams = 0, floor_scans = 0, runs = 0, longest = 0, run = 0;
  double worst_off_line = 0.0;
  for (std::size_t k = 0; k < plain.scans.size(); ++k) {
    const ScanFrame& a = plain.scans[k];
    const ScanFrame& b = bumpy.scans[k];
    std::vector<Eigen::Vector2d> points;
    for (std::size_t i = 0; i < a.truth.size(); ++i) {
      if (a.scan.ranges_m[i] == b.scan.ranges_m[i] && a.truth[i] == b.truth[i]) continue;
      ASSERT_EQ(b.truth[i], Truth::kStatic) << "scan " << k << " beam " << i;
      EXPECT_EQ(b.actor[i], 0);
      if (a.truth[i] != Truth::kNoReturn) {
        EXPECT_LT(b.scan.ranges_m[i], a.scan.ranges_m[i] + 0.05F);
      }
      // At most 8 degrees down and as much to the side: nowhere nearer than 0.3 m / tan(8 deg)
      // / sqrt(2), 1.5 m.
      EXPECT_GT(b.scan.ranges_m[i], 1.45F);
      const double bearing = b.scan.bearing_rad(i);
      const double r = b.scan.ranges_m[i];
      points.emplace_back(r * std::cos(bearing), r * std::sin(bearing));
    }
    floor_beams += static_cast<std::int64_t>(points.size());
    if (points.size() >= 20) {
      // The line through the points, from their covariance: the largest distance from it.
      Eigen::Vector2d mean = Eigen::Vector2d::Zero();
      for (const Eigen::Vector2d& p : points) mean += p;
      mean /= static_cast<double>(points.size());
      Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
      for (const Eigen::Vector2d& p : points) cov += (p - mean) * (p - mean).transpose();
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
      const Eigen::Vector2d normal = eig.eigenvectors().col(0);
      for (const Eigen::Vector2d& p : points) {
        worst_off_line = std::max(worst_off_line, std::abs((p - mean).dot(normal)));
      }
    }
    if (!points.empty()) {
      ++floor_scans;
      runs += run == 0 ? 1 : 0;
      longest = std::max(longest, ++run);
    } else {
      run = 0;
    }
  }
  EXPECT_GT(floor_beams, 1000);
  // Six bumps a minute for 40 s: a bump in each of the 4 slots, some too small to reach the floor
  // within range; each seen in at most 0.6 s at 20 Hz, 13 scans.
  EXPECT_GE(runs, 2);
  EXPECT_LE(runs, 4);
  EXPECT_LE(longest, 13);
  EXPECT_LT(floor_scans, static_cast<std::int64_t>(plain.scans.size()) / 5);
  EXPECT_LT(worst_off_line, 0.1);  // Range noise 0.01 m plus 0.0 m per m.
}

// Speckle: sporadic returns in the band, in runs of at most speckle_beams_max beams, only where
// nothing was in range (never on a beam a wall or a walker blocks nearer), labelled static. The
// walls of a 10 m room are within range of every beam, so the room is opened: one wall only.
TEST(Simulator, SpeckleReturnsOnlyWhereNothingIsInRangeAndIsBackground) {
  Scenario s = room_with_walker();
  s.world.walls = {{{-5, -5}, {5, -5}}};
  s.lidar.range_max_m = 12.0;
  const SimulationOutput plain = simulate(s, 3);
  s.lidar.speckle = 0.05;
  s.lidar.speckle_range_m = {6.0, 8.0};
  s.lidar.speckle_beams_max = 3;
  const SimulationOutput speckled = simulate(s, 3);
  ASSERT_EQ(plain.scans.size(), speckled.scans.size());
  std::int64_t speckle = 0, runs = 0, open_beams = 0;
  for (std::size_t k = 0; k < plain.scans.size(); ++k) {
    const ScanFrame& a = plain.scans[k];
    const ScanFrame& b = speckled.scans[k];
    std::size_t run = 0;
    for (std::size_t i = 0; i < a.truth.size(); ++i) {
      const bool open = a.truth[i] == Truth::kNoReturn;
      open_beams += open ? 1 : 0;
      if (a.scan.ranges_m[i] == b.scan.ranges_m[i] && a.truth[i] == b.truth[i]) {
        run = 0;
        continue;
      }
      ASSERT_TRUE(open) << "scan " << k << " beam " << i;  // Only where nothing was in range.
      EXPECT_EQ(b.truth[i], Truth::kStatic);
      EXPECT_EQ(b.actor[i], 0);
      EXPECT_GE(b.scan.ranges_m[i], 5.9F);
      EXPECT_LE(b.scan.ranges_m[i], 8.1F);
      ++speckle;
      runs += run == 0 ? 1 : 0;
      EXPECT_LT(++run, 4U) << "scan " << k << " beam " << i;
    }
  }
  // About 5 % of the open beams start a run of 2 beams on average.
  EXPECT_GT(runs, open_beams / 40);
  EXPECT_LT(runs, open_beams / 10);
  EXPECT_GT(speckle, runs);
}

}  // namespace
}  // namespace dispel::sim
