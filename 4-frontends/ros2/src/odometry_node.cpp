#include "dispel/ros2/odometry_node.hpp"

#include <set>
#include <utility>

#include "dispel/io/errors.hpp"
#include "dispel/io/frame_tree.hpp"
#include "dispel/io/odometry_inputs.hpp"
#include "dispel/io/text.hpp"
#include "parameter_file.hpp"

namespace dispel::ros2 {

OdometryNodeSettings parse_odometry_node_parameters(const std::string& yaml_text,
                                                    const std::string& origin,
                                                    const std::string& node_name) {
  return parse_odometry_node_parameters(std::vector<ParameterText>{{yaml_text, origin}}, node_name);
}

OdometryNodeSettings parse_odometry_node_parameters(const std::vector<ParameterText>& files,
                                                    const std::string& node_name) {
  ParameterFile p(files, node_name);
  const std::string& origin = p.origin();
  OdometryNodeSettings s;
  s.node_name = node_name;
  std::string wheel_message = "joint_state";
  p.choice("wheel_message", wheel_message, {"joint_state", "odometry"});
  s.wheels_as_odometry = wheel_message == "odometry";
  p.topic("wheels_topic", s.wheels_topic);
  p.topic("imu_topic", s.imu_topic);
  p.topic("odometry_topic", s.odometry_topic);
  p.text("odom_frame", s.odom_frame);
  p.text("base_frame", s.base_frame);
  s.odom_frame = io::FrameTree::normalise(s.odom_frame);
  s.base_frame = io::FrameTree::normalise(s.base_frame);
  if (s.odom_frame.empty() || s.base_frame.empty() || s.odom_frame == s.base_frame) {
    throw io::ConfigError(origin +
                          ": odom_frame and base_frame must be two different frames (got " +
                          io::quote(s.odom_frame) + " and " + io::quote(s.base_frame) + ")");
  }
  p.boolean("publish_tf", s.publish_tf);
  p.number("reorder_window_s", s.reorder_window_s, 0.0, "a finite number >= 0");
  p.number("source_timeout_s", s.source_timeout_s, 1e-3, "a finite number >= 0.001");
  p.integer("queue_size", s.queue_size, 1, 1000000);
  p.number("diagnostics_period_s", s.diagnostics_period_s, 1e-3, "a finite number >= 0.001");
  p.boolean("use_sim_time", s.use_sim_time);
  p.distribution("ros_distro", s.ros_distro);
  // The filter's keys may share the file (one file for both nodes), as they may share a file
  // given to `dispel odom --config`; anything else is a mistake.
  const std::set<std::string> filter_keys = io::filter_config_top_level_keys();
  for (const std::string& key : p.rest_keys()) {
    if (key != "odometry" && filter_keys.count(key) == 0) {
      throw io::ConfigError(origin + ": " + io::quote(key) + " is not a parameter of " + node_name);
    }
  }
  s.odometry = io::parse_odometry_settings(p.rest_yaml(), origin);
  return s;
}

namespace {

std::vector<OdometryNodeOutput> outputs(const std::vector<OdometryEstimate>& estimates,
                                        const OdometryNodeSettings& s, std::int64_t& published) {
  std::vector<OdometryNodeOutput> out;
  out.reserve(estimates.size());
  for (const OdometryEstimate& e : estimates) {
    OdometryNodeOutput o;
    o.odometry = io::odometry_message(e, s.odom_frame, s.base_frame);
    o.transform.transforms.push_back(
        {o.odometry.header.stamp, s.odom_frame, s.base_frame, o.odometry.pose});
    out.push_back(std::move(o));
  }
  published += static_cast<std::int64_t>(out.size());
  return out;
}

}  // namespace

OdometryNodeCore::OdometryNodeCore(OdometryNodeSettings settings)
    : settings_(std::move(settings)),
      runner_(settings_.odometry.filter, settings_.reorder_window_s) {}

std::vector<OdometryNodeOutput> OdometryNodeCore::joint_state(const io::JointStateMessage& m,
                                                              double now_s,
                                                              const io::Stamp& ros_time) {
  const auto w = io::wheel_speeds(m, settings_.odometry, ros_time);
  if (!w) {
    ++malformed_;
    return poll(now_s);
  }
  runner_.add_wheels(w->t_s, w->left_mps, w->right_mps);
  return poll(now_s);
}

std::vector<OdometryNodeOutput> OdometryNodeCore::wheel_odometry(const io::OdometryMessage& m,
                                                                 double now_s,
                                                                 const io::Stamp& ros_time) {
  const io::WheelSpeeds w = io::wheel_speeds(m, settings_.odometry.filter.track_width_m, ros_time);
  runner_.add_wheels(w.t_s, w.left_mps, w.right_mps);
  return poll(now_s);
}

std::vector<OdometryNodeOutput> OdometryNodeCore::imu(const io::ImuMessage& m, double now_s,
                                                      const io::Stamp& ros_time) {
  runner_.add_imu(io::stamp_or(m.header.stamp, ros_time), io::yaw_rate(m, settings_.odometry));
  return poll(now_s);
}

std::vector<OdometryNodeOutput> OdometryNodeCore::poll(double now_s) {
  return outputs(runner_.release_at(now_s, settings_.source_timeout_s), settings_, published_);
}

pipeline::DiagnosticStatus OdometryNodeCore::diagnostics(std::int64_t undecodable) {
  const std::int64_t refused = pipeline::odometry_refused(runner_);
  pipeline::DiagnosticStatus s = pipeline::odometry_node_status(
      settings_.node_name, odometry_model_name(settings_.odometry.filter.model), runner_,
      {published_, malformed_, refused > refused_reported_});
  refused_reported_ = refused;
  s.values.emplace_back("undecodable messages", std::to_string(undecodable));
  return s;
}

}  // namespace dispel::ros2
