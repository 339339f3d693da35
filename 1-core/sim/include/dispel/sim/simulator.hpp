#pragma once
/// @file
/// The scenario simulator: a differential-drive robot with a 2D LiDAR, wheel encoders and an IMU
/// among walls and moving people and carts, with exact ground truth per beam.

#include <cstdint>
#include <vector>

#include "dispel/core/laser_scan.hpp"
#include "dispel/core/pose2.hpp"
#include "dispel/sim/scenario.hpp"

namespace dispel::sim {

/// Ground-truth code of a beam, written in the intensities of /scan_truth (docs/simulator.md).
enum class Truth : std::uint8_t {
  kStatic = 0,    ///< Static structure.
  kMoving = 1,    ///< A moving actor.
  kStill = 2,     ///< An actor standing still at that moment.
  kNoReturn = 3,  ///< Nothing within range, a dropout, or a masked sector.
};

/// One scan with its ground truth.
struct ScanFrame {
  LaserScan scan;                   ///< In the laser frame, stamped.
  std::vector<Truth> truth;         ///< Per beam.
  std::vector<std::int32_t> actor;  ///< Per beam: index of the actor hit + 1, or 0.
  Pose2 base_pose;                  ///< True pose of base_link in the world.
};

/// One sample of the odometry sensors.
struct SensorSample {
  double stamp_s = 0.0;
  double wheel_left_mps = 0.0;  ///< Measured (noise, scale error, slips).
  double wheel_right_mps = 0.0;
  double imu_yaw_rate_radps = 0.0;  ///< Measured (noise, bias, vibration).
  Pose2 odom_pose;                  ///< Integrated from the measured wheels, from the start pose.
  double odom_v_mps = 0.0;
  double odom_w_radps = 0.0;
  Pose2 true_pose;  ///< Ground truth.
  double true_v_mps = 0.0;
  double true_w_radps = 0.0;
};

struct SimulationOutput {
  std::vector<ScanFrame> scans;
  std::vector<SensorSample> sensors;
  std::int32_t actor_count = 0;  ///< Scripted and generated actors.
};

/// Runs @p scenario for @p duration_s (the scenario's own duration if <= 0) with noise drawn from
/// @p seed. The same scenario and seed give the same output. @throws std::invalid_argument if
/// scenario.validate() does.
SimulationOutput simulate(const Scenario& scenario, std::uint64_t seed, double duration_s = 0.0);

/// The laser's beams for @p lidar (angle_min, increment, count, limits).
ScanGeometry lidar_geometry(const LidarConfig& lidar);

/// The four edges of a rectangle.
std::vector<Segment> rectangle_edges(const Rectangle& r);

}  // namespace dispel::sim
