#include "dispel/ros2/filter_node.hpp"

#include <cmath>
#include <set>
#include <utility>

#include "dispel/io/config_yaml.hpp"
#include "dispel/io/errors.hpp"
#include "dispel/io/ros2_messages.hpp"
#include "dispel/io/text.hpp"
#include "parameter_file.hpp"

namespace dispel::ros2 {
namespace {

// How long a transform from the fixed frame is kept, and the largest step interpolated across
// (as `dispel filter` reads odometry: MotionQuery's defaults).
constexpr double kPoseToleranceS = 0.05;
constexpr double kPoseMaxGapS = 0.5;
// How far back the robot's motion is kept (tf2's default buffer: 10 s).
constexpr double kMotionHistoryS = 10.0;

}  // namespace

FilterNodeSettings parse_filter_node_parameters(const std::string& yaml_text,
                                                const std::string& origin,
                                                const std::string& node_name) {
  return parse_filter_node_parameters(std::vector<ParameterText>{{yaml_text, origin}}, node_name);
}

FilterNodeSettings parse_filter_node_parameters(const std::vector<ParameterText>& files,
                                                const std::string& node_name) {
  ParameterFile p(files, node_name);
  const std::string& origin = p.origin();
  FilterNodeSettings s;
  s.node_name = node_name;
  p.topic("scan_topic", s.scan_topic);
  p.text("fixed_frame", s.fixed_frame);
  s.fixed_frame = io::FrameTree::normalise(s.fixed_frame);
  if (s.fixed_frame.empty()) throw io::ConfigError(origin + ": fixed_frame must not be empty");
  p.boolean("static_sensor", s.static_sensor);
  p.number("transform_timeout_s", s.transform_timeout_s, 0.0, "a finite number >= 0");
  std::string policy = "publish_unfiltered";
  p.choice("on_missing_transform", policy, {"publish_unfiltered", "drop"});
  s.drop_without_transform = policy == "drop";
  p.integer("queue_size", s.queue_size, 1, 1000000);
  p.number("diagnostics_period_s", s.diagnostics_period_s, 1e-3, "a finite number >= 0.001");
  p.distribution("ros_distro", s.ros_distro);
  p.boolean("scale_to_scanner", s.runner.scale_to_scanner);
  p.number("scan_period_s", s.runner.scan_period_s, 0.0,
           "a finite number >= 0 (0: from the scans)");
  p.boolean("use_sim_time", s.use_sim_time);
  // Everything else is the filter's: the same parser, keys and messages as `dispel filter`.
  s.runner.config = io::parse_filter_config(p.rest_yaml(), origin);
  s.runner.static_sensor = s.static_sensor;
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
      // Kept for kMotionHistoryS, as tf2 keeps its buffer: without scans (or with scans that
      // are dropped) it would otherwise grow for as long as the node runs.
      it->second.forget_before(stamp_s - kMotionHistoryS);
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

std::size_t FilterNodeCore::motion_kept() const {
  std::size_t n = 0;
  for (const auto& [robot, poses] : motion_) n += poses.size();
  return n;
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
    if (!pose) ++counts_.without_pose;
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

pipeline::DiagnosticStatus FilterNodeCore::diagnostics(std::int64_t undecodable_elsewhere) {
  pipeline::DiagnosticStatus s = pipeline::filter_node_status(
      settings_.node_name, runner_,
      {counts_.without_pose, counts_.without_pose - without_pose_reported_,
       counts_.dropped_without_transform});
  without_pose_reported_ = counts_.without_pose;
  s.values.insert(
      s.values.end(),
      {{"scans received", std::to_string(counts_.scans_in)},
       {"scans waiting for a sensor pose", std::to_string(waiting_.size())},
       {"scans dropped (queue full)", std::to_string(counts_.dropped_queue_full)},
       {"transforms refused", std::to_string(counts_.transforms_refused)},
       {"undecodable messages", std::to_string(counts_.undecodable + undecodable_elsewhere)},
       {"times time went backwards", std::to_string(counts_.time_resets)},
       {"scans without a stamp", std::to_string(counts_.zero_stamps)}});
  return s;
}

}  // namespace dispel::ros2
