#include "dispel/core/odometry_fusion.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "dispel/core/invalid_field.hpp"
#include "dispel/core/motion_models.hpp"
#include "dispel/core/ukf.hpp"

namespace dispel {
namespace {

constexpr int kMaxPredictionSteps = 1000;

void require(bool ok, const char* field, double value, const char* rule) {
  if (!ok) reject_field(std::string("odometry.") + field, value, rule);
}

void require_positive(double value, const char* field) {
  require(std::isfinite(value) && value > 0.0, field, value, "a finite number > 0");
}

double gate_threshold(double probability, int dof) {
  return probability > 0.0 ? chi_square_quantile(probability, dof)
                           : std::numeric_limits<double>::infinity();
}

}  // namespace

const char* odometry_model_name(OdometryModel model) {
  switch (model) {
    case OdometryModel::kCt:
      return "ct";
    case OdometryModel::kCtEuler:
      return "ct_euler";
    case OdometryModel::kOmni:
      return "omni";
  }
  return "unknown";
}

const char* odometry_event_name(OdometryEvent event) {
  switch (event) {
    case OdometryEvent::kAccepted:
      return "accepted";
    case OdometryEvent::kGateOverridden:
      return "gate_overridden";
    case OdometryEvent::kGated:
      return "gated";
    case OdometryEvent::kRejectedNonFinite:
      return "rejected_non_finite";
    case OdometryEvent::kRejectedOutOfOrder:
      return "rejected_out_of_order";
    case OdometryEvent::kNumericalFailure:
      return "numerical_failure";
  }
  return "unknown";
}

void OdometryConfig::validate() const {
  require(model == OdometryModel::kCt || model == OdometryModel::kCtEuler ||
              model == OdometryModel::kOmni,
          "model", static_cast<int>(model), "ct, ct_euler or omni");
  require_positive(track_width_m, "track_width_m");
  require_positive(linear_velocity_variance_m2ps3, "linear_velocity_variance_m2ps3");
  require_positive(yaw_rate_variance_rad2ps3, "yaw_rate_variance_rad2ps3");
  UkfParameters{ukf_alpha, ukf_beta, ukf_kappa}.validate("odometry.ukf_");
  // The smallest state (CT with bias) has n = 6.
  require(ukf_kappa > -6.0, "ukf_kappa", ukf_kappa, "> -6 (n + kappa > 0)");
  require_positive(wheel_velocity_variance_m2ps2, "wheel_velocity_variance_m2ps2");
  require_positive(wheel_yaw_rate_variance_rad2ps2, "wheel_yaw_rate_variance_rad2ps2");
  require_positive(wheel_lateral_velocity_variance_m2ps2, "wheel_lateral_velocity_variance_m2ps2");
  require_positive(imu_yaw_rate_variance_rad2ps2, "imu_yaw_rate_variance_rad2ps2");
  require(std::isfinite(imu_smoothing) && imu_smoothing > 0.0 && imu_smoothing <= 1.0,
          "imu_smoothing", imu_smoothing, "in (0, 1]");
  require_positive(gyro_bias_initial_variance_rad2ps2, "gyro_bias_initial_variance_rad2ps2");
  require(std::isfinite(gyro_bias_random_walk_variance_rad2ps3) &&
              gyro_bias_random_walk_variance_rad2ps3 >= 0.0,
          "gyro_bias_random_walk_variance_rad2ps3", gyro_bias_random_walk_variance_rad2ps3,
          "a finite number >= 0");
  require(gate_probability >= 0.0 && gate_probability < 1.0, "gate_probability", gate_probability,
          "in [0, 1) (0 = no gate)");
  require(std::isfinite(gate_override_after_s) && gate_override_after_s >= 0.0,
          "gate_override_after_s", gate_override_after_s, "a finite number >= 0 (0 = never)");
  require(std::isfinite(gate_agreement_radps) && gate_agreement_radps >= 0.0,
          "gate_agreement_radps", gate_agreement_radps, "a finite number >= 0 (0 = off)");
  require(std::isfinite(gate_agreement_window_s) && gate_agreement_window_s >= 0.0,
          "gate_agreement_window_s", gate_agreement_window_s, "a finite number >= 0");
  require_positive(max_time_step_s, "max_time_step_s");
  require_positive(initial_position_variance_m2, "initial_position_variance_m2");
  require_positive(initial_yaw_variance_rad2, "initial_yaw_variance_rad2");
  require_positive(initial_velocity_variance_m2ps2, "initial_velocity_variance_m2ps2");
  require_positive(initial_yaw_rate_variance_rad2ps2, "initial_yaw_rate_variance_rad2ps2");
}

namespace odometry_detail {

/// One filter over one model's state; the last state component is always the gyro bias.
class Engine {
 public:
  virtual ~Engine() = default;
  virtual std::unique_ptr<Engine> clone() const = 0;
  virtual UkfStatus predict(double dt_s) = 0;
  virtual UkfUpdateResult update_wheels(double v_mps, double omega_radps, double gate_nis) = 0;
  virtual UkfUpdateResult update_imu(double yaw_rate_radps, double gate_nis) = 0;
  virtual OdometryEstimate estimate() const = 0;
  virtual Eigen::VectorXd state() const = 0;
  virtual Eigen::MatrixXd covariance() const = 0;
  virtual long long cholesky_repairs() const = 0;
  virtual int wheel_dimension() const = 0;
};

namespace {

// Index layout of a model with the bias appended. Without the bias estimate, the bias component
// stays in the state but enters neither the process nor any measurement, so it remains exactly
// uncorrelated with everything else and never changes (one wasted dimension, one code path).
template <OdometryModel kModel>
struct Model;

template <>
struct Model<OdometryModel::kCt> {
  static constexpr int kN = 6, kX = 0, kY = 1, kPsi = 3, kV = 2, kOmega = 4, kBias = 5;
  static constexpr int kWheelDim = 2;
  static CtState<double> move(const CtState<double>& s, double dt) { return ct_predict(s, dt); }
};

template <>
struct Model<OdometryModel::kCtEuler> : Model<OdometryModel::kCt> {
  static CtState<double> move(const CtState<double>& s, double dt) {
    return ct_predict_euler(s, dt);
  }
};

template <>
struct Model<OdometryModel::kOmni> {
  static constexpr int kN = 7, kX = 0, kY = 1, kPsi = 2, kV = 3, kVy = 4, kOmega = 5, kBias = 6;
  static constexpr int kWheelDim = 3;
  static OmniState<double> move(const OmniState<double>& s, double dt) {
    return omni_predict(s, dt);
  }
};

template <OdometryModel kModel>
class ModelEngine final : public Engine {
 public:
  using M = Model<kModel>;
  static constexpr int kN = M::kN;
  using Filter = UnscentedKalmanFilter<kN>;
  using State = typename Filter::State;
  using Covariance = typename Filter::Covariance;

  ModelEngine(const OdometryConfig& c, const Pose2& start)
      : config_(c), ukf_(UkfParameters{c.ukf_alpha, c.ukf_beta, c.ukf_kappa}, layout()) {
    State x = State::Zero();
    x(M::kX) = start.x_m;
    x(M::kY) = start.y_m;
    x(M::kPsi) = start.yaw_rad;
    Covariance p = Covariance::Zero();
    p(M::kX, M::kX) = p(M::kY, M::kY) = c.initial_position_variance_m2;
    p(M::kPsi, M::kPsi) = c.initial_yaw_variance_rad2;
    p(M::kV, M::kV) = c.initial_velocity_variance_m2ps2;
    if constexpr (kModel == OdometryModel::kOmni) {
      p(M::kVy, M::kVy) = c.initial_velocity_variance_m2ps2;
    }
    p(M::kOmega, M::kOmega) = c.initial_yaw_rate_variance_rad2ps2;
    p(M::kBias, M::kBias) = c.gyro_bias_enabled ? c.gyro_bias_initial_variance_rad2ps2 : 1.0;
    ukf_.reset(x, p);
  }

  std::unique_ptr<Engine> clone() const override { return std::make_unique<ModelEngine>(*this); }

  UkfStatus predict(double dt_s) override {
    Covariance q = Covariance::Zero();
    q(M::kV, M::kV) = dt_s * config_.linear_velocity_variance_m2ps3;
    if constexpr (kModel == OdometryModel::kOmni) {
      q(M::kVy, M::kVy) = dt_s * config_.linear_velocity_variance_m2ps3;
    }
    q(M::kOmega, M::kOmega) = dt_s * config_.yaw_rate_variance_rad2ps3;
    if (config_.gyro_bias_enabled) {
      q(M::kBias, M::kBias) = dt_s * config_.gyro_bias_random_walk_variance_rad2ps3;
    }
    return ukf_.predict(
        [dt_s](const State& s) {
          State out = s;
          out.template head<kN - 1>() = M::move(s.template head<kN - 1>(), dt_s);
          return out;
        },
        q);
  }

  UkfUpdateResult update_wheels(double v_mps, double omega_radps, double gate_nis) override {
    using Z = Eigen::Matrix<double, M::kWheelDim, 1>;
    Z z;
    Z r;
    if constexpr (kModel == OdometryModel::kOmni) {
      z << v_mps, 0.0, omega_radps;
      r << config_.wheel_velocity_variance_m2ps2, config_.wheel_lateral_velocity_variance_m2ps2,
          config_.wheel_yaw_rate_variance_rad2ps2;
    } else {
      z << v_mps, omega_radps;
      r << config_.wheel_velocity_variance_m2ps2, config_.wheel_yaw_rate_variance_rad2ps2;
    }
    return ukf_.update(
        [](const State& s) {
          Z h;
          if constexpr (kModel == OdometryModel::kOmni) {
            h << s(M::kV), s(M::kVy), s(M::kOmega);
          } else {
            h << s(M::kV), s(M::kOmega);
          }
          return h;
        },
        z, Eigen::Matrix<double, M::kWheelDim, M::kWheelDim>(r.asDiagonal()), {}, gate_nis);
  }

  UkfUpdateResult update_imu(double yaw_rate_radps, double gate_nis) override {
    const bool bias = config_.gyro_bias_enabled;
    return ukf_.update(
        [bias](const State& s) {
          return Eigen::Matrix<double, 1, 1>(s(M::kOmega) + (bias ? s(M::kBias) : 0.0));
        },
        Eigen::Matrix<double, 1, 1>(yaw_rate_radps),
        Eigen::Matrix<double, 1, 1>(config_.imu_yaw_rate_variance_rad2ps2), {}, gate_nis);
  }

  OdometryEstimate estimate() const override {
    const State& x = ukf_.state();
    const Covariance& p = ukf_.covariance();
    OdometryEstimate e;
    e.x_m = x(M::kX);
    e.y_m = x(M::kY);
    e.yaw_rad = x(M::kPsi);
    e.v_mps = x(M::kV);
    if constexpr (kModel == OdometryModel::kOmni) e.lateral_velocity_mps = x(M::kVy);
    e.omega_radps = x(M::kOmega);
    e.x_variance_m2 = p(M::kX, M::kX);
    e.y_variance_m2 = p(M::kY, M::kY);
    e.yaw_variance_rad2 = p(M::kPsi, M::kPsi);
    e.v_variance_m2ps2 = p(M::kV, M::kV);
    e.omega_variance_rad2ps2 = p(M::kOmega, M::kOmega);
    if (config_.gyro_bias_enabled) {
      e.gyro_bias_radps = x(M::kBias);
      e.gyro_bias_variance_rad2ps2 = p(M::kBias, M::kBias);
    }
    return e;
  }

  Eigen::VectorXd state() const override { return ukf_.state(); }
  Eigen::MatrixXd covariance() const override { return ukf_.covariance(); }
  long long cholesky_repairs() const override { return ukf_.cholesky_repairs(); }
  int wheel_dimension() const override { return M::kWheelDim; }

 private:
  static UkfStateLayout<kN> layout() {
    UkfStateLayout<kN> l;
    l.angle[M::kPsi] = true;
    l.translation[M::kX] = l.translation[M::kY] = true;
    return l;
  }

  OdometryConfig config_;
  Filter ukf_;
};

std::unique_ptr<Engine> make_engine(const OdometryConfig& c, const Pose2& start) {
  switch (c.model) {
    case OdometryModel::kCt:
      return std::make_unique<ModelEngine<OdometryModel::kCt>>(c, start);
    case OdometryModel::kCtEuler:
      return std::make_unique<ModelEngine<OdometryModel::kCtEuler>>(c, start);
    case OdometryModel::kOmni:
      return std::make_unique<ModelEngine<OdometryModel::kOmni>>(c, start);
  }
  return nullptr;  // Unreachable: validate() accepted the model.
}

// Predicts @p engine from @p from_s to @p to_s in equal steps of at most max_time_step_s.
// Returns the time reached (to_s unless a step failed) and counts a split prediction.
double predict_engine(Engine& engine, const OdometryConfig& c, double from_s, double to_s,
                      std::int64_t* split_predictions) {
  const double dt = to_s - from_s;
  if (!(dt > 0.0)) return from_s;
  const double wanted = std::ceil(dt / c.max_time_step_s);
  const int steps =
      wanted > kMaxPredictionSteps ? kMaxPredictionSteps : std::max(1, static_cast<int>(wanted));
  if (steps > 1 && split_predictions != nullptr) ++*split_predictions;
  const double h = dt / steps;
  for (int k = 0; k < steps; ++k) {
    if (engine.predict(h) != UkfStatus::kOk) return from_s + k * h;
  }
  return to_s;
}

}  // namespace
}  // namespace odometry_detail

OdometryFusion::OdometryFusion(const OdometryConfig& config, const Pose2& start)
    : config_((config.validate(), config)),
      engine_(odometry_detail::make_engine(config, start)),
      wheel_gate_nis_(gate_threshold(config.gate_probability, engine_->wheel_dimension())),
      imu_gate_nis_(gate_threshold(config.gate_probability, 1)) {}

OdometryFusion::~OdometryFusion() = default;
OdometryFusion::OdometryFusion(OdometryFusion&&) noexcept = default;
OdometryFusion& OdometryFusion::operator=(OdometryFusion&&) noexcept = default;

bool OdometryFusion::admit(double t_s, bool finite, Counts& counts, OdometryEvent& event) {
  auto reject = [&](OdometryEvent e) {
    ++counts[static_cast<std::size_t>(e)];
    event = e;
    return false;
  };
  if (!finite || !std::isfinite(t_s)) return reject(OdometryEvent::kRejectedNonFinite);
  if (std::isnan(t_s_)) {
    t_s_ = t_s;
    return true;
  }
  if (t_s < t_s_) return reject(OdometryEvent::kRejectedOutOfOrder);
  t_s_ =
      odometry_detail::predict_engine(*engine_, config_, t_s_, t_s, &counters_.split_predictions);
  counters_.cholesky_repairs = engine_->cholesky_repairs();
  if (t_s_ != t_s) return reject(OdometryEvent::kNumericalFailure);
  return true;
}

template <class Agrees, class Update>
OdometryEvent OdometryFusion::fuse(double t_s, double gate_nis, Counts& counts,
                                   double& gated_since_s, Agrees&& other_sensor_agrees,
                                   Update&& update) {
  OdometryEvent event = OdometryEvent::kAccepted;
  UkfUpdateResult result = update(engine_.get(), gate_nis);
  if (result.status == UkfStatus::kGated) {
    if (std::isnan(gated_since_s)) gated_since_s = t_s;
    if (other_sensor_agrees() || (config_.gate_override_after_s > 0.0 &&
                                  t_s - gated_since_s >= config_.gate_override_after_s)) {
      result = update(engine_.get(), std::numeric_limits<double>::infinity());
      event = OdometryEvent::kGateOverridden;
    } else {
      event = OdometryEvent::kGated;
    }
  }
  if (result.status == UkfStatus::kOk) {
    gated_since_s = std::numeric_limits<double>::quiet_NaN();
  } else if (result.status != UkfStatus::kGated) {
    event = OdometryEvent::kNumericalFailure;
  }
  counters_.cholesky_repairs = engine_->cholesky_repairs();
  ++counts[static_cast<std::size_t>(event)];
  return event;
}

OdometryEvent OdometryFusion::add_wheels(double t_s, double v_left_mps, double v_right_mps) {
  OdometryEvent event{};
  if (!admit(t_s, std::isfinite(v_left_mps) && std::isfinite(v_right_mps), counters_.wheels,
             event)) {
    return event;
  }
  const double v = wheel_linear_velocity(v_left_mps, v_right_mps);
  const double omega = wheel_yaw_rate(v_left_mps, v_right_mps, config_.track_width_m);
  // Read before this measurement changes them; the state is the predicted one while gated.
  const double imu_rate = last_imu_yaw_rate_, imu_t_s = last_imu_t_s_;
  const auto imu_agrees = [&] {
    const OdometryEstimate now = engine_->estimate();
    return agrees(t_s, omega, imu_rate - now.gyro_bias_radps, imu_t_s, now.omega_radps);
  };
  last_wheel_yaw_rate_ = omega;
  last_wheel_t_s_ = t_s;
  constexpr double kImuRecent_s = 1.0;
  const bool imu_recent = std::isfinite(last_imu_t_s_) && t_s - last_imu_t_s_ <= kImuRecent_s;
  const double wheel_gate = imu_recent || config_.gate_wheels_without_imu
                                ? wheel_gate_nis_
                                : std::numeric_limits<double>::infinity();
  return fuse(t_s, wheel_gate, counters_.wheels, wheels_gated_since_s_, imu_agrees,
              [v, omega](odometry_detail::Engine* e, double gate) {
                return e->update_wheels(v, omega, gate);
              });
}

OdometryEvent OdometryFusion::add_imu(double t_s, double yaw_rate_radps) {
  OdometryEvent event{};
  if (!admit(t_s, std::isfinite(yaw_rate_radps), counters_.imu, event)) return event;
  const double f = config_.imu_smoothing;
  imu_smoothed_radps_ =
      imu_seen_ ? f * yaw_rate_radps + (1.0 - f) * imu_smoothed_radps_ : yaw_rate_radps;
  imu_seen_ = true;
  const double rate = imu_smoothed_radps_;
  const double wheel_rate = last_wheel_yaw_rate_, wheel_t_s = last_wheel_t_s_;
  const auto wheels_agree = [&] {
    const OdometryEstimate now = engine_->estimate();
    return agrees(t_s, rate - now.gyro_bias_radps, wheel_rate, wheel_t_s, now.omega_radps);
  };
  last_imu_yaw_rate_ = rate;
  last_imu_t_s_ = t_s;
  return fuse(
      t_s, imu_gate_nis_, counters_.imu, imu_gated_since_s_, wheels_agree,
      [rate](odometry_detail::Engine* e, double gate) { return e->update_imu(rate, gate); });
}

bool OdometryFusion::agrees(double t_s, double yaw_rate_radps, double other_rate, double other_t_s,
                            double predicted_yaw_rate_radps) const {
  // Both sensors must see the same turn, and one the filter did not expect: a wheel measurement
  // whose speed alone jumped (both wheels spinning, a push) gets no help from a quiet gyro.
  const double tolerance = config_.gate_agreement_radps;
  return tolerance > 0.0 && std::isfinite(other_t_s) &&
         t_s - other_t_s <= config_.gate_agreement_window_s &&
         std::abs(yaw_rate_radps - other_rate) <= tolerance &&
         std::abs(other_rate - predicted_yaw_rate_radps) > tolerance;
}

OdometryEstimate OdometryFusion::estimate() const {
  OdometryEstimate e = engine_->estimate();
  e.t_s = t_s_;
  return e;
}

Eigen::VectorXd OdometryFusion::state() const { return engine_->state(); }
Eigen::MatrixXd OdometryFusion::covariance() const { return engine_->covariance(); }

OdometryEstimate OdometryFusion::predict(double t_s) const {
  if (!(t_s > t_s_)) return estimate();
  const std::unique_ptr<odometry_detail::Engine> ahead = engine_->clone();
  const double reached = odometry_detail::predict_engine(*ahead, config_, t_s_, t_s, nullptr);
  OdometryEstimate e = ahead->estimate();
  e.t_s = reached;
  return e;
}

WheelOdometry::WheelOdometry(double track_width_m, const Pose2& start)
    : track_width_m_(track_width_m) {
  if (!std::isfinite(track_width_m) || !(track_width_m > 0.0)) {
    reject_field("odometry.track_width_m", track_width_m, "a finite number > 0");
  }
  estimate_.x_m = start.x_m;
  estimate_.y_m = start.y_m;
  estimate_.yaw_rad = wrap_to_pi(start.yaw_rad);
}

OdometryEvent WheelOdometry::add_wheels(double t_s, double v_left_mps, double v_right_mps) {
  auto count = [&](OdometryEvent e) {
    ++counters_[static_cast<std::size_t>(e)];
    return e;
  };
  if (!std::isfinite(t_s) || !std::isfinite(v_left_mps) || !std::isfinite(v_right_mps)) {
    return count(OdometryEvent::kRejectedNonFinite);
  }
  if (t_s < estimate_.t_s) return count(OdometryEvent::kRejectedOutOfOrder);
  if (!std::isnan(estimate_.t_s)) {
    CtState<double> s;
    s << estimate_.x_m, estimate_.y_m, estimate_.v_mps, estimate_.yaw_rad, estimate_.omega_radps;
    s = ct_predict(s, t_s - estimate_.t_s);
    estimate_.x_m = s(CtIndex::kX);
    estimate_.y_m = s(CtIndex::kY);
    estimate_.yaw_rad = wrap_to_pi(s(CtIndex::kPsi));
  }
  estimate_.t_s = t_s;
  estimate_.v_mps = wheel_linear_velocity(v_left_mps, v_right_mps);
  estimate_.omega_radps = wheel_yaw_rate(v_left_mps, v_right_mps, track_width_m_);
  return count(OdometryEvent::kAccepted);
}

}  // namespace dispel
