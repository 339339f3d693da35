#include "dispel/io/odometry_inputs.hpp"

#include <algorithm>
#include <cctype>

namespace dispel::io {
namespace {

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Index of the joint named `wanted`, or (when empty) the first whose name contains `side`; else
// `fallback`.
int joint_index(const JointStateMessage& js, const std::string& wanted, const std::string& side,
                int fallback) {
  for (std::size_t i = 0; i < js.names.size(); ++i) {
    if (wanted.empty() ? lower(js.names[i]).find(side) != std::string::npos
                       : js.names[i] == wanted) {
      return static_cast<int>(i);
    }
  }
  return wanted.empty() ? fallback : -1;
}

}  // namespace

double stamp_or(const Stamp& header, const Stamp& received) {
  return header.is_zero() ? received.seconds() : header.seconds();
}

std::optional<WheelSpeeds> wheel_speeds(const JointStateMessage& msg,
                                        const OdometrySettings& settings, const Stamp& received) {
  const int l = joint_index(msg, settings.left_wheel_joint, "left", 0);
  const int r = joint_index(msg, settings.right_wheel_joint, "right", 1);
  if (l < 0 || r < 0 || l == r ||
      static_cast<std::size_t>(std::max(l, r)) >= msg.velocities.size()) {
    return std::nullopt;
  }
  const double scale = settings.wheel_radius_m > 0.0 ? settings.wheel_radius_m : 1.0;
  return WheelSpeeds{stamp_or(msg.header.stamp, received),
                     scale * msg.velocities[static_cast<std::size_t>(l)],
                     scale * msg.velocities[static_cast<std::size_t>(r)]};
}

WheelSpeeds wheel_speeds(const OdometryMessage& msg, double track_width_m, const Stamp& received) {
  const double v = msg.v_mps, w = msg.w_radps;
  return {stamp_or(msg.header.stamp, received), v - 0.5 * w * track_width_m,
          v + 0.5 * w * track_width_m};
}

double yaw_rate(const ImuMessage& msg, const OdometrySettings& settings) {
  return settings.imu_yaw_sign * msg.angular_velocity_radps[settings.imu_yaw_axis];
}

}  // namespace dispel::io
