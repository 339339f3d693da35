#pragma once
/// @file
/// Odometry fusion of differential-drive wheel speeds and an IMU yaw rate with an unscented
/// Kalman filter (thesis sections 2.3 and 3.3), and plain wheel dead reckoning to compare with.
/// Frames: the pose is the robot's base frame in the odometry frame (x, y in metres, yaw in
/// radians in (-pi, pi], counter-clockwise); velocities are in the body frame.

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>

#include "dispel/core/pose2.hpp"

namespace dispel {

/// The motion model of the fusion filter.
enum class OdometryModel : std::uint8_t {
  /// Coordinated turn, exact discretisation (thesis Eq. 3.12): state x, y, v, psi, omega.
  kCt,
  /// Coordinated turn discretised by Euler's method.
  kCtEuler,
  /// Omnidirectional constant velocity (robot_localization's default, planar): x, y, psi, vx, vy,
  /// omega; the baseline the thesis compares with.
  kOmni,
};

/// Stable short name of a model: "ct", "ct_euler" or "omni".
const char* odometry_model_name(OdometryModel model);

/// Configuration of OdometryFusion. Defaults are the thesis's (Appendix A) where it gives one.
/// Variances of random walks ("per second") are in unit^2/s: the process noise of a step of T
/// seconds is T times the value. A YAML section `odometry:` mirrors these field names.
struct OdometryConfig {
  OdometryModel model = OdometryModel::kCt;
  /// Distance between the wheels' contact points (m), for the wheel yaw rate (vR - vL) / b.
  double track_width_m = 0.5;
  /// sigma_v^2: random walk of the linear velocity (m^2/s^3); for omni, of vx and of vy.
  double linear_velocity_variance_m2ps3 = 0.01;
  /// sigma_omega^2: random walk of the yaw rate (rad^2/s^3).
  double yaw_rate_variance_rad2ps3 = 0.049;
  /// Sigma point spread alpha in (0, 1], prior beta >= 0, secondary scaling kappa > -6.
  double ukf_alpha = 0.001;
  double ukf_beta = 2.0;
  double ukf_kappa = 0.0;
  /// Variance of the wheel speed v = (vL + vR) / 2 (m^2/s^2). With independent wheel noise of
  /// variance s^2 on each wheel: s^2 / 2.
  double wheel_velocity_variance_m2ps2 = 1e-4;
  /// Variance of the wheel yaw rate (vR - vL) / b (rad^2/s^2). Independent wheel noise: 2 s^2/b^2.
  double wheel_yaw_rate_variance_rad2ps2 = 4e-4;
  /// Omni only: variance of the pseudo-measurement vy = 0 that the wheels contribute (m^2/s^2),
  /// as robot_localization users fuse it from wheel odometry.
  double wheel_lateral_velocity_variance_m2ps2 = 1e-4;
  /// Variance of the IMU yaw rate as fed to the filter (rad^2/s^2; after smoothing).
  double imu_yaw_rate_variance_rad2ps2 = 1e-4;
  /// Factor f of the exponential moving average of the IMU yaw rate (thesis):
  /// s_k = f * raw_k + (1 - f) * s_{k-1}; in (0, 1], 1 feeds the raw rate.
  double imu_smoothing = 1.0;
  /// Estimate a gyro bias b (the IMU measures omega + b), a random walk. Off reproduces the thesis.
  bool gyro_bias_enabled = true;
  /// Initial variance of the bias (rad^2/s^2), > 0.
  double gyro_bias_initial_variance_rad2ps2 = 4e-4;
  /// Random walk of the bias (rad^2/s^3), >= 0.
  double gyro_bias_random_walk_variance_rad2ps3 = 1e-7;
  /// Chi-square gate on each measurement's normalised innovation squared: a measurement whose
  /// NIS exceeds the gate_probability quantile for its dimension is refused (wheel slip).
  /// In [0, 1); 0 switches the gate off.
  double gate_probability = 0.999;
  /// After a sensor has been gated without a break for this long (s), its next measurement is
  /// accepted whatever its innovation, so that a real change cannot lock the filter out.
  /// >= 0; 0 never overrides the gate.
  double gate_override_after_s = 2.0;
  /// A gated measurement is fused after all when the other sensor, measured within
  /// gate_agreement_window_s, shows the same yaw rate within this (rad/s; the IMU's without its
  /// estimated bias), and that rate differs from the predicted one by more than this: both see a
  /// real manoeuvre (a U-turn begun faster than the yaw-rate random walk expects), not a slipping
  /// wheel, which the gyro does not feel. >= 0; 0 switches it off.
  double gate_agreement_radps = 0.05;
  double gate_agreement_window_s = 0.1;
  /// Gate wheel measurements also while no IMU measurement has come for a second. Off by
  /// default: without the gyro nothing tells a slip from a manoeuvre but the motion model, and on
  /// a real robot turning on the spot (the optiodom recordings) the model's random walk refuses
  /// every turn for gate_override_after_s.
  bool gate_wheels_without_imu = false;
  /// Longest single prediction (s), > 0; longer gaps are split into equal steps of at most this
  /// (at most 1000 steps; beyond that the steps grow).
  double max_time_step_s = 0.1;
  /// Initial uncertainty around the start pose and of the (zero) initial velocities.
  double initial_position_variance_m2 = 1e-6;
  double initial_yaw_variance_rad2 = 1e-6;
  double initial_velocity_variance_m2ps2 = 0.25;
  double initial_yaw_rate_variance_rad2ps2 = 0.25;

  /// Throws std::invalid_argument naming the first bad field ("odometry.<field> must be ...").
  void validate() const;
};

/// What happened to one measurement.
enum class OdometryEvent : std::uint8_t {
  kAccepted,            ///< Predicted to its time and fused.
  kGateOverridden,      ///< Fused although the gate refused it (see gate_override_after_s).
  kGated,               ///< Failed the chi-square gate (e.g. wheel slip): predicted, not fused.
  kRejectedNonFinite,   ///< NaN or infinite time or value: ignored, state untouched.
  kRejectedOutOfOrder,  ///< Earlier than the last processed time stamp: ignored, state untouched.
  kNumericalFailure,    ///< The filter refused the step (covariance not positive definite).
};
inline constexpr std::size_t kOdometryEventCount = 6;

/// Stable short name of an event, e.g. "rejected_out_of_order" (for counters and JSON keys).
const char* odometry_event_name(OdometryEvent event);

/// Running totals since construction.
struct OdometryCounters {
  std::array<std::int64_t, kOdometryEventCount> wheels{};  ///< Wheel measurements per event.
  std::array<std::int64_t, kOdometryEventCount> imu{};     ///< IMU measurements per event.
  /// Predictions longer than max_time_step_s (split into several steps).
  std::int64_t split_predictions = 0;
  /// Covariances that had to be repaired (symmetrised, jitter added) before factorisation.
  std::int64_t cholesky_repairs = 0;

  std::int64_t count(OdometryEvent event) const {
    const auto i = static_cast<std::size_t>(event);
    return wheels[i] + imu[i];
  }
};

/// The current estimate. Variances are the covariance diagonal; NaN where not estimated.
struct OdometryEstimate {
  static constexpr double kUnknown = std::numeric_limits<double>::quiet_NaN();
  double t_s = kUnknown;  ///< Time of the last processed measurement (NaN before the first).
  double x_m = 0.0;
  double y_m = 0.0;
  double yaw_rad = 0.0;               ///< In (-pi, pi].
  double v_mps = 0.0;                 ///< Forward speed (omni: vx).
  double lateral_velocity_mps = 0.0;  ///< Omni: vy; 0 for the CT models.
  double omega_radps = 0.0;           ///< Yaw rate (true, without the gyro bias).
  double gyro_bias_radps = 0.0;       ///< 0 when the bias is not estimated.
  double x_variance_m2 = kUnknown;
  double y_variance_m2 = kUnknown;
  double yaw_variance_rad2 = kUnknown;
  double v_variance_m2ps2 = kUnknown;
  double omega_variance_rad2ps2 = kUnknown;
  double gyro_bias_variance_rad2ps2 = kUnknown;

  Pose2 pose() const { return {x_m, y_m, yaw_rad}; }
};

namespace odometry_detail {
class Engine;
}

/// Fuses timestamped wheel speeds and IMU yaw rates into a planar pose with an unscented Kalman
/// filter. Measurements must come in time order (either sensor); each one predicts the state to
/// its time stamp (in steps of at most max_time_step_s) and then corrects it. The first
/// measurement sets the start time. Bad data is counted and skipped, never thrown.
///
/// The wheel measurement is z = (v, omega) = ((vL + vR) / 2, (vR - vL) / b), for omni
/// (vx, vy = 0, omega); the IMU measures omega (+ b with the gyro bias state).
class OdometryFusion {
 public:
  /// Throws std::invalid_argument (from OdometryConfig::validate()) for a bad configuration.
  explicit OdometryFusion(const OdometryConfig& config, const Pose2& start = {});
  ~OdometryFusion();
  OdometryFusion(OdometryFusion&&) noexcept;
  OdometryFusion& operator=(OdometryFusion&&) noexcept;
  OdometryFusion(const OdometryFusion&) = delete;
  OdometryFusion& operator=(const OdometryFusion&) = delete;

  /// Wheel speeds of the left and right wheel (m/s, forward positive) measured at @p t_s (s).
  OdometryEvent add_wheels(double t_s, double v_left_mps, double v_right_mps);
  /// IMU yaw rate (rad/s, counter-clockwise positive) measured at @p t_s (s).
  OdometryEvent add_imu(double t_s, double yaw_rate_radps);

  /// The estimate at the last processed time stamp.
  OdometryEstimate estimate() const;
  /// The estimate predicted to @p t_s (>= the last time stamp; earlier gives estimate()),
  /// without changing the filter.
  OdometryEstimate predict(double t_s) const;
  /// The full filter state and covariance, in the model's order: ct and ct_euler
  /// (x, y, v, psi, omega, b), omni (x, y, psi, vx, vy, omega, b); b is the gyro bias (constant
  /// and uncorrelated when gyro_bias_enabled is false).
  Eigen::VectorXd state() const;
  Eigen::MatrixXd covariance() const;
  const OdometryCounters& counters() const { return counters_; }
  const OdometryConfig& config() const { return config_; }

 private:
  using Counts = std::array<std::int64_t, kOdometryEventCount>;
  // Rejects a non-finite or out-of-order input, else predicts to t_s (false: the predictor failed).
  bool admit(double t_s, bool finite, Counts& counts, OdometryEvent& event);
  // other_sensor_agrees() is asked only when the gate refuses the measurement.
  template <class Agrees, class Update>
  OdometryEvent fuse(double t_s, double gate_nis, Counts& counts, double& gated_since_s,
                     Agrees&& other_sensor_agrees, Update&& update);
  // Whether the other sensor's latest yaw rate, recent enough, matches @p yaw_rate_radps.
  bool agrees(double t_s, double yaw_rate_radps, double other_rate, double other_t_s,
              double predicted_yaw_rate_radps) const;

  OdometryConfig config_;
  std::unique_ptr<odometry_detail::Engine> engine_;
  OdometryCounters counters_;
  double t_s_ = std::numeric_limits<double>::quiet_NaN();
  double imu_smoothed_radps_ = 0.0;
  bool imu_seen_ = false;
  double wheels_gated_since_s_ = std::numeric_limits<double>::quiet_NaN();
  double imu_gated_since_s_ = std::numeric_limits<double>::quiet_NaN();
  double wheel_gate_nis_ = std::numeric_limits<double>::infinity();
  double imu_gate_nis_ = std::numeric_limits<double>::infinity();
  // The latest yaw rate each sensor reported (IMU: raw, bias not removed) and when.
  double last_wheel_yaw_rate_ = 0.0;
  double last_wheel_t_s_ = std::numeric_limits<double>::quiet_NaN();
  double last_imu_yaw_rate_ = 0.0;
  double last_imu_t_s_ = std::numeric_limits<double>::quiet_NaN();
};

/// Dead reckoning from the wheels alone, for comparison: each interval is integrated along an
/// exact arc (thesis Eq. 3.12) with the speeds of the measurement at its start (a zero-order
/// hold, as the filter's prediction uses the previous estimate). Same rejections as
/// OdometryFusion (non-finite, out of order); nothing is gated. Variances are NaN.
class WheelOdometry {
 public:
  /// Throws std::invalid_argument if track_width_m is not a finite number > 0.
  explicit WheelOdometry(double track_width_m, const Pose2& start = {});

  OdometryEvent add_wheels(double t_s, double v_left_mps, double v_right_mps);
  OdometryEstimate estimate() const { return estimate_; }
  /// Wheel measurements per event (only kAccepted and the two rejections occur).
  const std::array<std::int64_t, kOdometryEventCount>& counters() const { return counters_; }

 private:
  double track_width_m_;
  OdometryEstimate estimate_;
  std::array<std::int64_t, kOdometryEventCount> counters_{};
};

}  // namespace dispel
