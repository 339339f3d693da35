#pragma once
/// @file
/// The measurements odometry fusion takes, read from a recording's messages as the `odometry:`
/// settings say (wheel joints, wheel radius, the IMU's yaw axis): shared by `dispel odom` and the
/// odometry node.

#include <optional>

#include "dispel/io/config_yaml.hpp"
#include "dispel/io/recording.hpp"

namespace dispel::io {

/// Left and right wheel speeds (m/s, forward positive) measured at t_s.
struct WheelSpeeds {
  double t_s = 0.0;
  double left_mps = 0.0;
  double right_mps = 0.0;
};

/// A message's stamp in seconds: its header's, or @p received when the header's is zero.
double stamp_or(const Stamp& header, const Stamp& received);

/// The wheel speeds in a JointState, as @p settings say: the joints named left_wheel_joint and
/// right_wheel_joint (when empty, the first whose names contain "left" and "right", else the
/// first two velocities), multiplied by wheel_radius_m when it is > 0. std::nullopt when the
/// message does not hold both. @p received is used when the header's stamp is zero.
std::optional<WheelSpeeds> wheel_speeds(const JointStateMessage& msg,
                                        const OdometrySettings& settings, const Stamp& received);
/// The wheel speeds that an Odometry message's forward speed and yaw rate stand for, on a
/// differential drive of @p track_width_m: v -+ w b / 2.
WheelSpeeds wheel_speeds(const OdometryMessage& msg, double track_width_m, const Stamp& received);
/// The robot's yaw rate (rad/s) in an Imu message: the axis imu_yaw_axis of @p settings, signed.
double yaw_rate(const ImuMessage& msg, const OdometrySettings& settings);

}  // namespace dispel::io
