// dispel_odometry_node: wheel speeds and an IMU yaw rate fused by dispel's unscented Kalman filter.
// Subscribes `wheels` (sensor_msgs/JointState or nav_msgs/Odometry) and `imu`
// (sensor_msgs/Imu); publishes `odometry/filtered` (nav_msgs/Odometry), optionally the TF
// odom -> base_link, and /diagnostics. Parameters: the node's own (below) and `odometry/...`
// under the names of config/default.yaml's `odometry:` section.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/JointState.h>
#include <tf2_ros/transform_broadcaster.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#include "dispel/io/config_yaml.hpp"
#include "dispel/io/frame_tree.hpp"
#include "dispel/io/ros1_messages.hpp"
#include "dispel/pipeline/odometry_runner.hpp"
#include "dispel/ros1/convert.hpp"
#include "dispel/ros1/parameters.hpp"

namespace dispel::ros1 {
namespace {

struct OdometryNodeSettings {
  bool wheels_as_odometry = false;  ///< `wheels` is nav_msgs/Odometry, else sensor_msgs/JointState.
  std::string odom_frame = "odom";
  std::string base_frame = "base_link";
  bool publish_tf = false;
  double reorder_window_s = 0.05;
  double source_timeout_s = 0.5;
  int queue_size = 100;
  double diagnostics_period_s = 1.0;
  io::OdometrySettings odometry;
};

OdometryNodeSettings read_settings(const std::string& node_name) {
  XmlRpc::XmlRpcValue tree;
  ros::param::get(node_name, tree);
  NodeParameters p(tree, node_name + "/");
  OdometryNodeSettings s;
  s.wheels_as_odometry =
      p.choice("wheel_message", "joint_state", {"joint_state", "odometry"}) == "odometry";
  s.odom_frame = io::FrameTree::normalise(p.text("odom_frame", s.odom_frame));
  s.base_frame = io::FrameTree::normalise(p.text("base_frame", s.base_frame));
  if (s.odom_frame.empty() || s.base_frame.empty() || s.odom_frame == s.base_frame) {
    throw ParameterError(node_name + "/odom_frame and " + node_name +
                         "/base_frame must be two different frames, got '" + s.odom_frame +
                         "' and '" + s.base_frame + "'");
  }
  s.publish_tf = p.boolean("publish_tf", s.publish_tf);
  s.reorder_window_s = p.number("reorder_window_s", s.reorder_window_s);
  p.require(std::isfinite(s.reorder_window_s) && s.reorder_window_s >= 0.0, "reorder_window_s",
            "a finite number >= 0", s.reorder_window_s);
  s.source_timeout_s = p.number("source_timeout_s", s.source_timeout_s);
  p.require(std::isfinite(s.source_timeout_s) && s.source_timeout_s > 0.0, "source_timeout_s",
            "a finite number > 0", s.source_timeout_s);
  s.queue_size = p.integer("queue_size", s.queue_size);
  p.require(s.queue_size >= 1, "queue_size", "an integer >= 1", s.queue_size);
  s.diagnostics_period_s = p.number("diagnostics_period_s", s.diagnostics_period_s);
  p.require(std::isfinite(s.diagnostics_period_s) && s.diagnostics_period_s > 0.0,
            "diagnostics_period_s", "a finite number > 0", s.diagnostics_period_s);
  // The filter's keys may share the namespace (one YAML file for both nodes), as they may share
  // a file given to `dispel odom --config`; anything else is a mistake.
  const std::set<std::string> filter_keys = io::filter_config_top_level_keys();
  for (const std::string& name : p.members()) {
    if (p.keys().count(name) == 0 && filter_keys.count(name) == 0) {
      throw ParameterError(node_name + "/" + name + " is not a parameter of this node");
    }
  }
  s.odometry =
      io::parse_odometry_settings(to_yaml(p.tree(), p.keys()), "parameters of " + node_name);
  return s;
}

std::string seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4f", s);
  return buf;
}

class OdometryNode {
 public:
  OdometryNode(ros::NodeHandle& nh, OdometryNodeSettings settings)
      : settings_(std::move(settings)),
        runner_(settings_.odometry.filter, settings_.reorder_window_s) {
    const auto queue = static_cast<std::uint32_t>(settings_.queue_size);
    const auto hints = ros::TransportHints().tcpNoDelay();
    wheels_sub_ = settings_.wheels_as_odometry
                      ? nh.subscribe("wheels", queue, &OdometryNode::on_wheel_odometry, this, hints)
                      : nh.subscribe("wheels", queue, &OdometryNode::on_joint_state, this, hints);
    imu_sub_ = nh.subscribe("imu", queue, &OdometryNode::on_imu, this, hints);
    odom_pub_ = nh.advertise<nav_msgs::Odometry>("odometry/filtered", queue);
    diagnostics_pub_ = nh.advertise<diagnostic_msgs::DiagnosticArray>("/diagnostics", 2);
    if (settings_.publish_tf) broadcaster_.emplace();
    // Measurements wait for every source; one that has been quiet for source_timeout_s (a stalled
    // sensor, the end of a recording) is no longer waited for: checked four times per timeout.
    quiet_timer_ =
        nh.createSteadyTimer(ros::WallDuration(std::max(settings_.source_timeout_s / 4.0, 0.001)),
                             [this](auto&) { publish(); });
    diagnostics_timer_ = nh.createSteadyTimer(ros::WallDuration(settings_.diagnostics_period_s),
                                              &OdometryNode::publish_diagnostics, this);
    ROS_INFO("dispel odometry (%s): %s (%s) + %s -> %s%s",
             odometry_model_name(settings_.odometry.filter.model), wheels_sub_.getTopic().c_str(),
             settings_.wheels_as_odometry ? "nav_msgs/Odometry" : "sensor_msgs/JointState",
             imu_sub_.getTopic().c_str(), odom_pub_.getTopic().c_str(),
             settings_.publish_tf
                 ? (", TF " + settings_.odom_frame + " -> " + settings_.base_frame).c_str()
                 : "");
  }

 private:
  static double now_s() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
  }

  void on_joint_state(const sensor_msgs::JointState::ConstPtr& msg) {
    const auto w =
        io::wheel_speeds(io::to_message(*msg), settings_.odometry, io::to_stamp(ros::Time::now()));
    if (!w) {
      ++malformed_;
      ROS_WARN_THROTTLE(5.0, "dispel odometry: a JointState on %s without both wheel velocities",
                        wheels_sub_.getTopic().c_str());
      return;
    }
    runner_.add_wheels(w->t_s, w->left_mps, w->right_mps);
    publish();
  }

  void on_wheel_odometry(const nav_msgs::Odometry::ConstPtr& msg) {
    const io::WheelSpeeds w =
        io::wheel_speeds(io::to_message(*msg), settings_.odometry.filter.track_width_m,
                         io::to_stamp(ros::Time::now()));
    runner_.add_wheels(w.t_s, w.left_mps, w.right_mps);
    publish();
  }

  void on_imu(const sensor_msgs::Imu::ConstPtr& msg) {
    const io::ImuMessage imu = io::to_message(*msg);
    runner_.add_imu(io::stamp_or(imu.header.stamp, io::to_stamp(ros::Time::now())),
                    io::yaw_rate(imu, settings_.odometry));
    publish();
  }

  void publish() {
    const std::array<bool, 2> waited = {runner_.waiting_for(pipeline::OdometrySource::kWheels),
                                        runner_.waiting_for(pipeline::OdometrySource::kImu)};
    for (const OdometryEstimate& e : runner_.release_at(now_s(), settings_.source_timeout_s)) {
      odom_pub_.publish(odometry_message(e, settings_.odom_frame, settings_.base_frame));
      if (broadcaster_) {
        broadcaster_->sendTransform(
            odometry_transform(e, settings_.odom_frame, settings_.base_frame));
      }
      ++published_;
    }
    // One throttled warning per source (a macro's throttle is per place in the code).
    if (waited[0] && !runner_.waiting_for(pipeline::OdometrySource::kWheels)) {
      ROS_WARN_THROTTLE(5.0, "%s", quiet_message("wheel", wheels_sub_.getTopic()).c_str());
    }
    if (waited[1] && !runner_.waiting_for(pipeline::OdometrySource::kImu)) {
      ROS_WARN_THROTTLE(5.0, "%s", quiet_message("IMU", imu_sub_.getTopic()).c_str());
    }
    const std::int64_t late = runner_.late(pipeline::OdometrySource::kWheels) +
                              runner_.late(pipeline::OdometrySource::kImu);
    if (late > late_warned_) {
      ROS_WARN_THROTTLE(5.0,
                        "dispel odometry: %lld wheel and %lld IMU measurements so far arrived "
                        "later than reorder_window_s (%g s) and source_timeout_s (%g s) allow: "
                        "older than a measurement already fused, refused",
                        static_cast<long long>(runner_.late(pipeline::OdometrySource::kWheels)),
                        static_cast<long long>(runner_.late(pipeline::OdometrySource::kImu)),
                        settings_.reorder_window_s, settings_.source_timeout_s);
      late_warned_ = late;
    }
  }

  std::string quiet_message(const char* what, const std::string& topic) const {
    return std::string("dispel odometry: no ") + what + " measurement on " + topic + " for " +
           seconds(settings_.source_timeout_s) +
           " s (source_timeout_s) while measurements wait for it: fusing without it until it "
           "comes back";
  }

  void publish_diagnostics(const ros::SteadyTimerEvent&) {
    const std::int64_t refused = pipeline::odometry_refused(runner_);
    diagnostic_msgs::DiagnosticArray array;
    array.header.stamp = ros::Time::now();
    array.status.push_back(to_ros(pipeline::odometry_node_status(
        ros::this_node::getName(), odometry_model_name(settings_.odometry.filter.model), runner_,
        {published_, malformed_, refused > refused_reported_})));
    refused_reported_ = refused;
    diagnostics_pub_.publish(array);
  }

  OdometryNodeSettings settings_;
  pipeline::OdometryRunner runner_;
  ros::Subscriber wheels_sub_, imu_sub_;
  ros::Publisher odom_pub_, diagnostics_pub_;
  std::optional<tf2_ros::TransformBroadcaster> broadcaster_;
  ros::SteadyTimer quiet_timer_, diagnostics_timer_;
  std::int64_t malformed_ = 0;
  std::int64_t late_warned_ = 0;
  std::int64_t published_ = 0;
  std::int64_t refused_reported_ = 0;
};

}  // namespace
}  // namespace dispel::ros1

int main(int argc, char** argv) {
  ros::init(argc, argv, "dispel_odometry");
  ros::NodeHandle nh;
  std::optional<dispel::ros1::OdometryNode> node;
  try {
    node.emplace(nh, dispel::ros1::read_settings(ros::this_node::getName()));
  } catch (const std::exception& e) {  // ParameterError, io::ConfigError, std::invalid_argument
    ROS_FATAL("dispel_odometry_node: bad parameter: %s", e.what());
    return 1;
  }
  ros::spin();
  return 0;
}
