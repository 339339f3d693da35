#pragma once
// Internal to dispel::slam: reading a ROS 1 bag for a run over its scans (the ICP-SLAM run and
// the particle-filter localisation read it alike). No MRPT here.

#include <rosbag/bag.h>

#include <cstdint>
#include <functional>
#include <string>

#include "dispel/core/laser_scan.hpp"
#include "dispel/core/pose2.hpp"
#include "dispel/core/pose_buffer.hpp"

namespace dispel::slam::detail {

/// Throws io::JobError "<path>: <reason>" unless @p path is a regular file.
void check_input_file(const std::string& path);

/// What the first pass over a bag gives.
struct BagMotion {
  PoseBuffer odometry;                ///< The robot (base frame) in the odometry frame.
  Pose2 mount;                        ///< The laser on the robot.
  std::int64_t odometry_refused = 0;  ///< Odometry messages out of order or not finite.
  std::string scan_topic;             ///< The scan topic read.
};

/// Opens @p path, checks that it has @p scan_topic (LaserScan; empty: /scan_filtered when the bag
/// has it, else /scan) and @p odom_topic (Odometry), and
/// reads the odometry and the laser mount (from /tf_static or /tf; base frame = the odometry's
/// child_frame_id). @throws io::JobError with a one-line message (not a bag, a missing topic, no
/// scans, no usable odometry, no laser mount).
BagMotion read_odometry_and_mount(rosbag::Bag& bag, const std::string& path,
                                  const std::string& scan_topic, const std::string& odom_topic,
                                  double odom_tolerance_s);

/// Calls @p visit with every scan on @p scan_topic, in order; errors of the bag library become
/// io::JobError naming @p path.
void for_each_scan(const rosbag::Bag& bag, const std::string& path, const std::string& scan_topic,
                   const std::function<void(const LaserScan&)>& visit);

}  // namespace dispel::slam::detail
