#pragma once
/// @file
/// Conversions between ROS 1 messages and dispel's types (the core's, and the recording model's
/// of recording.hpp): free functions, nothing else. Needs the ROS 1 message headers and rostime,
/// not the bag library, so that a live node can use them.

#include <geometry_msgs/Transform.h>
#include <nav_msgs/Odometry.h>
#include <ros/time.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/JointState.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/NavSatFix.h>
#include <tf2_msgs/TFMessage.h>

#include <optional>
#include <string>

#include "dispel/core/dynamic_filter.hpp"
#include "dispel/core/laser_scan.hpp"
#include "dispel/core/pose2.hpp"
#include "dispel/io/odometry_inputs.hpp"
#include "dispel/io/recording.hpp"

namespace dispel::io {

/// Seconds since the epoch of a ROS time.
double to_seconds(const ros::Time& t);
/// A ROS time from seconds (rounded to the nanosecond).
ros::Time to_ros_time(double seconds);
/// Exact conversions of stamps. A stamp outside ROS 1's range (negative, or 2^32 s and more) is
/// clamped to it.
Stamp to_stamp(const ros::Time& t);
ros::Time to_ros_time(const Stamp& s);

/// Yaw (rotation about z) of a quaternion; the planar part of a 3D rotation.
double yaw_of(const geometry_msgs::Quaternion& q);
/// A quaternion for a rotation of @p yaw_rad about z.
geometry_msgs::Quaternion quaternion_from_yaw(double yaw_rad);
/// The planar part of a transform (x, y, yaw).
Pose2 from_ros(const geometry_msgs::Transform& t);
/// The planar part of a pose (x, y, yaw).
Pose2 from_ros(const geometry_msgs::Pose& p);

/// The scan's stamp, angles, limits, ranges and intensities.
LaserScan from_ros(const sensor_msgs::LaserScan& msg);
/// A LaserScan message with the core scan's values and the given frame (angle_max from the beam
/// count, no stated period).
sensor_msgs::LaserScan to_ros(const LaserScan& scan, const std::string& frame_id);
/// An Odometry message for a planar pose and velocity (forward v, yaw rate w).
nav_msgs::Odometry to_ros_odometry(double stamp_s, const std::string& frame_id,
                                   const std::string& child_frame_id, const Pose2& pose,
                                   double v_mps = 0.0, double w_radps = 0.0);

/// ROS 1 messages and the recording model, both ways. The ROS message made from a model message
/// made from a ROS message is the ROS message again, for the scan in every field.
ScanMessage to_message(const sensor_msgs::LaserScan& msg);
OdometryMessage to_message(const nav_msgs::Odometry& msg);
TransformsMessage to_message(const tf2_msgs::TFMessage& msg);
JointStateMessage to_message(const sensor_msgs::JointState& msg);
ImuMessage to_message(const sensor_msgs::Imu& msg);
NavSatFixMessage to_message(const sensor_msgs::NavSatFix& msg);
sensor_msgs::LaserScan to_ros(const ScanMessage& msg);
nav_msgs::Odometry to_ros(const OdometryMessage& msg);
tf2_msgs::TFMessage to_ros(const TransformsMessage& msg);
sensor_msgs::JointState to_ros(const JointStateMessage& msg);
sensor_msgs::Imu to_ros(const ImuMessage& msg);

/// The messages a filter node publishes for @p original: filtered_message() and labels_message()
/// of recording.hpp, in ROS 1 form.
sensor_msgs::LaserScan filtered_message(const sensor_msgs::LaserScan& original,
                                        const FilterResult& result);
sensor_msgs::LaserScan labels_message(const sensor_msgs::LaserScan& original,
                                      const FilterResult& result);

}  // namespace dispel::io
