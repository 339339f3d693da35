#include "dispel/io/ros1_messages.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dispel::io {
namespace {

Header from_ros(const std_msgs::Header& h) { return {h.seq, to_stamp(h.stamp), h.frame_id}; }

std_msgs::Header to_ros(const Header& h) {
  std_msgs::Header out;
  out.seq = h.seq;
  out.stamp = to_ros_time(h.stamp);
  out.frame_id = h.frame_id;
  return out;
}

geometry_msgs::Pose pose_to_ros(const Pose2& p) {
  geometry_msgs::Pose out;
  out.position.x = p.x_m;
  out.position.y = p.y_m;
  out.orientation = quaternion_from_yaw(p.yaw_rad);
  return out;
}

}  // namespace

double to_seconds(const ros::Time& t) { return t.toSec(); }

ros::Time to_ros_time(double seconds) { return to_ros_time(Stamp::from_seconds(seconds)); }

Stamp to_stamp(const ros::Time& t) { return {static_cast<std::int64_t>(t.sec), t.nsec}; }

ros::Time to_ros_time(const Stamp& s) {
  constexpr std::int64_t kMax = std::numeric_limits<std::uint32_t>::max();
  if (s.sec < 0) return ros::Time(0, 0);
  if (s.sec > kMax) return ros::Time(static_cast<std::uint32_t>(kMax), 999999999);
  return ros::Time(static_cast<std::uint32_t>(s.sec), s.nsec);
}

double yaw_of(const geometry_msgs::Quaternion& q) {
  return std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
}

geometry_msgs::Quaternion quaternion_from_yaw(double yaw_rad) {
  geometry_msgs::Quaternion q;
  q.x = 0.0;
  q.y = 0.0;
  q.z = std::sin(0.5 * yaw_rad);
  q.w = std::cos(0.5 * yaw_rad);
  return q;
}

Pose2 from_ros(const geometry_msgs::Transform& t) {
  return {t.translation.x, t.translation.y, yaw_of(t.rotation)};
}

Pose2 from_ros(const geometry_msgs::Pose& p) {
  return {p.position.x, p.position.y, yaw_of(p.orientation)};
}

LaserScan from_ros(const sensor_msgs::LaserScan& msg) {
  LaserScan scan;
  scan.stamp_s = to_seconds(msg.header.stamp);
  scan.angle_min_rad = msg.angle_min;
  scan.angle_increment_rad = msg.angle_increment;
  scan.range_min_m = msg.range_min;
  scan.range_max_m = msg.range_max;
  scan.time_increment_s = msg.time_increment;
  scan.ranges_m = msg.ranges;
  scan.intensities = msg.intensities;
  return scan;
}

sensor_msgs::LaserScan to_ros(const LaserScan& scan, const std::string& frame_id) {
  return to_ros(scan_message(scan, frame_id));
}

nav_msgs::Odometry to_ros_odometry(double stamp_s, const std::string& frame_id,
                                   const std::string& child_frame_id, const Pose2& pose,
                                   double v_mps, double w_radps) {
  return to_ros(odometry_message(stamp_s, frame_id, child_frame_id, pose, v_mps, w_radps));
}

ScanMessage to_message(const sensor_msgs::LaserScan& msg) {
  ScanMessage m;
  m.header = from_ros(msg.header);
  m.scan = from_ros(msg);
  m.angle_max = msg.angle_max;
  m.time_increment = msg.time_increment;
  m.scan_time = msg.scan_time;
  return m;
}

sensor_msgs::LaserScan to_ros(const ScanMessage& m) {
  sensor_msgs::LaserScan msg;
  msg.header = to_ros(m.header);
  msg.angle_min = static_cast<float>(m.scan.angle_min_rad);
  msg.angle_max = m.angle_max;
  msg.angle_increment = static_cast<float>(m.scan.angle_increment_rad);
  msg.time_increment = m.time_increment;
  msg.scan_time = m.scan_time;
  msg.range_min = m.scan.range_min_m;
  msg.range_max = m.scan.range_max_m;
  msg.ranges = m.scan.ranges_m;
  msg.intensities = m.scan.intensities;
  return msg;
}

OdometryMessage to_message(const nav_msgs::Odometry& msg) {
  OdometryMessage m;
  m.header = from_ros(msg.header);
  m.child_frame_id = msg.child_frame_id;
  m.pose = from_ros(msg.pose.pose);
  m.v_mps = msg.twist.twist.linear.x;
  m.vy_mps = msg.twist.twist.linear.y;
  m.w_radps = msg.twist.twist.angular.z;
  std::copy(msg.pose.covariance.begin(), msg.pose.covariance.end(), m.pose_covariance.begin());
  std::copy(msg.twist.covariance.begin(), msg.twist.covariance.end(), m.twist_covariance.begin());
  return m;
}

nav_msgs::Odometry to_ros(const OdometryMessage& m) {
  nav_msgs::Odometry msg;
  msg.header = to_ros(m.header);
  msg.child_frame_id = m.child_frame_id;
  msg.pose.pose = pose_to_ros(m.pose);
  msg.twist.twist.linear.x = m.v_mps;
  msg.twist.twist.linear.y = m.vy_mps;
  msg.twist.twist.angular.z = m.w_radps;
  std::copy(m.pose_covariance.begin(), m.pose_covariance.end(), msg.pose.covariance.begin());
  std::copy(m.twist_covariance.begin(), m.twist_covariance.end(), msg.twist.covariance.begin());
  return msg;
}

TransformsMessage to_message(const tf2_msgs::TFMessage& msg) {
  TransformsMessage m;
  for (const auto& t : msg.transforms) {
    m.transforms.push_back(
        {to_stamp(t.header.stamp), t.header.frame_id, t.child_frame_id, from_ros(t.transform)});
  }
  return m;
}

tf2_msgs::TFMessage to_ros(const TransformsMessage& m) {
  tf2_msgs::TFMessage msg;
  for (const FrameTransform& t : m.transforms) {
    geometry_msgs::TransformStamped ts;
    ts.header.stamp = to_ros_time(t.stamp);
    ts.header.frame_id = t.parent;
    ts.child_frame_id = t.child;
    ts.transform.translation.x = t.child_in_parent.x_m;
    ts.transform.translation.y = t.child_in_parent.y_m;
    ts.transform.rotation = quaternion_from_yaw(t.child_in_parent.yaw_rad);
    msg.transforms.push_back(ts);
  }
  return msg;
}

JointStateMessage to_message(const sensor_msgs::JointState& msg) {
  return {from_ros(msg.header), msg.name, msg.position, msg.velocity};
}

sensor_msgs::JointState to_ros(const JointStateMessage& m) {
  sensor_msgs::JointState msg;
  msg.header = to_ros(m.header);
  msg.name = m.names;
  msg.position = m.positions;
  msg.velocity = m.velocities;
  return msg;
}

ImuMessage to_message(const sensor_msgs::Imu& msg) {
  ImuMessage m;
  m.header = from_ros(msg.header);
  m.angular_velocity_radps = {msg.angular_velocity.x, msg.angular_velocity.y,
                              msg.angular_velocity.z};
  m.has_orientation = msg.orientation_covariance[0] != -1.0;
  return m;
}

sensor_msgs::Imu to_ros(const ImuMessage& m) {
  sensor_msgs::Imu msg;
  msg.header = to_ros(m.header);
  msg.angular_velocity.x = m.angular_velocity_radps.x();
  msg.angular_velocity.y = m.angular_velocity_radps.y();
  msg.angular_velocity.z = m.angular_velocity_radps.z();
  if (!m.has_orientation) msg.orientation_covariance[0] = -1.0;  // REP 145.
  return msg;
}

NavSatFixMessage to_message(const sensor_msgs::NavSatFix& msg) {
  return {from_ros(msg.header), msg.status.status, msg.latitude, msg.longitude};
}

sensor_msgs::LaserScan filtered_message(const sensor_msgs::LaserScan& original,
                                        const FilterResult& result) {
  return to_ros(filtered_message(to_message(original), result));
}

sensor_msgs::LaserScan labels_message(const sensor_msgs::LaserScan& original,
                                      const FilterResult& result) {
  return to_ros(labels_message(to_message(original), result));
}

}  // namespace dispel::io
