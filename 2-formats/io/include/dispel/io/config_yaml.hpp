#pragma once
/// @file
/// The filter's configuration from YAML. Keys mirror the configuration structs (config/default.yaml
/// lists every one with its default):
///   preset: default | thesis   the starting point: DynamicFilterConfig{} (when absent) or
///                              thesis_config(); every other key changes it
///   segmentation: {...}, tracking: {...}, velocity: {...}, classification: {...},
///   free_space: {...}, max_time_gap_s, max_pose_jump_m, max_pose_jump_rad,
///   max_speed_mps, max_turn_rate_radps
///   odometry: {...}            read by `dispel odom` (parse_odometry_settings), skipped here
/// Missing keys keep the preset's value. Unknown keys, wrong types and invalid values are errors.

#include <set>
#include <string>

#include "dispel/core/dynamic_filter_config.hpp"
#include "dispel/core/odometry_fusion.hpp"
#include "dispel/io/errors.hpp"

namespace dispel::io {

/// Reads and validates a configuration file. @throws ConfigError
DynamicFilterConfig load_filter_config(const std::string& path);

/// Parses and validates YAML text; @p origin names it in errors. @throws ConfigError
DynamicFilterConfig parse_filter_config(const std::string& yaml_text, const std::string& origin);

/// The keys parse_filter_config() accepts at the top level of a file ("preset", "segmentation",
/// ..., "max_time_gap_s", and "odometry", which it skips): for a reader of the `odometry:` section
/// that must tell the filter's keys from unknown ones in a shared file.
std::set<std::string> filter_config_top_level_keys();

/// What `dispel odom` reads from the `odometry:` section of a YAML file (other keys are the
/// filter's and are not looked at): OdometryConfig's fields under their own names, plus how wheel
/// speeds are read from sensor_msgs/JointState.
struct OdometrySettings {
  OdometryConfig filter;
  /// > 0: JointState velocities are wheel rates (rad/s) and are multiplied by this radius; 0: they
  /// are already wheel speeds (m/s), as in the simulator's bags.
  double wheel_radius_m = 0.0;
  /// Joint names of the wheels; empty: the joints whose names contain "left" and "right", or else
  /// the first two velocities as [left, right].
  std::string left_wheel_joint;
  std::string right_wheel_joint;
  /// Which axis of the IMU's angular velocity is the robot's yaw rate: 0 = x, 1 = y, 2 = z, with
  /// the sign (YAML: z, -z, y, -y, x or -x; default z). For an IMU mounted on its side when the
  /// recording has no transform to tell (robot_localization's test1.bag: y).
  int imu_yaw_axis = 2;
  double imu_yaw_sign = 1.0;
};

/// Parses the `odometry:` section of YAML text (missing: all defaults). Unknown keys, wrong types
/// and invalid values are errors naming the key. @throws ConfigError
OdometrySettings parse_odometry_settings(const std::string& yaml_text, const std::string& origin);

/// Reads a file and parses its `odometry:` section. @throws ConfigError
OdometrySettings load_odometry_settings(const std::string& path);

}  // namespace dispel::io
