#pragma once
/// @file
/// The ROS 2 filter node's work without DDS: its parameters (a ROS 2 parameter file), the sensor
/// pose from /tf and /tf_static, the scans that wait for it, and the shared runner
/// (pipeline::ScanFilterRunner, the one `dispel filter` and the ROS 1 node use). dispel-ros2
/// adds only the DDS readers and writers around it (docs/ros2.md).

#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "dispel/core/pose_buffer.hpp"
#include "dispel/io/frame_tree.hpp"
#include "dispel/io/recording.hpp"
#include "dispel/pipeline/node_diagnostics.hpp"
#include "dispel/pipeline/scan_filter_runner.hpp"
#include "dispel/ros2/parameter_text.hpp"

namespace dispel::ros2 {

/// The node's parameters; the filter's are config/default.yaml's keys.
struct FilterNodeSettings {
  std::string node_name = "dispel_filter";
  std::string scan_topic = "/scan";
  std::string fixed_frame = "odom";     ///< The frame objects are tracked in.
  bool static_sensor = false;           ///< The sensor does not move: identity pose, no TF.
  double transform_timeout_s = 0.1;     ///< Longest wait for the sensor pose at a scan's stamp.
  bool drop_without_transform = false;  ///< Else published unfiltered.
  bool use_sim_time = false;            ///< ROS time from /clock (a recording played).
  int queue_size = 10;                  ///< Scans waiting for their pose, at most.
  double diagnostics_period_s = 1.0;    ///< Steady time between two /diagnostics messages.
  /// The ROS 2 distribution whose graph layout (gid size) ros_discovery_info uses; empty: the
  /// environment's ROS_DISTRO, else humble.
  std::string ros_distro;
  pipeline::ScanFilterRunnerOptions runner;
};

/// Reads a ROS 2 parameter file (`<node>: ros__parameters: {...}`, the node's name or "/**"
/// matching; or the parameters at the top level, as `dispel filter --config` reads them).
/// @p origin names the file in errors. @throws io::ConfigError naming the key and the value.
FilterNodeSettings parse_filter_node_parameters(const std::string& yaml_text,
                                                const std::string& origin,
                                                const std::string& node_name);
/// The same from several files in order (ParameterFile's rules: "/**" then the node's block, a
/// later value replacing an earlier one).
FilterNodeSettings parse_filter_node_parameters(const std::vector<ParameterText>& files,
                                                const std::string& node_name);

/// What the node publishes for one scan.
struct FilterNodeOutput {
  io::ScanMessage filtered;  ///< On <scan>_filtered: removed beams NaN.
  io::ScanMessage labels;    ///< On <scan>_labels: intensities = beam labels.
  pipeline::ScanOutcome outcome;
};

/// Counts since the node started.
struct FilterNodeCounts {
  std::int64_t scans_in = 0;
  std::int64_t published = 0;
  std::int64_t without_pose = 0;               ///< No sensor pose in time (published or dropped).
  std::int64_t dropped_without_transform = 0;  ///< on_missing_transform: drop.
  std::int64_t dropped_queue_full = 0;         ///< The oldest waiting scan, for a newer one.
  std::int64_t transforms_refused = 0;         ///< Not finite, or not after the last one.
  std::int64_t undecodable = 0;                ///< Messages the CDR decoders refused.
  /// The robot's motion forgotten: a transform from the fixed frame more than kTimeJumpS before
  /// the last one (a recording played again, /clock reset).
  std::int64_t time_resets = 0;
  std::int64_t zero_stamps = 0;  ///< Scans without a stamp, given the time they came.
};

/// An earlier transform than the last by more than this is time going backwards (s); less is
/// transforms out of order, refused.
constexpr double kTimeJumpS = 1.0;

class FilterNodeCore {
 public:
  /// @throws std::invalid_argument if settings.runner.validate() does.
  explicit FilterNodeCore(FilterNodeSettings settings);

  /// A tf2_msgs/TFMessage from /tf (@p is_static false) or /tf_static. Transforms from the fixed
  /// frame are the robot's motion (kept in time); the others are mounts (the latest counts).
  void transforms(const io::TransformsMessage& message, bool is_static);

  /// A scan, received at @p now_s (a steady clock, seconds) and at @p ros_time_s (ROS time:
  /// the system clock, or /clock under use_sim_time), which a scan without a stamp is filtered at
  /// (the header it is published with keeps its zero stamp). It waits for its pose with the
  /// others. Returns what is ready to publish, in the scans' order.
  std::vector<FilterNodeOutput> scan(io::ScanMessage message, double now_s, double ros_time_s);

  /// What is ready at @p now_s: scans whose pose is known, or whose wait ran out.
  std::vector<FilterNodeOutput> poll(double now_s);

  const FilterNodeSettings& settings() const { return settings_; }
  const FilterNodeCounts& counts() const { return counts_; }
  const pipeline::ScanFilterRunner& runner() const { return runner_; }
  void count_undecodable() { ++counts_.undecodable; }
  /// The node's status on /diagnostics for the period since the last call: the filter's
  /// (pipeline::filter_node_status, as the ROS 1 node says it; WARN for scans without a sensor
  /// pose in the period) and what this node counts besides. @p undecodable_elsewhere: messages
  /// refused outside the core (/clock).
  pipeline::DiagnosticStatus diagnostics(std::int64_t undecodable_elsewhere);
  /// The transforms of the robot's motion kept (all robot frames).
  std::size_t motion_kept() const;

 private:
  struct Waiting {
    io::ScanMessage message;
    double since_s;
  };
  // The sensor pose at @p stamp_s, or why there is none yet.
  std::optional<Pose2> sensor_pose(const std::string& laser_frame, double stamp_s,
                                   PoseLookup& why) const;
  FilterNodeOutput run(const io::ScanMessage& message, const std::optional<Pose2>& pose);

  FilterNodeSettings settings_;
  pipeline::ScanFilterRunner runner_;
  io::FrameTree mounts_;
  std::map<std::string, PoseBuffer> motion_;  // By child frame: its pose in the fixed frame.
  std::deque<Waiting> waiting_;
  FilterNodeCounts counts_;
  std::int64_t without_pose_reported_ = 0;  // By the last diagnostics().
};

}  // namespace dispel::ros2
