#pragma once
/// @file
/// Constant-velocity Kalman filter for one tracked point in the plane (thesis Eq. 3.4-3.5).

#include <Eigen/Core>

namespace dispel {

/// Noise parameters of the point velocity filters. The defaults are dispel's; thesis_config()
/// (dynamic_filter_config.hpp) has the thesis's (Appendix A: sigma_p^2 0.75, sigma_m^2 15).
struct VelocityFilterConfig {
  /// sigma_p^2: process noise of each position coordinate per nominal scan period. dispel's 0.001
  /// with sigma_m^2 0.1 (a point measured to about 0.3 m, little position noise per scan) follows
  /// a walker within a few scans; the thesis's values take about 2 s to reach a walker's speed.
  double position_variance_m2 = 0.001;
  /// sigma_v^2: process noise of each velocity coordinate per nominal scan period; also the
  /// initial velocity variance of a new track.
  double velocity_variance_m2ps2 = 1.5;
  /// sigma_m^2: measurement noise of each position coordinate; also the initial position
  /// variance of a new track.
  double measurement_variance_m2 = 0.1;
  /// gamma: factor applied to the velocity of a point that cannot be measured reliably.
  double velocity_decay = 0.8;
  /// The scan period the variances above are given for (the thesis's scanner: 20 Hz). Process
  /// noise is scaled by dt / nominal_scan_period_s, so a 10 Hz scanner behaves the same per second.
  double nominal_scan_period_s = 0.05;

  /// Throws std::invalid_argument naming the first bad field and its value.
  void validate() const;
};

/// A 4-state constant-velocity linear Kalman filter, state (x, y, vx, vy) in a fixed frame:
///   x_k = F(dt) x_{k-1} + w,  F = [I dt*I; 0 I],  Q = diag(sp2, sp2, sv2, sv2) * dt / T0
///   z_k = [I 0] x_k + v,      R = sm2 * I
/// with a variable time step dt (seconds since the point was last seen).
class PointVelocityFilter {
 public:
  static constexpr int kX = 0, kY = 1, kVx = 2, kVy = 3;
  using State = Eigen::Vector4d;
  using Covariance = Eigen::Matrix4d;

  PointVelocityFilter() = default;
  /// Starts at @p position_m with zero velocity and covariance diag(sm2, sm2, sv2, sv2).
  PointVelocityFilter(const Eigen::Vector2d& position_m, const VelocityFilterConfig& config);

  /// Predicts dt_s ahead (dt_s >= 0) and corrects with the measured position.
  void predict_and_update(const Eigen::Vector2d& measured_m, double dt_s,
                          const VelocityFilterConfig& config);

  /// For a point that cannot be trusted this scan (thesis section 3.2.2): predicts dt_s ahead,
  /// multiplies the velocity by gamma, and moves the position to the measurement, so that the
  /// apparent motion of an ambiguous edge never becomes velocity.
  void predict_and_decay(const Eigen::Vector2d& measured_m, double dt_s,
                         const VelocityFilterConfig& config);

  /// Replaces the velocity estimate (a track that continues another one).
  void set_velocity(const Eigen::Vector2d& velocity_mps) { x_.tail<2>() = velocity_mps; }

  /// Predicts dt_s ahead without a measurement (x <- F x, P <- F P F^T + Q).
  void predict(double dt_s, const VelocityFilterConfig& config);

  /// Predicts dt_s ahead, keeps the velocity, and moves the position to the measurement: for a
  /// point that is measured again after a time it could not be (the gap is not motion).
  void predict_and_hold(const Eigen::Vector2d& measured_m, double dt_s,
                        const VelocityFilterConfig& config);

  Eigen::Vector2d position() const { return x_.head<2>(); }
  Eigen::Vector2d velocity() const { return x_.tail<2>(); }
  /// Position predicted dt_s ahead under constant velocity (the state is not changed).
  Eigen::Vector2d predicted_position(double dt_s) const { return position() + dt_s * velocity(); }
  const State& state() const { return x_; }
  const Covariance& covariance() const { return p_; }

 private:
  State x_ = State::Zero();
  Covariance p_ = Covariance::Identity();
};

}  // namespace dispel
