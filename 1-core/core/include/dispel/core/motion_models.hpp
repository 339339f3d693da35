#pragma once
/// @file
/// Planar motion models for odometry fusion (thesis section 3.3) as pure functions of
/// (state, T), templated on the scalar type so that automatic differentiation can use them.
/// Frames: x, y in the odometry (world) frame in metres, yaw psi in radians counter-clockwise
/// from the world x axis; velocities in the robot's body frame (x forward, y left).

#include <Eigen/Core>
#include <cmath>

namespace dispel {

/// sin(a) / a, with its limit 1 at a = 0: a Taylor series for |a| < 0.01 (truncation error below
/// a^6 / 5040 < 2e-16), the quotient elsewhere, so the function is smooth to machine precision.
template <typename T>
T sinc(const T& a) {
  using std::abs;
  using std::sin;
  if (abs(a) < T(0.01)) {
    const T a2 = a * a;
    return T(1.0) - a2 / T(6.0) * (T(1.0) - a2 / T(20.0));
  }
  return sin(a) / a;
}

/// State layout of the coordinated-turn (CT) model: (x, y, v, psi, omega).
struct CtIndex {
  static constexpr int kX = 0, kY = 1, kV = 2, kPsi = 3, kOmega = 4, kSize = 5;
};
template <typename T>
using CtState = Eigen::Matrix<T, CtIndex::kSize, 1>;

/// The CT model's exact discretisation over @p dt_s seconds (thesis Eq. 3.12): speed v (m/s) and
/// yaw rate omega (rad/s) constant, the robot moves on a circular arc,
///   x += (2 v / omega) sin(omega T / 2) cos(psi + omega T / 2)  = v T sinc(omega T / 2) cos(...)
///   y += (2 v / omega) sin(omega T / 2) sin(psi + omega T / 2)  = v T sinc(omega T / 2) sin(...)
///   psi += omega T.
/// Written with sinc, it is one continuous formula whose limit omega -> 0 is the straight line.
/// psi is not wrapped.
template <typename T>
CtState<T> ct_predict(const CtState<T>& s, const T& dt_s) {
  using std::cos;
  using std::sin;
  using I = CtIndex;
  const T half_turn = s(I::kOmega) * dt_s / T(2.0);
  const T chord = s(I::kV) * dt_s * sinc(half_turn);
  const T heading = s(I::kPsi) + half_turn;
  CtState<T> out = s;
  out(I::kX) += chord * cos(heading);
  out(I::kY) += chord * sin(heading);
  out(I::kPsi) += s(I::kOmega) * dt_s;
  return out;
}

/// The CT model discretised by Euler's method (error O(T^2) per step):
/// x += v T cos psi, y += v T sin psi, psi += omega T.
template <typename T>
CtState<T> ct_predict_euler(const CtState<T>& s, const T& dt_s) {
  using std::cos;
  using std::sin;
  using I = CtIndex;
  CtState<T> out = s;
  out(I::kX) += s(I::kV) * dt_s * cos(s(I::kPsi));
  out(I::kY) += s(I::kV) * dt_s * sin(s(I::kPsi));
  out(I::kPsi) += s(I::kOmega) * dt_s;
  return out;
}

/// The CT model's process noise over @p dt_s (thesis): Q = diag(0, 0, T sigma_v^2, 0,
/// T sigma_omega^2), with @p linear_velocity_variance sigma_v^2 in m^2/s^3 and
/// @p yaw_rate_variance sigma_omega^2 in rad^2/s^3 (variances of random walks per second).
inline Eigen::Matrix<double, 5, 5> ct_process_noise(double dt_s, double linear_velocity_variance,
                                                    double yaw_rate_variance) {
  Eigen::Matrix<double, 5, 5> q = Eigen::Matrix<double, 5, 5>::Zero();
  q(CtIndex::kV, CtIndex::kV) = dt_s * linear_velocity_variance;
  q(CtIndex::kOmega, CtIndex::kOmega) = dt_s * yaw_rate_variance;
  return q;
}

/// State layout of the omnidirectional constant-velocity model (robot_localization's default,
/// reduced to the plane): (x, y, psi, vx, vy, omega), vx and vy in the body frame.
struct OmniIndex {
  static constexpr int kX = 0, kY = 1, kPsi = 2, kVx = 3, kVy = 4, kOmega = 5, kSize = 6;
};
template <typename T>
using OmniState = Eigen::Matrix<T, OmniIndex::kSize, 1>;

/// The omnidirectional model over @p dt_s, discretised like robot_localization (Euler):
/// [x y] += R(psi) [vx vy] T, psi += omega T; velocities constant. psi is not wrapped.
template <typename T>
OmniState<T> omni_predict(const OmniState<T>& s, const T& dt_s) {
  using std::cos;
  using std::sin;
  using I = OmniIndex;
  const T c = cos(s(I::kPsi));
  const T si = sin(s(I::kPsi));
  OmniState<T> out = s;
  out(I::kX) += (c * s(I::kVx) - si * s(I::kVy)) * dt_s;
  out(I::kY) += (si * s(I::kVx) + c * s(I::kVy)) * dt_s;
  out(I::kPsi) += s(I::kOmega) * dt_s;
  return out;
}

/// The omnidirectional model's process noise: T sigma_v^2 on vx and on vy, T sigma_omega^2 on
/// omega (units as in ct_process_noise).
inline Eigen::Matrix<double, 6, 6> omni_process_noise(double dt_s, double linear_velocity_variance,
                                                      double yaw_rate_variance) {
  Eigen::Matrix<double, 6, 6> q = Eigen::Matrix<double, 6, 6>::Zero();
  q(OmniIndex::kVx, OmniIndex::kVx) = dt_s * linear_velocity_variance;
  q(OmniIndex::kVy, OmniIndex::kVy) = dt_s * linear_velocity_variance;
  q(OmniIndex::kOmega, OmniIndex::kOmega) = dt_s * yaw_rate_variance;
  return q;
}

/// Forward speed of a differential drive from its wheel speeds: v = (vL + vR) / 2 (m/s).
inline double wheel_linear_velocity(double v_left_mps, double v_right_mps) {
  return 0.5 * (v_left_mps + v_right_mps);
}

/// Yaw rate of a differential drive from its wheel speeds: omega = (vR - vL) / b (rad/s), b the
/// track width (distance between the wheels' contact points) in metres.
inline double wheel_yaw_rate(double v_left_mps, double v_right_mps, double track_width_m) {
  return (v_right_mps - v_left_mps) / track_width_m;
}

}  // namespace dispel
