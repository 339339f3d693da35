#include "dispel/io/ros_convert.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>

namespace dispel::io {

double to_seconds(const ros::Time& t) { return t.toSec(); }

ros::Time to_ros_time(double seconds) {
  const double whole = std::floor(seconds);
  auto nsec = static_cast<std::int64_t>(std::llround((seconds - whole) * 1e9));
  auto sec = static_cast<std::int64_t>(whole);
  if (nsec >= 1000000000) {
    nsec -= 1000000000;
    ++sec;
  }
  return ros::Time(static_cast<std::uint32_t>(sec), static_cast<std::uint32_t>(nsec));
}

double stamp_or(const ros::Time& header, const ros::Time& received) {
  return header.isZero() ? received.toSec() : header.toSec();
}

LaserScan from_ros(const sensor_msgs::LaserScan& msg) {
  LaserScan scan;
  scan.stamp_s = to_seconds(msg.header.stamp);
  scan.angle_min_rad = msg.angle_min;
  scan.angle_increment_rad = msg.angle_increment;
  scan.range_min_m = msg.range_min;
  scan.range_max_m = msg.range_max;
  scan.ranges_m = msg.ranges;
  scan.intensities = msg.intensities;
  return scan;
}

sensor_msgs::LaserScan to_ros(const LaserScan& scan, const std::string& frame_id) {
  sensor_msgs::LaserScan msg;
  msg.header.stamp = to_ros_time(scan.stamp_s);
  msg.header.frame_id = frame_id;
  msg.angle_min = static_cast<float>(scan.angle_min_rad);
  msg.angle_increment = static_cast<float>(scan.angle_increment_rad);
  msg.angle_max = static_cast<float>(
      scan.angle_min_rad +
      scan.angle_increment_rad * static_cast<double>(scan.size() > 0 ? scan.size() - 1 : 0));
  msg.range_min = scan.range_min_m;
  msg.range_max = scan.range_max_m;
  msg.ranges = scan.ranges_m;
  msg.intensities = scan.intensities;
  return msg;
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

nav_msgs::Odometry to_ros_odometry(double stamp_s, const std::string& frame_id,
                                   const std::string& child_frame_id, const Pose2& pose,
                                   double v_mps, double w_radps) {
  nav_msgs::Odometry m;
  m.header.stamp = to_ros_time(stamp_s);
  m.header.frame_id = frame_id;
  m.child_frame_id = child_frame_id;
  m.pose.pose.position.x = pose.x_m;
  m.pose.pose.position.y = pose.y_m;
  m.pose.pose.orientation = quaternion_from_yaw(pose.yaw_rad);
  m.twist.twist.linear.x = v_mps;
  m.twist.twist.angular.z = w_radps;
  return m;
}

Pose2 from_ros(const geometry_msgs::Transform& t) {
  return {t.translation.x, t.translation.y, yaw_of(t.rotation)};
}

Pose2 from_ros(const geometry_msgs::Pose& p) {
  return {p.position.x, p.position.y, yaw_of(p.orientation)};
}

sensor_msgs::LaserScan filtered_message(const sensor_msgs::LaserScan& original,
                                        const FilterResult& result) {
  sensor_msgs::LaserScan msg = original;
  if (result.filtered.ranges_m.size() == msg.ranges.size()) msg.ranges = result.filtered.ranges_m;
  return msg;
}

sensor_msgs::LaserScan labels_message(const sensor_msgs::LaserScan& original,
                                      const FilterResult& result) {
  sensor_msgs::LaserScan msg = original;
  msg.intensities.assign(msg.ranges.size(), static_cast<float>(BeamLabel::kInvalid));
  for (std::size_t i = 0; i < msg.ranges.size() && i < result.labels.size(); ++i) {
    msg.intensities[i] = static_cast<float>(result.labels[i]);
  }
  return msg;
}

namespace {

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Index of the joint named `wanted`, or (when empty) the first whose name contains `side`; else
// `fallback`.
int joint_index(const sensor_msgs::JointState& js, const std::string& wanted,
                const std::string& side, int fallback) {
  for (std::size_t i = 0; i < js.name.size(); ++i) {
    if (wanted.empty() ? lower(js.name[i]).find(side) != std::string::npos : js.name[i] == wanted) {
      return static_cast<int>(i);
    }
  }
  return wanted.empty() ? fallback : -1;
}

}  // namespace

std::optional<WheelSpeeds> wheel_speeds_from_ros(const sensor_msgs::JointState& msg,
                                                 const OdometrySettings& settings,
                                                 const ros::Time& received) {
  const int l = joint_index(msg, settings.left_wheel_joint, "left", 0);
  const int r = joint_index(msg, settings.right_wheel_joint, "right", 1);
  if (l < 0 || r < 0 || l == r || static_cast<std::size_t>(std::max(l, r)) >= msg.velocity.size()) {
    return std::nullopt;
  }
  const double scale = settings.wheel_radius_m > 0.0 ? settings.wheel_radius_m : 1.0;
  return WheelSpeeds{stamp_or(msg.header.stamp, received),
                     scale * msg.velocity[static_cast<std::size_t>(l)],
                     scale * msg.velocity[static_cast<std::size_t>(r)]};
}

WheelSpeeds wheel_speeds_from_ros(const nav_msgs::Odometry& msg, double track_width_m,
                                  const ros::Time& received) {
  const double v = msg.twist.twist.linear.x, w = msg.twist.twist.angular.z;
  return {stamp_or(msg.header.stamp, received), v - 0.5 * w * track_width_m,
          v + 0.5 * w * track_width_m};
}

double yaw_rate_from_ros(const sensor_msgs::Imu& msg, const OdometrySettings& settings) {
  const geometry_msgs::Vector3& w = msg.angular_velocity;
  const double axes[3] = {w.x, w.y, w.z};
  return settings.imu_yaw_sign * axes[settings.imu_yaw_axis];
}

}  // namespace dispel::io
