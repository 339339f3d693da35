#include "dispel/io/recording_motion.hpp"

#include <map>
#include <utility>

#include "dispel/io/errors.hpp"
#include "dispel/io/frame_tree.hpp"
#include "dispel/pipeline/scan_period.hpp"

namespace dispel::io {
namespace {

// Scans decoded at most for the period (when their stamps never increase it stays unknown).
constexpr std::int64_t kPeriodScans = 200;

}  // namespace

std::optional<Pose2> RecordingMotion::sensor_pose(double stamp_s, PoseLookup* why) const {
  if (static_sensor) return Pose2{};
  if (laser_only) {
    if (why != nullptr) *why = PoseLookup::kEmpty;
    return std::nullopt;
  }
  Pose2 base;
  const PoseLookup found = base_poses.lookup(stamp_s, base);
  if (why != nullptr) *why = found;
  if (found != PoseLookup::kOk) return std::nullopt;
  return base * mount;
}

RecordingMotion read_motion(RecordingReader& reader, const MotionQuery& q,
                            const std::function<void()>& poll) {
  const std::string& path = reader.path();
  const Topics& topics = reader.topics();
  RecordingMotion m;
  m.scan_topic = q.scan_topic;
  if (m.scan_topic.empty()) {
    m.scan_topic =
        topics.has("/scan_filtered", MessageKind::kLaserScan) ? "/scan_filtered" : "/scan";
  }
  if (!topics.has(m.scan_topic, MessageKind::kLaserScan)) {
    throw InputError(path + ": no sensor_msgs/LaserScan topic " + m.scan_topic +
                     " (LaserScan topics: " + topics.list(MessageKind::kLaserScan) + ")" +
                     q.missing_scan_hint);
  }
  m.laser_only = q.laser_only || (q.laser_only_without_odometry && q.pose_topic &&
                                  topics.of_kind(MessageKind::kOdometry).empty());
  m.static_sensor = !q.pose_topic && !m.laser_only;
  const bool read_poses = q.pose_topic && !m.laser_only;
  if (read_poses && !topics.has(*q.pose_topic, MessageKind::kOdometry)) {
    throw InputError(path + ": no nav_msgs/Odometry topic " + *q.pose_topic +
                     " (Odometry topics: " + topics.list(MessageKind::kOdometry) + ")" +
                     q.missing_pose_hint);
  }
  m.fixed_frame = q.default_fixed_frame;
  m.base_frame = "base_link";
  m.base_poses = PoseBuffer(q.pose_tolerance_s, q.pose_max_gap_s);

  std::vector<std::string> wanted{m.scan_topic, "/tf", "/tf_static"};
  if (read_poses) wanted.push_back(*q.pose_topic);
  std::int64_t decoded = 0;
  bool have_pose_frames = false;
  pipeline::ScanPeriod period;
  std::map<std::pair<std::string, std::string>, Pose2> edges;  // Latest value of each.
  reader.read(wanted, [&](const RecordedMessage& msg) {
    if (poll) poll();
    if (msg.topic() == m.scan_topic) {
      ++m.scans;
      if (decoded >= kPeriodScans || (decoded > 0 && period.period())) return;
      const std::optional<ScanMessage> scan = msg.scan();
      if (!scan) return;
      if (decoded++ == 0) {
        m.first_scan = scan->scan;
        m.laser_frame = FrameTree::normalise(scan->header.frame_id);
      }
      period.add(scan->scan.stamp_s, scan->scan_time);
    } else if (read_poses && msg.topic() == *q.pose_topic) {
      const std::optional<OdometryMessage> odom = msg.odometry();
      if (!odom) return;
      if (!have_pose_frames) {
        if (!odom->child_frame_id.empty())
          m.base_frame = FrameTree::normalise(odom->child_frame_id);
        if (!odom->header.frame_id.empty()) {
          m.fixed_frame = FrameTree::normalise(odom->header.frame_id);
        }
        have_pose_frames = true;
      }
      if (!m.base_poses.add(odom->header.stamp.seconds(), odom->pose)) ++m.poses_refused;
    } else if (const std::optional<TransformsMessage> tf = msg.transforms()) {
      for (const FrameTransform& t : tf->transforms) {
        edges[{FrameTree::normalise(t.parent), FrameTree::normalise(t.child)}] = t.child_in_parent;
      }
    }
  });
  if (decoded == 0) throw InputError(path + ": no scans on " + m.scan_topic);
  m.scan_period_s = period.period();
  if (m.static_sensor || m.laser_only) return m;
  if (m.base_poses.empty()) throw InputError(path + ": no usable poses on " + *q.pose_topic);
  // Only fixed mounts: not the robot's motion in the fixed frame, odom or map.
  FrameTree mounts;
  const auto moving = [&](const std::string& frame) {
    return frame == m.fixed_frame || frame == "odom" || frame == "map";
  };
  for (const auto& [edge, pose] : edges) {
    if (!moving(edge.first) && !moving(edge.second)) mounts.set(edge.first, edge.second, pose);
  }
  const std::string laser = m.laser_frame.empty() ? m.base_frame : m.laser_frame;
  const std::optional<Pose2> mount = mounts.lookup(m.base_frame, laser);
  if (!mount) {
    throw InputError(path + ": no transform from " + m.base_frame + " to " + laser +
                     " in /tf_static or /tf" + q.missing_mount_hint);
  }
  m.mount = *mount;
  return m;
}

}  // namespace dispel::io
