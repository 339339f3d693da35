#pragma once
/// @file
/// The first pass over a recording, written once for every command that puts scans in a fixed
/// frame (`dispel filter`, `render`, `slam`, `experiment`): the robot's poses from an odometry (or
/// ground-truth) topic, the laser's mount from /tf_static and /tf by one set of rules, a look at
/// the scanner (its frame, its period by the filter's rule), and the checks with their one-line
/// errors. Format-free: it reads through RecordingReader.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "dispel/core/laser_scan.hpp"
#include "dispel/core/pose2.hpp"
#include "dispel/core/pose_buffer.hpp"
#include "dispel/io/recording.hpp"

namespace dispel::io {

/// What to read.
struct MotionQuery {
  /// The LaserScan topic; empty: `dispel filter`'s output (<scan>_filtered of /scan) when the
  /// recording has it, else /scan.
  std::string scan_topic = "/scan";
  /// The nav_msgs/Odometry topic with the robot's pose (odometry, or the simulator's ground
  /// truth); std::nullopt: the sensor does not move (identity pose, no mount needed).
  std::optional<std::string> pose_topic = std::string("/odom");
  /// No poses: the scans alone (the filter registers them). The pose topic and mount are not read.
  bool laser_only = false;
  /// Laser-only, instead of an error, when the recording has no nav_msgs/Odometry topic at all.
  bool laser_only_without_odometry = false;
  /// The fixed frame when the pose topic's messages name none.
  std::string default_fixed_frame = "odom";
  /// How far before the first or after the last pose a scan's pose may be taken from it, and
  /// the largest gap between two poses that is interpolated across.
  double pose_tolerance_s = 0.05;
  double pose_max_gap_s = 0.5;
  /// Appended to the errors for a missing scan topic, pose topic and mount, e.g. "; choose one
  /// with --odom-topic, or use --static-sensor for a sensor that does not move".
  std::string missing_scan_hint;
  std::string missing_pose_hint;
  std::string missing_mount_hint;
};

/// What the first pass learns.
struct RecordingMotion {
  std::string scan_topic;
  std::int64_t scans = 0;   ///< Messages on scan_topic.
  LaserScan first_scan;     ///< Decoded from the first message on scan_topic.
  std::string laser_frame;  ///< Its frame, without a leading '/'.
  /// The scanner's period by the filter's rule (pipeline::ScanPeriod over the first scans), if
  /// the scans tell it.
  std::optional<double> scan_period_s;
  bool static_sensor = false;
  /// No poses (MotionQuery::laser_only, or no odometry topic): sensor_pose() is always unset.
  bool laser_only = false;
  std::string fixed_frame;         ///< The frame of the poses ("odom", or the topic's).
  std::string base_frame;          ///< The robot's frame (the pose topic's child frame).
  PoseBuffer base_poses;           ///< The robot in the fixed frame; empty for a static sensor.
  std::int64_t poses_refused = 0;  ///< Pose messages out of order or not finite.
  Pose2 mount;                     ///< The laser in the robot's frame.

  /// The laser's pose in the fixed frame at @p stamp_s: the identity for a static sensor, else
  /// the robot's interpolated pose times the mount; std::nullopt with the reason in @p why when
  /// there is none (before the first pose, after the last, in a gap).
  std::optional<Pose2> sensor_pose(double stamp_s, PoseLookup* why = nullptr) const;
};

/// Reads @p reader once: the scan topic's first scan and period, the poses and the mount.
/// Transforms count as the mount only when neither end is the fixed frame, "odom" or "map" (the
/// robot's motion is not a mount); the latest value of each one counts, whenever it came. The
/// mount is looked up from the pose topic's child frame (base_link when it names none) to the
/// scan's frame. @throws InputError naming the recording: no such scan topic (listing the
/// LaserScan topics), no scans, no such pose topic (listing the Odometry topics), no usable pose,
/// no mount. @p poll is called before each message (it may throw, e.g. to cancel: that goes through
/// unchanged).
RecordingMotion read_motion(RecordingReader& reader, const MotionQuery& query,
                            const std::function<void()>& poll = {});

}  // namespace dispel::io
