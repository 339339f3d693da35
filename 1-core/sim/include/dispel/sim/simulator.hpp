#pragma once
/// @file
/// The scenario simulator: a differential-drive robot with a 2D LiDAR, wheel encoders and an IMU
/// among walls and moving people and carts, with exact ground truth per beam.

#include <cstdint>
#include <functional>
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

/// Where a streamed run goes: each scan and each sensor sample as it is made, in time order (at
/// the same instant the scan first, then the sensor sample). Either may be empty (not wanted);
/// either may throw to stop the run (the exception comes out of simulate()).
struct SimulationSink {
  std::function<void(ScanFrame&&)> scan;
  std::function<void(const SensorSample&)> sensor;
};

/// Runs @p scenario for @p duration_s (the scenario's own duration if <= 0) with noise drawn from
/// @p seed, handing every scan and sensor sample to @p sink as it is made: nothing of the run is
/// held, so any duration whose stamps a bag can hold runs in the same memory. The same scenario
/// and seed give the same stream. Returns the number of actors (scripted and generated).
/// @throws std::invalid_argument if scenario.validate() does, naming a scripted actor whose path
/// goes through a wall, rectangle or circle (a person reaches 0.16 m either side of its path, a
/// vehicle half its width, and half its length beyond each waypoint), or naming "--duration" for a
/// @p duration_s that is not finite or whose stamps reach 2^32 s.
std::int32_t simulate(const Scenario& scenario, std::uint64_t seed, double duration_s,
                      const SimulationSink& sink);

/// The same run held in memory: the stream above collected (the same scans and samples). A run
/// that would hold more than 4 GiB is refused before any work, naming duration_s (or
/// "--duration") and the longest duration that fits. @throws std::invalid_argument
SimulationOutput simulate(const Scenario& scenario, std::uint64_t seed, double duration_s = 0.0);

/// How long a run of @p duration_s lasts (the scenario's own duration if <= 0), checked as
/// simulate() checks it before any work. @throws std::invalid_argument as the streamed simulate()
double run_duration(const Scenario& scenario, double duration_s);

/// The laser's beams for @p lidar (angle_min, increment, count, limits).
ScanGeometry lidar_geometry(const LidarConfig& lidar);

/// The four edges of a rectangle.
std::vector<Segment> rectangle_edges(const Rectangle& r);

}  // namespace dispel::sim
