#include "dispel/io/recording.hpp"

#include <cmath>
#include <limits>
#include <type_traits>
#include <utility>

#include "dispel/io/errors.hpp"

namespace dispel::io {

DecodedMessage::DecodedMessage(std::string topic, Stamp time, DecodedPayload payload)
    : topic_(std::move(topic)), time_(time), payload_(std::move(payload)) {
  // The variant's alternatives in MessageKind's order.
  static_assert(std::is_same_v<std::variant_alternative_t<0, DecodedPayload>, ScanMessage> &&
                std::is_same_v<std::variant_alternative_t<5, DecodedPayload>, NavSatFixMessage>);
  constexpr MessageKind kKinds[] = {MessageKind::kLaserScan,  MessageKind::kOdometry,
                                    MessageKind::kTransforms, MessageKind::kJointState,
                                    MessageKind::kImu,        MessageKind::kNavSatFix};
  kind_ = kKinds[payload_.index()];
}

Stamp Stamp::from_seconds(double seconds) {
  // Beyond what 64-bit seconds hold (or not a number): the farthest stamp on that side, never
  // an undefined conversion (writers refuse such a stamp, they do not wrap it).
  constexpr double kLimit = 9.2e18;
  if (std::isnan(seconds)) return {std::numeric_limits<std::int64_t>::min(), 0};
  if (seconds >= kLimit) return {std::numeric_limits<std::int64_t>::max(), 0};
  if (seconds <= -kLimit) return {std::numeric_limits<std::int64_t>::min(), 0};
  const double whole = std::floor(seconds);
  auto nsec = static_cast<std::int64_t>(std::llround((seconds - whole) * 1e9));
  auto sec = static_cast<std::int64_t>(whole);
  if (nsec >= 1000000000) {
    nsec -= 1000000000;
    ++sec;
  }
  return {sec, static_cast<std::uint32_t>(nsec)};
}

const char* message_kind_name(MessageKind kind) {
  switch (kind) {
    case MessageKind::kLaserScan:
      return "sensor_msgs/LaserScan";
    case MessageKind::kOdometry:
      return "nav_msgs/Odometry";
    case MessageKind::kTransforms:
      return "tf2_msgs/TFMessage";
    case MessageKind::kJointState:
      return "sensor_msgs/JointState";
    case MessageKind::kImu:
      return "sensor_msgs/Imu";
    case MessageKind::kNavSatFix:
      return "sensor_msgs/NavSatFix";
    case MessageKind::kOther:
      break;
  }
  return "other";
}

bool Topics::has(const std::string& topic, MessageKind kind) const {
  const auto it = topics_.find(topic);
  return it != topics_.end() && it->second.kind == kind;
}

std::vector<std::string> Topics::of_kind(MessageKind kind) const {
  std::vector<std::string> names;
  for (const auto& [topic, info] : topics_) {
    if (info.kind == kind) names.push_back(topic);
  }
  return names;
}

std::string Topics::list(MessageKind kind) const { return join_names(of_kind(kind)); }

std::int64_t Topics::messages(const std::string& topic) const {
  const auto it = topics_.find(topic);
  return it == topics_.end() ? 0 : it->second.messages;
}

std::string join_names(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s.empty() ? std::string("none") : s;
}

bool is_convertible(MessageKind kind) {
  return kind != MessageKind::kNavSatFix && kind != MessageKind::kOther;
}

void write_decoded(RecordingWriter& writer, const RecordedMessage& message) {
  const std::string& topic = message.topic();
  const Stamp time = message.time();
  // A message that does not decode as its kind says is passed over: a reader gives std::nullopt
  // only for a message of another kind (or ROS 1's instantiate() for a type it cannot match).
  switch (message.kind()) {
    case MessageKind::kLaserScan:
      if (const auto m = message.scan()) writer.write(topic, time, *m);
      return;
    case MessageKind::kOdometry:
      if (const auto m = message.odometry()) writer.write(topic, time, *m);
      return;
    case MessageKind::kTransforms:
      if (const auto m = message.transforms()) writer.write(topic, time, *m);
      return;
    case MessageKind::kJointState:
      if (const auto m = message.joint_state()) writer.write(topic, time, *m);
      return;
    case MessageKind::kImu:
      if (const auto m = message.imu()) writer.write(topic, time, *m);
      return;
    case MessageKind::kNavSatFix:
    case MessageKind::kOther:
      break;
  }
  throw OutputError(topic + ": cannot copy a message of type " + message_kind_name(message.kind()) +
                    " from another format (only the recording model's types can be converted)");
}

ScanMessage scan_message(const LaserScan& scan, const std::string& frame_id) {
  ScanMessage m;
  m.header.stamp = Stamp::from_seconds(scan.stamp_s);
  m.header.frame_id = frame_id;
  m.scan = scan;
  m.time_increment = static_cast<float>(scan.time_increment_s);
  const double last = static_cast<double>(scan.size() > 0 ? scan.size() - 1 : 0);
  m.angle_max = static_cast<float>(scan.angle_min_rad + scan.angle_increment_rad * last);
  return m;
}

OdometryMessage odometry_message(double stamp_s, const std::string& frame_id,
                                 const std::string& child_frame_id, const Pose2& pose, double v_mps,
                                 double w_radps) {
  OdometryMessage m;
  m.header.stamp = Stamp::from_seconds(stamp_s);
  m.header.frame_id = frame_id;
  m.child_frame_id = child_frame_id;
  m.pose = pose;
  m.v_mps = v_mps;
  m.w_radps = w_radps;
  return m;
}

OdometryMessage odometry_message(const OdometryEstimate& e, const std::string& frame_id,
                                 const std::string& child_frame_id) {
  const auto or_zero = [](double v) { return std::isfinite(v) ? v : 0.0; };
  OdometryMessage m =
      odometry_message(e.t_s, frame_id, child_frame_id, e.pose(), e.v_mps, e.omega_radps);
  m.vy_mps = e.lateral_velocity_mps;
  m.pose_covariance[0] = or_zero(e.x_variance_m2);
  m.pose_covariance[7] = or_zero(e.y_variance_m2);
  m.pose_covariance[35] = or_zero(e.yaw_variance_rad2);
  m.twist_covariance[0] = or_zero(e.v_variance_m2ps2);
  m.twist_covariance[35] = or_zero(e.omega_variance_rad2ps2);
  return m;
}

ScanMessage filtered_message(const ScanMessage& original, const FilterResult& result) {
  ScanMessage msg = original;
  if (result.filtered.ranges_m.size() == msg.scan.ranges_m.size()) {
    msg.scan.ranges_m = result.filtered.ranges_m;
  }
  return msg;
}

ScanMessage labels_message(const ScanMessage& original, const FilterResult& result) {
  ScanMessage msg = original;
  const std::size_t n = msg.scan.ranges_m.size();
  msg.scan.intensities.assign(n, static_cast<float>(BeamLabel::kInvalid));
  for (std::size_t i = 0; i < n && i < result.labels.size(); ++i) {
    msg.scan.intensities[i] = static_cast<float>(result.labels[i]);
  }
  return msg;
}

}  // namespace dispel::io
