#pragma once
/// @file
/// Writing a simulation as a ROS 1 bag (topics in DESIGN.md, "Command line").

#include <string>

#include "dispel/sim/simulator.hpp"

namespace dispel::io {

/// Writes /scan, /scan_truth (intensities = ground-truth codes), /scan_truth_actor (intensities =
/// index of the actor hit + 1, 0 for none), /odom (wheel odometry), /wheels (JointState velocity
/// = [left, right] m/s), /imu (angular_velocity.z; orientation unknown, covariance[0] = -1),
/// /ground_truth (Odometry) and /tf_static (base_link -> laser). Written to "<path>.partial" and
/// renamed when complete. @throws std::runtime_error
void write_simulation_bag(const sim::SimulationOutput& run, const sim::Scenario& scenario,
                          const std::string& path);

}  // namespace dispel::io
