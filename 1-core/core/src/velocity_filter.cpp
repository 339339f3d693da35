#include "dispel/core/velocity_filter.hpp"

#include <Eigen/LU>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "dispel/core/invalid_field.hpp"

namespace dispel {
namespace {

void require_positive(double value, const char* name) {
  if (!std::isfinite(value) || !(value > 0.0)) {
    reject_field(std::string("velocity.") + name, value, "a finite number > 0");
  }
}

}  // namespace

void VelocityFilterConfig::validate() const {
  require_positive(position_variance_m2, "position_variance_m2");
  require_positive(velocity_variance_m2ps2, "velocity_variance_m2ps2");
  require_positive(measurement_variance_m2, "measurement_variance_m2");
  require_positive(nominal_scan_period_s, "nominal_scan_period_s");
  if (!std::isfinite(velocity_decay) || velocity_decay < 0.0 || velocity_decay > 1.0) {
    reject_field("velocity.velocity_decay", velocity_decay, "in [0, 1]");
  }
}

PointVelocityFilter::PointVelocityFilter(const Eigen::Vector2d& position_m,
                                         const VelocityFilterConfig& config) {
  x_ << position_m.x(), position_m.y(), 0.0, 0.0;
  p_.setZero();
  p_(kX, kX) = p_(kY, kY) = config.measurement_variance_m2;
  p_(kVx, kVx) = p_(kVy, kVy) = config.velocity_variance_m2ps2;
}

void PointVelocityFilter::predict(double dt_s, const VelocityFilterConfig& config) {
  // x <- F x, P <- F P F^T + Q, written out for F = [I dt*I; 0 I].
  x_.head<2>() += dt_s * x_.tail<2>();
  const Eigen::Matrix2d ppv = p_.block<2, 2>(0, 2);
  const Eigen::Matrix2d pvv = p_.block<2, 2>(2, 2);
  p_.block<2, 2>(0, 0) += dt_s * (ppv + ppv.transpose()) + dt_s * dt_s * pvv;
  p_.block<2, 2>(0, 2) += dt_s * pvv;
  p_.block<2, 2>(2, 0) = p_.block<2, 2>(0, 2).transpose();
  const double scale = dt_s / config.nominal_scan_period_s;
  p_(kX, kX) += config.position_variance_m2 * scale;
  p_(kY, kY) += config.position_variance_m2 * scale;
  p_(kVx, kVx) += config.velocity_variance_m2ps2 * scale;
  p_(kVy, kVy) += config.velocity_variance_m2ps2 * scale;
}

void PointVelocityFilter::predict_and_update(const Eigen::Vector2d& measured_m, double dt_s,
                                             const VelocityFilterConfig& config) {
  predict(dt_s, config);
  // H = [I 0]: S = P_pp + R, K = P[:, pos] S^-1.
  Eigen::Matrix2d s = p_.block<2, 2>(0, 0);
  s(0, 0) += config.measurement_variance_m2;
  s(1, 1) += config.measurement_variance_m2;
  const Eigen::Matrix<double, 4, 2> k = p_.block<4, 2>(0, 0) * s.inverse();
  x_ += k * (measured_m - x_.head<2>());
  // Joseph form keeps P symmetric and positive definite: P = (I - KH) P (I - KH)^T + K R K^T.
  Eigen::Matrix4d i_kh = Eigen::Matrix4d::Identity();
  i_kh.block<4, 2>(0, 0) -= k;
  p_ = i_kh * p_ * i_kh.transpose() + config.measurement_variance_m2 * k * k.transpose();
}

void PointVelocityFilter::predict_and_decay(const Eigen::Vector2d& measured_m, double dt_s,
                                            const VelocityFilterConfig& config) {
  predict(dt_s, config);
  x_.head<2>() = measured_m;
  x_.tail<2>() *= config.velocity_decay;
}

void PointVelocityFilter::predict_and_hold(const Eigen::Vector2d& measured_m, double dt_s,
                                           const VelocityFilterConfig& config) {
  predict(dt_s, config);
  x_.head<2>() = measured_m;
}

}  // namespace dispel
