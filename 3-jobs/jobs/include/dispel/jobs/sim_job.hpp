#pragma once
/// @file
/// `dispel sim`: a simulation written as a recording (the topics are in docs/simulator.md).

#include <string>

#include "dispel/jobs/job.hpp"
#include "dispel/sim/simulator.hpp"

namespace dispel::jobs {

/// Writes /scan, /scan_truth (intensities = ground-truth codes), /scan_truth_actor (intensities =
/// index of the actor hit + 1, 0 for none), /odom (wheel odometry), /wheels (JointState velocity
/// = [left, right] m/s), /imu (angular_velocity.z; orientation unknown, covariance[0] = -1),
/// /ground_truth (Odometry) and /tf_static (base_link -> laser), LZ4-compressed. Written to
/// "<path>.partial" and renamed when complete; when @p cancel becomes true, or on an error, the
/// partial file is removed. @throws JobError, JobCancelled
void write_simulation(const sim::SimulationOutput& run, const sim::Scenario& scenario,
                      const std::string& path, const std::atomic<bool>* cancel = nullptr);

}  // namespace dispel::jobs
