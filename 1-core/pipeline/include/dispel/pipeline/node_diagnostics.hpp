#pragma once
/// @file
/// What dispel's nodes say on /diagnostics, whichever ROS they run on: one status per node and
/// period, composed here from the shared runners' counts so that the ROS 1 and ROS 2 nodes say
/// the same things under the same keys (each converts it to diagnostic_msgs/DiagnosticStatus).

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "dispel/pipeline/odometry_runner.hpp"
#include "dispel/pipeline/scan_filter_runner.hpp"

namespace dispel::pipeline {

/// diagnostic_msgs/DiagnosticStatus.
struct DiagnosticStatus {
  /// diagnostic_msgs/DiagnosticStatus's levels.
  enum class Level : std::uint8_t { kOk = 0, kWarn = 1, kError = 2, kStale = 3 };
  Level level = Level::kOk;
  std::string name;
  std::string message;
  std::string hardware_id;
  std::vector<std::pair<std::string, std::string>> values;
};

/// What the filter node counts around the runner, since it started.
struct FilterNodeTallies {
  std::int64_t without_pose = 0;            ///< Scans whose sensor pose was not found.
  std::int64_t without_pose_in_period = 0;  ///< The same since the last status: WARN when > 0.
  std::int64_t dropped = 0;                 ///< Scans dropped for want of a pose.
};

/// The filter node's status "<node_name>: dynamic filter" for the period since the last one:
/// takes the runner's processing times (ScanFilterRunner::take_times).
DiagnosticStatus filter_node_status(const std::string& node_name, ScanFilterRunner& runner,
                                    const FilterNodeTallies& tallies);

/// What the odometry node counts around the runner, since it started.
struct OdometryNodeTallies {
  std::int64_t published = 0;      ///< Estimates published.
  std::int64_t malformed = 0;      ///< Wheel messages without both wheels.
  bool refused_in_period = false;  ///< Measurements refused since the last status: WARN.
};

/// Measurements the odometry engine refused: not finite, out of order, a numerical failure.
std::int64_t odometry_refused(const OdometryRunner& runner);

/// The odometry node's status "<node_name>: odometry fusion"; @p model names the motion model
/// (odometry_model_name).
DiagnosticStatus odometry_node_status(const std::string& node_name, const std::string& model,
                                      const OdometryRunner& runner,
                                      const OdometryNodeTallies& tallies);

}  // namespace dispel::pipeline
