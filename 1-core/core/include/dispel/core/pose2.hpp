#pragma once
/// @file
/// Planar rigid transform (SE(2)) and angle helpers.

#include <Eigen/Core>
#include <cmath>

namespace dispel {

inline constexpr double kPi = 3.14159265358979323846;

/// Wraps an angle to [-pi, pi).
inline double wrap_angle(double angle_rad) {
  constexpr double kTwoPi = 2.0 * kPi;
  double a = std::fmod(angle_rad + kPi, kTwoPi);
  if (a < 0.0) a += kTwoPi;
  return a - kPi;
}

/// A pose in the plane: the frame it describes, seen from a parent frame. Applying it maps a point
/// from the child frame into the parent frame: p_parent = R(yaw) * p_child + (x, y).
struct Pose2 {
  double x_m = 0.0;
  double y_m = 0.0;
  double yaw_rad = 0.0;

  Eigen::Vector2d translation() const { return {x_m, y_m}; }

  /// Maps a point given in this pose's frame into the parent frame.
  Eigen::Vector2d apply(const Eigen::Vector2d& p) const {
    const double c = std::cos(yaw_rad);
    const double s = std::sin(yaw_rad);
    return {c * p.x() - s * p.y() + x_m, s * p.x() + c * p.y() + y_m};
  }

  /// The inverse transform (parent seen from this frame).
  Pose2 inverse() const {
    const double c = std::cos(yaw_rad);
    const double s = std::sin(yaw_rad);
    return {-(c * x_m + s * y_m), s * x_m - c * y_m, wrap_angle(-yaw_rad)};
  }

  /// Composition: (*this) * other maps other's child frame into this pose's parent frame.
  Pose2 operator*(const Pose2& other) const {
    const Eigen::Vector2d t = apply(other.translation());
    return {t.x(), t.y(), wrap_angle(yaw_rad + other.yaw_rad)};
  }
};

/// A pose's transform with its cosine and sine computed once, for applying it to many points:
/// the same result as Pose2::apply, bit for bit, without a sine and a cosine per point.
class PoseTransform {
 public:
  explicit PoseTransform(const Pose2& pose)
      : c_(std::cos(pose.yaw_rad)), s_(std::sin(pose.yaw_rad)), x_(pose.x_m), y_(pose.y_m) {}

  Eigen::Vector2d operator()(const Eigen::Vector2d& p) const {
    return {c_ * p.x() - s_ * p.y() + x_, s_ * p.x() + c_ * p.y() + y_};
  }
  /// The rotation alone (a direction or a normal).
  Eigen::Vector2d rotate(const Eigen::Vector2d& v) const {
    return {c_ * v.x() - s_ * v.y(), s_ * v.x() + c_ * v.y()};
  }

 private:
  double c_, s_, x_, y_;
};

/// The rotations by 0, step, 2 x step, ... in turn, by recurrence: one sine and cosine in all
/// (a scan's beams, each turned by the sensor's turn up to its own time). A zero step gives the
/// identity exactly at every step.
class SteppedRotation {
 public:
  explicit SteppedRotation(double step_rad) : cs_(std::cos(step_rad)), ss_(std::sin(step_rad)) {}

  /// On to the next multiple of the step.
  void advance() {
    const double c_next = c_ * cs_ - s_ * ss_;
    s_ = s_ * cs_ + c_ * ss_;
    c_ = c_next;
  }
  /// @p v turned by the current multiple of the step.
  Eigen::Vector2d rotate(const Eigen::Vector2d& v) const {
    return {c_ * v.x() - s_ * v.y(), s_ * v.x() + c_ * v.y()};
  }

 private:
  double cs_, ss_;
  double c_ = 1.0, s_ = 0.0;
};

}  // namespace dispel
