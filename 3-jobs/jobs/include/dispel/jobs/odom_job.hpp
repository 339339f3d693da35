#pragma once
/// @file
/// `dispel odom`: odometry fusion over a recording (a ROS 1 bag, or CSV files of wheel speeds and
/// yaw rates) written as a trajectory CSV. The measurements go through pipeline::OdometryRunner,
/// as in the odometry node.

#include <cstdint>
#include <optional>
#include <string>

#include "dispel/core/odometry_fusion.hpp"
#include "dispel/jobs/job.hpp"

namespace dispel::jobs {

struct OdomJobOptions {
  std::string input;                       ///< A ROS 1 bag; empty when wheels_csv is given.
  std::string wheels_csv;                  ///< CSV with the header t,v_left,v_right (s, m/s, m/s).
  std::string imu_csv;                     ///< CSV with the header t,yaw_rate (s, rad/s); optional.
  std::string output;                      ///< The trajectory CSV to write.
  std::optional<std::string> config_path;  ///< YAML with an `odometry:` section.
  /// ct, ct_euler, omni or dead_reckoning (wheels alone); overrides the configuration's model.
  std::optional<std::string> model;
  std::string wheel_topic;  ///< Empty: /wheels, or the only JointState or Odometry topic.
  std::string imu_topic;    ///< Empty: the only sensor_msgs/Imu topic, if any; "none": no IMU.
  /// nav_msgs/Odometry, or sensor_msgs/NavSatFix (east and north in metres from the first fix,
  /// yaw NaN), written to truth_csv.
  std::string truth_topic = "/ground_truth";
  std::string truth_csv;  ///< Non-empty: also write the truth as t,x,y,yaw.
};

struct OdomJobStats {
  std::string model;         ///< The model used ("dead_reckoning" for the wheels alone).
  std::string wheel_source;  ///< Topic or file the wheel speeds came from.
  std::string imu_source;    ///< Topic or file of the yaw rates; empty when none.
  std::int64_t wheel_messages = 0;
  std::int64_t imu_messages = 0;
  /// Messages whose stamp is earlier than the previous one of the same source: processed in time
  /// order with the rest.
  std::int64_t stamps_out_of_order = 0;
  /// Messages that carry no usable measurement (a JointState without both wheels, say): skipped.
  std::int64_t malformed = 0;
  OdometryCounters counters;  ///< The filter's; for dead reckoning only `wheels` is filled.
  std::int64_t rows = 0;      ///< Trajectory rows written.
  std::int64_t truth_rows = 0;
  double track_width_m = 0.0;
  OdometryEstimate final_estimate;
};

/// Runs the job; the CSV appears only when complete. @throws JobError (a missing or unreadable
/// input, no wheel topic, a malformed CSV line, named with its file and line; a bad
/// configuration)
OdomJobStats run_odom_job(const OdomJobOptions& options);

}  // namespace dispel::jobs
