#pragma once
/// @file
/// Conversions between ROS 1 messages and dispel's core types: free functions, nothing else.

#include <geometry_msgs/Transform.h>
#include <nav_msgs/Odometry.h>
#include <ros/time.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/JointState.h>
#include <sensor_msgs/LaserScan.h>

#include <optional>
#include <string>

#include "dispel/core/dynamic_filter.hpp"
#include "dispel/core/laser_scan.hpp"
#include "dispel/core/pose2.hpp"
#include "dispel/io/config_yaml.hpp"

namespace dispel::io {

/// Seconds since the epoch of a ROS time.
double to_seconds(const ros::Time& t);
/// A ROS time from seconds (rounded to the nanosecond).
ros::Time to_ros_time(double seconds);
/// A message's stamp in seconds: its header's, or @p received when the header's is zero.
double stamp_or(const ros::Time& header, const ros::Time& received);

/// The scan's stamp, angles, limits, ranges and intensities.
LaserScan from_ros(const sensor_msgs::LaserScan& msg);

/// A LaserScan message with the core scan's values and the given frame.
sensor_msgs::LaserScan to_ros(const LaserScan& scan, const std::string& frame_id);

/// Yaw (rotation about z) of a quaternion; the planar part of a 3D rotation.
double yaw_of(const geometry_msgs::Quaternion& q);
/// A quaternion for a rotation of @p yaw_rad about z.
geometry_msgs::Quaternion quaternion_from_yaw(double yaw_rad);

/// An Odometry message for a planar pose and velocity (forward v, yaw rate w).
nav_msgs::Odometry to_ros_odometry(double stamp_s, const std::string& frame_id,
                                   const std::string& child_frame_id, const Pose2& pose,
                                   double v_mps = 0.0, double w_radps = 0.0);

/// The planar part of a transform (x, y, yaw).
Pose2 from_ros(const geometry_msgs::Transform& t);
/// The planar part of a pose (x, y, yaw).
Pose2 from_ros(const geometry_msgs::Pose& p);

/// The message published on <scan topic>_filtered: @p original with the filtered ranges.
sensor_msgs::LaserScan filtered_message(const sensor_msgs::LaserScan& original,
                                        const FilterResult& result);
/// The message published on <scan topic>_labels: @p original whose intensities are the labels.
sensor_msgs::LaserScan labels_message(const sensor_msgs::LaserScan& original,
                                      const FilterResult& result);

/// Left and right wheel speeds (m/s, forward positive) measured at t_s.
struct WheelSpeeds {
  double t_s = 0.0;
  double left_mps = 0.0;
  double right_mps = 0.0;
};

/// The wheel speeds in a JointState, as @p settings say: the joints named left_wheel_joint and
/// right_wheel_joint (when empty, the first whose names contain "left" and "right", else the
/// first two velocities), multiplied by wheel_radius_m when it is > 0. nullopt when the message
/// does not hold both. @p received is used when the header's stamp is zero.
std::optional<WheelSpeeds> wheel_speeds_from_ros(const sensor_msgs::JointState& msg,
                                                 const OdometrySettings& settings,
                                                 const ros::Time& received);
/// The wheel speeds that an Odometry message's forward speed and yaw rate stand for, on a
/// differential drive of @p track_width_m: v -+ w b / 2.
WheelSpeeds wheel_speeds_from_ros(const nav_msgs::Odometry& msg, double track_width_m,
                                  const ros::Time& received);
/// The robot's yaw rate (rad/s) in an Imu message: the axis imu_yaw_axis of @p settings, signed.
double yaw_rate_from_ros(const sensor_msgs::Imu& msg, const OdometrySettings& settings);

}  // namespace dispel::io
