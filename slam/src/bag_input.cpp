// Internal to dispel::slam: the first pass over a bag (odometry, laser mount) and the scan loop.

#include "bag_input.hpp"

#include <nav_msgs/Odometry.h>
#include <rosbag/view.h>
#include <sensor_msgs/LaserScan.h>
#include <sys/stat.h>
#include <tf2_msgs/TFMessage.h>

#include <cerrno>
#include <cstring>

#include "dispel/io/bag_topics.hpp"
#include "dispel/io/filter_job.hpp"
#include "dispel/io/frame_tree.hpp"
#include "dispel/io/ros_convert.hpp"

namespace dispel::slam::detail {

using io::JobError;

void check_input_file(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) throw JobError(path + ": " + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) throw JobError(path + ": not a regular file");
}

BagMotion read_odometry_and_mount(rosbag::Bag& in, const std::string& path,
                                  const std::string& requested_scan_topic,
                                  const std::string& odom_topic, double odom_tolerance_s) {
  io::open_bag_for_reading(in, path);
  const io::BagTopics topics(in);
  std::string scan_topic = requested_scan_topic;
  if (scan_topic.empty()) {
    // What `dispel filter` writes, when it is there.
    scan_topic = topics.has("/scan_filtered", "sensor_msgs/LaserScan") ? "/scan_filtered" : "/scan";
  }
  if (!topics.has(scan_topic, "sensor_msgs/LaserScan")) {
    throw JobError(path + ": no sensor_msgs/LaserScan topic " + scan_topic +
                   " (LaserScan topics: " + topics.list("sensor_msgs/LaserScan") + ")");
  }
  if (!topics.has(odom_topic, "nav_msgs/Odometry")) {
    throw JobError(path + ": no nav_msgs/Odometry topic " + odom_topic +
                   " (Odometry topics: " + topics.list("nav_msgs/Odometry") + ")");
  }

  BagMotion out{PoseBuffer(odom_tolerance_s, 0.5), Pose2{}, 0, scan_topic};
  io::FrameTree mounts;
  std::string base_frame = "base_link";
  std::string odom_frame = "odom";
  std::string laser_frame;
  bool have_laser_frame = false;
  try {
    rosbag::View view(in, rosbag::TopicQuery({scan_topic, odom_topic, "/tf", "/tf_static"}));
    bool have_odom_frames = false;
    for (const rosbag::MessageInstance& m : view) {
      if (m.getTopic() == scan_topic) {
        if (have_laser_frame) continue;
        if (const auto scan = m.instantiate<sensor_msgs::LaserScan>()) {
          laser_frame = io::FrameTree::normalise(scan->header.frame_id);
          have_laser_frame = true;
        }
      } else if (m.getTopic() == odom_topic) {
        const auto odom = m.instantiate<nav_msgs::Odometry>();
        if (!odom) continue;
        if (!have_odom_frames) {
          if (!odom->child_frame_id.empty())
            base_frame = io::FrameTree::normalise(odom->child_frame_id);
          if (!odom->header.frame_id.empty())
            odom_frame = io::FrameTree::normalise(odom->header.frame_id);
          have_odom_frames = true;
        }
        if (!out.odometry.add(io::to_seconds(odom->header.stamp), io::from_ros(odom->pose.pose))) {
          ++out.odometry_refused;
        }
      } else if (const auto tf = m.instantiate<tf2_msgs::TFMessage>()) {
        for (const auto& t : tf->transforms) {
          const std::string parent = io::FrameTree::normalise(t.header.frame_id);
          const std::string child = io::FrameTree::normalise(t.child_frame_id);
          // Only fixed mounts: not the robot's motion in odom or map.
          if (parent == odom_frame || child == odom_frame || parent == "map" || child == "map") {
            continue;
          }
          mounts.set(parent, child, io::from_ros(t.transform));
        }
      }
    }
  } catch (...) {
    io::rethrow_as_recording_error(path);
  }
  if (!have_laser_frame) throw JobError(path + ": no scans on " + scan_topic);
  if (out.odometry.empty()) throw JobError(path + ": no usable odometry on " + odom_topic);
  if (!laser_frame.empty() && laser_frame != base_frame) {
    const auto found = mounts.lookup(base_frame, laser_frame);
    if (!found) {
      throw JobError(path + ": no transform from " + base_frame + " to " + laser_frame +
                     " in /tf_static or /tf; record the sensor mount");
    }
    out.mount = *found;
  }
  return out;
}

void for_each_scan(const rosbag::Bag& in, const std::string& path, const std::string& scan_topic,
                   const std::function<void(const LaserScan&)>& visit) {
  try {
    rosbag::View view(in, rosbag::TopicQuery(scan_topic));
    for (const rosbag::MessageInstance& m : view) {
      const auto msg = m.instantiate<sensor_msgs::LaserScan>();
      if (msg) visit(io::from_ros(*msg));
    }
  } catch (...) {
    io::rethrow_as_recording_error(path);
  }
}

}  // namespace dispel::slam::detail
