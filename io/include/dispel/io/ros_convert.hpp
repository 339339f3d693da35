#pragma once
/// @file
/// Conversions between ROS 1 messages and dispel's core types: free functions, nothing else.

#include <geometry_msgs/Transform.h>
#include <nav_msgs/Odometry.h>
#include <ros/time.h>
#include <sensor_msgs/LaserScan.h>

#include "dispel/core/dynamic_filter.hpp"
#include "dispel/core/laser_scan.hpp"
#include "dispel/core/pose2.hpp"

namespace dispel::io {

/// Seconds since the epoch of a ROS time.
double to_seconds(const ros::Time& t);
/// A ROS time from seconds (rounded to the nanosecond).
ros::Time to_ros_time(double seconds);

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

}  // namespace dispel::io
