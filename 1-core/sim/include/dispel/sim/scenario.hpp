#pragma once
/// @file
/// A scenario: the world, the robot and its path, the LiDAR, the odometry sensors and the moving
/// actors. Plain data with defaults; loading from YAML lives in dispel::io.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "dispel/core/pose2.hpp"
#include "dispel/sim/raycast.hpp"

namespace dispel::sim {

/// A rectangle (shelf, machine, cart body): centre, length along its yaw, width across.
struct Rectangle {
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  double length_m = 1.0;
  double width_m = 1.0;
  double yaw_rad = 0.0;
};

/// Static structure.
struct StaticWorld {
  std::vector<Segment> walls;  ///< Walls and polyline pieces.
  std::vector<Rectangle> rectangles;
  std::vector<Circle> circles;
};

/// The thesis's lawnmower pattern: straight lanes along x joined by half-circle U-turns.
struct Lawnmower {
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  ///< Start of the first lane.
  double lane_length_m = 10.0;
  double lane_spacing_m = 2.0;  ///< Lanes advance along +y.
  int lanes = 4;
};

struct RobotConfig {
  Pose2 start;
  double speed_mps = 0.067;                ///< The thesis's robot.
  std::vector<Eigen::Vector2d> waypoints;  ///< Used when no lawnmower is given.
  bool loop = true;                        ///< Start over at the end of the path.
  std::optional<Lawnmower> lawnmower;
  double wheel_base_m = 0.5;
  Pose2 laser_mount{0.2, 0.0, 0.0};  ///< Laser in base_link.
};

struct LidarConfig {
  double range_max_m = 40.0;
  double fov_deg = 275.0;
  double resolution_deg = 0.17;
  double rate_hz = 20.0;
  /// Returns beyond this are dropped (the thesis cut the range to 5.5 m to emulate a
  /// feature-sparse hall); 0 keeps the full range.
  double range_limit_m = 0.0;
  /// Sectors [begin_deg, end_deg] in the laser frame that return nothing (the thesis's mirrors).
  std::vector<std::pair<double, double>> masked_sectors_deg;
  double range_noise_m = 0.01;  ///< Gaussian, standard deviation.
  double dropout = 0.002;       ///< Probability that a beam returns nothing.
};

struct SensorConfig {
  double rate_hz = 50.0;                  ///< Wheels, IMU and odometry.
  double wheel_noise_mps = 0.003;         ///< Gaussian on each wheel speed.
  double wheel_scale_error = 0.01;        ///< Both wheels read this much more (a worn tyre).
  double wheel_difference_error = 0.001;  ///< Right reads this much more, left less: heading drift.
  double slips_per_minute = 0.5;          ///< Events where one wheel reads 30% fast for 0.5 s.
  double imu_noise_radps = 0.003;         ///< Gaussian on the yaw rate.
  double imu_bias_walk_radps = 0.0002;    ///< Random walk of the bias per sqrt(second).
  double imu_vibration_radps = 0.005;     ///< 15 Hz vibration amplitude at 1 m/s.
};

enum class ActorKind { kPerson, kCart };

/// Someone or something that moves: along waypoints at a speed, pausing at each waypoint, or
/// standing still the whole run (no waypoints after the start).
struct Actor {
  ActorKind kind = ActorKind::kPerson;
  std::vector<Eigen::Vector2d> waypoints;  ///< The first is the start.
  double speed_mps = 1.0;
  double pause_s = 0.0;  ///< Standing time at each waypoint.
  bool loop = true;      ///< Walk the waypoints again from the start.
  double start_delay_s = 0.0;
  double length_m = 1.2;  ///< Carts: footprint.
  double width_m = 0.8;
};

/// People generated from the seed: each walks between random points of the area.
struct RandomPeople {
  int count = 0;
  Eigen::Vector2d area_min = Eigen::Vector2d::Zero();
  Eigen::Vector2d area_max = Eigen::Vector2d::Zero();
  double min_speed_mps = 0.5;
  double max_speed_mps = 1.5;
  double max_pause_s = 3.0;
  int waypoints = 6;
};

struct Scenario {
  std::string name = "scenario";
  double duration_s = 60.0;
  /// Stamp of the first message (ROS bags cannot hold time 0).
  double start_time_s = 100.0;
  StaticWorld world;
  RobotConfig robot;
  LidarConfig lidar;
  SensorConfig sensors;
  std::vector<Actor> actors;
  RandomPeople random_people;

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

}  // namespace dispel::sim
