#pragma once
/// @file
/// Reader for CARMEN logs (.log, .clf), the classic 2D SLAM datasets.
///
/// Lines used (the others, and comments '#', are ignored and counted):
///   FLASER n r1..rn x y theta odom_x odom_y odom_theta ipc_timestamp ipc_hostname logger_timestamp
///   RLASER (same; the rear laser, looking backwards)
///   ROBOTLASER1 laser_type start_angle field_of_view angular_resolution maximum_range accuracy
///       remission_mode n r1..rn m v1..vm laser_x laser_y laser_theta robot_x robot_y
///       robot_theta tv rv forward_safety side_safety turn_axis ipc_timestamp host logger_timestamp
///   ODOM x y theta tv rv accel ipc_timestamp ipc_hostname logger_timestamp
/// FLASER and RLASER carry no field of view or range limit: they are read as a 180 degree scan
/// from -90 degrees (the SICK LMS of those datasets) with readings at or beyond `old_max_range_m`
/// as no return. Their x y theta is the laser's pose in the odometry frame.

#include <cstdint>
#include <string>
#include <vector>

#include "dispel/core/laser_scan.hpp"
#include "dispel/core/pose_buffer.hpp"

namespace dispel::io {

/// One laser line with the laser's pose in the odometry frame at that time.
struct CarmenScan {
  LaserScan scan;
  Pose2 laser_pose;
  std::string kind;  ///< "FLASER", "RLASER" or "ROBOTLASER1".
};

struct CarmenLog {
  std::vector<CarmenScan> scans;     ///< In file order.
  std::vector<TimedPose> odometry;   ///< ODOM lines, in file order.
  std::int64_t lines = 0;            ///< Lines read.
  std::int64_t ignored_lines = 0;    ///< Other message types and comments.
  std::int64_t malformed_lines = 0;  ///< Laser or ODOM lines that could not be parsed.
  std::string first_malformed;       ///< "line N: what", for the message.
};

/// Reads a CARMEN log. Malformed laser and odometry lines are skipped and counted.
/// @throws InputError (errors.hpp) if the file cannot be read, holds no laser line at all, or
/// has a stamp (ipc_timestamp) that is not finite, negative, or not below 2^32 - 1 s:
/// "<path>: line N (FLASER): ipc_timestamp '5e9' is not a time a recording can hold (...)".
CarmenLog read_carmen_log(const std::string& path, float old_max_range_m = 80.0F);

/// Parses the text of a log (for tests); @p origin names it in errors.
CarmenLog parse_carmen_log(std::istream& in, const std::string& origin,
                           float old_max_range_m = 80.0F);

}  // namespace dispel::io
