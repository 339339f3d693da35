#pragma once
/// @file
/// The ROS 2 odometry node's work without DDS: its parameters (a ROS 2 parameter file), wheel
/// speeds from sensor_msgs/JointState or nav_msgs/Odometry and the yaw rate from sensor_msgs/Imu
/// read as `dispel odom` reads them (io/odometry_inputs.hpp), and the shared runner
/// (pipeline::OdometryRunner, the one `dispel odom` and the ROS 1 node use). dispel-ros2 adds
/// only the DDS readers and writers around it (docs/ros2.md).

#include <cstdint>
#include <string>
#include <vector>

#include "dispel/io/config_yaml.hpp"
#include "dispel/io/recording.hpp"
#include "dispel/pipeline/node_diagnostics.hpp"
#include "dispel/pipeline/odometry_runner.hpp"
#include "dispel/ros2/parameter_text.hpp"

namespace dispel::ros2 {

/// The node's parameters; the fusion's are config/default.yaml's `odometry:` section.
struct OdometryNodeSettings {
  std::string node_name = "dispel_odometry";
  std::string wheels_topic = "/wheels";
  bool wheels_as_odometry = false;  ///< wheels_topic is nav_msgs/Odometry, else JointState.
  std::string imu_topic = "/imu";
  std::string odometry_topic = "/odometry/filtered";
  std::string odom_frame = "odom";
  std::string base_frame = "base_link";
  bool publish_tf = false;            ///< Also odom_frame -> base_frame on /tf.
  double reorder_window_s = 0.05;     ///< Stamp time measurements wait for both sources.
  double source_timeout_s = 0.5;      ///< Steady time a silent source is waited for.
  int queue_size = 100;               ///< Of the readers (best effort: the oldest go when full).
  double diagnostics_period_s = 1.0;  ///< Steady time between two /diagnostics messages.
  bool use_sim_time = false;
  std::string ros_distro;  ///< As FilterNodeSettings::ros_distro.
  io::OdometrySettings odometry;
};

/// Reads a ROS 2 parameter file as parse_filter_node_parameters() does; the filter's keys may be
/// there too (one file for both nodes) and are ignored. @throws io::ConfigError
OdometryNodeSettings parse_odometry_node_parameters(const std::string& yaml_text,
                                                    const std::string& origin,
                                                    const std::string& node_name);
/// The same from several files in order (ParameterFile's rules: "/**" then the node's block, a
/// later value replacing an earlier one).
OdometryNodeSettings parse_odometry_node_parameters(const std::vector<ParameterText>& files,
                                                    const std::string& node_name);

/// What the node publishes for one estimate.
struct OdometryNodeOutput {
  io::OdometryMessage odometry;     ///< On odometry_topic.
  io::TransformsMessage transform;  ///< On /tf when publish_tf.
};

class OdometryNodeCore {
 public:
  /// @throws std::invalid_argument for a bad configuration (OdometryRunner's).
  explicit OdometryNodeCore(OdometryNodeSettings settings);

  /// A message on wheels_topic or imu_topic, received at @p now_s (steady clock, s) and
  /// @p ros_time (for a message without a stamp). Returns the estimates now released.
  std::vector<OdometryNodeOutput> joint_state(const io::JointStateMessage& m, double now_s,
                                              const io::Stamp& ros_time);
  std::vector<OdometryNodeOutput> wheel_odometry(const io::OdometryMessage& m, double now_s,
                                                 const io::Stamp& ros_time);
  std::vector<OdometryNodeOutput> imu(const io::ImuMessage& m, double now_s,
                                      const io::Stamp& ros_time);
  /// What is released at @p now_s: a source silent for source_timeout_s is no longer waited for.
  std::vector<OdometryNodeOutput> poll(double now_s);

  const OdometryNodeSettings& settings() const { return settings_; }
  const pipeline::OdometryRunner& runner() const { return runner_; }
  std::int64_t published() const { return published_; }
  /// JointState messages without both wheels' velocities.
  std::int64_t malformed() const { return malformed_; }
  /// The node's status on /diagnostics (pipeline::odometry_node_status, as the ROS 1 node says
  /// it; WARN when measurements were refused since the last call). @p undecodable: messages the
  /// node could not decode.
  pipeline::DiagnosticStatus diagnostics(std::int64_t undecodable);

 private:
  OdometryNodeSettings settings_;
  pipeline::OdometryRunner runner_;
  std::int64_t published_ = 0;
  std::int64_t malformed_ = 0;
  std::int64_t refused_reported_ = 0;  // By the last diagnostics().
};

}  // namespace dispel::ros2
