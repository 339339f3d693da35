#include "dispel/ros2/filter_node.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <set>
#include <utility>

#include "dispel/io/config_yaml.hpp"
#include "dispel/io/errors.hpp"
#include "dispel/io/ros2_messages.hpp"
#include "dispel/io/text.hpp"
#include "dispel/ros2/graph.hpp"

namespace dispel::ros2 {
namespace {

// How long a transform from the fixed frame is kept, and the largest step interpolated across
// (as `dispel filter` reads odometry: MotionQuery's defaults).
constexpr double kPoseToleranceS = 0.05;
constexpr double kPoseMaxGapS = 0.5;

// The node's own parameters, read and removed from @p p; the rest is the filter's.
void read_node_keys(YAML::Node& p, FilterNodeSettings& s, const std::string& origin) {
  const auto take = [&](const char* key) {
    const YAML::Node& map = p;  // Looked up const: a missing key is not made.
    const YAML::Node v = map[key];
    if (!v.IsDefined()) return YAML::Node(YAML::NodeType::Undefined);
    YAML::Node copy = YAML::Clone(v);
    p.remove(key);
    return copy;
  };
  const auto bad = [&](const char* key, const YAML::Node& v, const char* want) {
    return io::ConfigError(origin + ": " + key + " must be " + want + " (got " +
                           io::quote(YAML::Dump(v)) + ")");
  };
  const auto text = [&](const char* key, std::string& out) {
    const YAML::Node v = take(key);
    if (!v.IsDefined()) return;
    if (!v.IsScalar()) throw bad(key, v, "a string");
    out = v.Scalar();
  };
  const auto boolean = [&](const char* key, bool& out) {
    const YAML::Node v = take(key);
    if (!v.IsDefined()) return;
    if (!v.IsScalar() || !YAML::convert<bool>::decode(v, out)) throw bad(key, v, "true or false");
  };
  const auto number = [&](const char* key, double& out, double min, const char* want) {
    const YAML::Node v = take(key);
    if (!v.IsDefined()) return;
    double d = 0.0;
    if (!v.IsScalar() || !YAML::convert<double>::decode(v, d) || !std::isfinite(d) || d < min) {
      throw bad(key, v, want);
    }
    out = d;
  };
  text("scan_topic", s.scan_topic);
  if (!s.scan_topic.empty() && s.scan_topic[0] != '/') s.scan_topic = "/" + s.scan_topic;
  text("fixed_frame", s.fixed_frame);
  s.fixed_frame = io::FrameTree::normalise(s.fixed_frame);
  if (s.fixed_frame.empty()) throw io::ConfigError(origin + ": fixed_frame must not be empty");
  boolean("static_sensor", s.static_sensor);
  number("transform_timeout_s", s.transform_timeout_s, 0.0, "a finite number >= 0");
  std::string policy = "publish_unfiltered";
  text("on_missing_transform", policy);
  if (policy != "publish_unfiltered" && policy != "drop") {
    throw io::ConfigError(origin +
                          ": on_missing_transform must be publish_unfiltered or drop (got " +
                          io::quote(policy) + ")");
  }
  s.drop_without_transform = policy == "drop";
  double queue = s.queue_size;
  number("queue_size", queue, 1.0, "an integer >= 1");
  if (queue != std::floor(queue) || queue > 1e6) {
    throw io::ConfigError(origin + ": queue_size must be an integer from 1 to 1000000");
  }
  s.queue_size = static_cast<int>(queue);
  text("ros_distro", s.ros_distro);
  if (!s.ros_distro.empty()) {
    try {
      gid_layout_named(s.ros_distro);
    } catch (const DdsError& e) {
      throw io::ConfigError(origin + ": " + e.what());
    }
  }
  boolean("scale_to_scanner", s.runner.scale_to_scanner);
  number("scan_period_s", s.runner.scan_period_s, 0.0, "a finite number >= 0 (0: from the scans)");
  boolean("use_sim_time", s.use_sim_time);
}

}  // namespace

FilterNodeSettings parse_filter_node_parameters(const std::string& yaml_text,
                                                const std::string& origin,
                                                const std::string& node_name) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw io::ConfigError(origin + ": not YAML (" + io::one_line(e.what()) + ")");
  }
  FilterNodeSettings s;
  s.node_name = node_name;
  YAML::Node params = root;
  if (root.IsMap()) {
    // ROS 2's layout: the node's name (with or without its leading '/'), or "/**" for every node.
    for (const std::string& key : {node_name, "/" + node_name, std::string("/**")}) {
      if (root[key] && root[key]["ros__parameters"]) {
        params = root[key]["ros__parameters"];
        break;
      }
    }
    if (params == root) {
      for (const auto& entry : root) {
        if (entry.second.IsMap() && entry.second["ros__parameters"]) {
          throw io::ConfigError(origin + ": has parameters for " +
                                io::quote(entry.first.as<std::string>()) + ", not for " +
                                io::quote(node_name) + " or /**");
        }
      }
    }
  } else if (root.IsDefined() && !root.IsNull()) {
    throw io::ConfigError(origin + ": must be a mapping of parameters");
  }
  YAML::Node rest = params.IsMap() ? YAML::Clone(params) : YAML::Node(YAML::NodeType::Map);
  read_node_keys(rest, s, origin);
  s.runner.config = io::parse_filter_config(rest.size() == 0 ? "{}" : YAML::Dump(rest), origin);
  try {
    s.runner.validate();
  } catch (const std::invalid_argument& e) {
    throw io::ConfigError(origin + ": " + e.what());
  }
  return s;
}

FilterNodeCore::FilterNodeCore(FilterNodeSettings settings)
    : settings_(std::move(settings)), runner_(settings_.runner) {}

void FilterNodeCore::transforms(const io::TransformsMessage& message, bool is_static) {
  for (const io::FrameTransform& t : message.transforms) {
    const std::string parent = io::FrameTree::normalise(t.parent);
    const std::string child = io::FrameTree::normalise(t.child);
    if (!is_static && parent == settings_.fixed_frame) {
      auto it = motion_.try_emplace(child, kPoseToleranceS, kPoseMaxGapS).first;
      const double stamp_s = t.stamp.seconds();
      if (!it->second.empty() && stamp_s < it->second.poses().back().stamp_s - kTimeJumpS) {
        // Time went backwards: the motion known belongs to another run. Forgotten, so that the
        // new one is taken (a PoseBuffer refuses what is not after its last pose).
        for (auto& [robot, poses] : motion_) poses = PoseBuffer(kPoseToleranceS, kPoseMaxGapS);
        ++counts_.time_resets;
      }
      if (!it->second.add(stamp_s, t.child_in_parent)) ++counts_.transforms_refused;
      continue;
    }
    const Pose2& p = t.child_in_parent;
    if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m) || !std::isfinite(p.yaw_rad)) {
      ++counts_.transforms_refused;
      continue;
    }
    mounts_.set(parent, child, p);
  }
}

std::optional<Pose2> FilterNodeCore::sensor_pose(const std::string& laser_frame, double stamp_s,
                                                 PoseLookup& why) const {
  why = PoseLookup::kEmpty;
  if (settings_.static_sensor) {
    why = PoseLookup::kOk;
    return Pose2{};
  }
  const std::string laser = io::FrameTree::normalise(laser_frame);
  for (const auto& [robot, poses] : motion_) {
    const std::optional<Pose2> mount =
        robot == laser ? std::optional<Pose2>(Pose2{}) : mounts_.lookup(robot, laser);
    if (!mount) continue;
    Pose2 pose;
    why = poses.lookup(stamp_s, pose);
    if (why == PoseLookup::kOk) return pose * *mount;
    return std::nullopt;
  }
  return std::nullopt;
}

FilterNodeOutput FilterNodeCore::run(const io::ScanMessage& message,
                                     const std::optional<Pose2>& pose) {
  const FilterResult& result = runner_.process(message.scan, message.scan_time, pose);
  ++counts_.published;
  return {io::filtered_message(message, result), io::labels_message(message, result),
          runner_.last_outcome()};
}

std::vector<FilterNodeOutput> FilterNodeCore::scan(io::ScanMessage message, double now_s,
                                                   double ros_time_s) {
  ++counts_.scans_in;
  if (message.header.stamp.is_zero()) {  // A driver without a clock: the time it came.
    message.scan.stamp_s = ros_time_s;
    ++counts_.zero_stamps;
  }
  waiting_.push_back({std::move(message), now_s});
  std::vector<FilterNodeOutput> out = poll(now_s);
  // Still more waiting than the queue holds: the oldest go, filtered without a pose or dropped
  // (a robot whose odometry stopped must not make the node queue without bound).
  while (waiting_.size() > static_cast<std::size_t>(settings_.queue_size)) {
    ++counts_.dropped_queue_full;
    waiting_.pop_front();
  }
  return out;
}

std::vector<FilterNodeOutput> FilterNodeCore::poll(double now_s) {
  std::vector<FilterNodeOutput> out;
  while (!waiting_.empty()) {
    const Waiting& w = waiting_.front();
    PoseLookup why = PoseLookup::kEmpty;
    const std::optional<Pose2> pose =
        sensor_pose(w.message.header.frame_id, w.message.scan.stamp_s, why);
    // A pose that may still come: none yet, or the scan is newer than the last one. One before
    // the first pose or in a gap never will.
    const bool may_come = why == PoseLookup::kEmpty || why == PoseLookup::kAfterLast;
    if (!pose && may_come && now_s - w.since_s < settings_.transform_timeout_s) break;
    if (pose || !settings_.drop_without_transform) {
      out.push_back(run(w.message, pose));
    } else {
      ++counts_.dropped_without_transform;
    }
    waiting_.pop_front();
  }
  // Poses no waiting scan needs any more.
  if (!waiting_.empty()) {
    for (auto& [robot, poses] : motion_) poses.forget_before(waiting_.front().message.scan.stamp_s);
  } else if (!out.empty()) {
    for (auto& [robot, poses] : motion_) poses.forget_before(out.back().filtered.scan.stamp_s);
  }
  return out;
}

double decode_clock(const std::vector<std::uint8_t>& cdr) {
  // The encapsulation header, then builtin_interfaces/Time: int32 sec, uint32 nanosec.
  if (cdr.size() < 12 || cdr[0] != 0 || cdr[1] > 1) {
    throw io::CdrError("a /clock message is not rosgraph_msgs/Clock in CDR (" +
                       std::to_string(cdr.size()) + " bytes)");
  }
  const bool little = cdr[1] == 1;
  const auto u32 = [&](std::size_t at) {
    std::uint32_t v = 0;
    for (std::size_t k = 0; k < 4; ++k) {
      v |= static_cast<std::uint32_t>(cdr[at + (little ? k : 3 - k)]) << (8 * k);
    }
    return v;
  };
  const auto sec = static_cast<std::int32_t>(u32(4));
  const std::uint32_t nanosec = u32(8);
  if (nanosec >= 1000000000U) throw io::CdrError("a /clock message has nanosec >= 1e9");
  return static_cast<double>(sec) + 1e-9 * static_cast<double>(nanosec);
}

}  // namespace dispel::ros2
