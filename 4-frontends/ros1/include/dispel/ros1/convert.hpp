#pragma once
/// @file
/// ROS 1 messages the nodes publish, built from dispel's results: free functions, nothing else
/// (the scan, odometry and IMU conversions shared with the bag tools are in
/// dispel/io/ros1_messages.hpp).

#include <diagnostic_msgs/DiagnosticStatus.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <std_msgs/Header.h>
#include <visualization_msgs/MarkerArray.h>

#include <string>
#include <utility>
#include <vector>

#include "dispel/core/dynamic_filter.hpp"
#include "dispel/core/odometry_fusion.hpp"
#include "dispel/pipeline/node_diagnostics.hpp"

namespace dispel::ros1 {

/// RViz markers for the tracks seen in the last scan, in the frame and at the stamp of
/// @p header (the fixed frame the filter tracks in): a DELETEALL first, then per object a
/// cylinder at its centroid coloured by class (static grey, dynamic red, unknown orange), a line
/// between its edge points, an arrow for its velocity (one second of motion) and its id.
visualization_msgs::MarkerArray object_markers(const std::vector<TrackedObject>& tracks,
                                               const std_msgs::Header& header);

/// nav_msgs/Odometry for an estimate: pose and forward, lateral and yaw velocity, with the
/// estimate's variances on the covariance diagonals (x, y, yaw; v, omega; unestimated 0).
nav_msgs::Odometry odometry_message(const OdometryEstimate& estimate, const std::string& frame_id,
                                    const std::string& child_frame_id);

/// The transform @p frame_id -> @p child_frame_id that an estimate's pose stands for.
geometry_msgs::TransformStamped odometry_transform(const OdometryEstimate& estimate,
                                                   const std::string& frame_id,
                                                   const std::string& child_frame_id);

/// A node's diagnostic status (pipeline::filter_node_status, odometry_node_status) as ROS 1's.
diagnostic_msgs::DiagnosticStatus to_ros(const pipeline::DiagnosticStatus& status);

}  // namespace dispel::ros1
