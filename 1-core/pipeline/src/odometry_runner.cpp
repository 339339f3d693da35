#include "dispel/pipeline/odometry_runner.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace dispel::pipeline {
namespace {

constexpr double kNegInf = -std::numeric_limits<double>::infinity();

double checked_window(double window_s) {
  if (std::isnan(window_s) || window_s < 0.0) {
    throw std::invalid_argument("reorder_window_s must be a number >= 0, got " +
                                std::to_string(window_s));
  }
  return window_s;
}

bool given_out(OdometryEvent event) {
  return event == OdometryEvent::kAccepted || event == OdometryEvent::kGated ||
         event == OdometryEvent::kGateOverridden;
}

}  // namespace

bool OdometryRunner::Later::operator()(const Measurement& x, const Measurement& y) const {
  if (x.t_s != y.t_s) return x.t_s > y.t_s;
  if (x.source != y.source) return x.source > y.source;
  return x.seq > y.seq;
}

OdometryRunner::OdometryRunner(const OdometryConfig& config, double reorder_window_s,
                               OdometryEngine engine)
    : engine_(engine),
      window_s_(checked_window(reorder_window_s)),
      newest_s_(kNegInf),
      last_given_s_(kNegInf),
      last_arrival_s_{kNegInf, kNegInf} {
  if (engine_ == OdometryEngine::kFusion) {
    fusion_.emplace(config);
  } else {
    config.validate();
    wheels_only_.emplace(config.track_width_m);
  }
}

void OdometryRunner::add_wheels(double t_s, double v_left_mps, double v_right_mps) {
  add(t_s, 0, v_left_mps, v_right_mps);
}

void OdometryRunner::add_imu(double t_s, double yaw_rate_radps) {
  add(t_s, 1, yaw_rate_radps, 0.0);
}

void OdometryRunner::add(double t_s, int source, double a, double b) {
  if (std::isfinite(t_s)) {
    if (t_s < last_arrival_s_[source]) ++arrived_out_of_order_;
    last_arrival_s_[source] = t_s;
  }
  if (source == 1 && engine_ == OdometryEngine::kDeadReckoning) return;  // The wheels alone.
  const Measurement m{t_s, source, next_seq_++, a, b};
  if (!std::isfinite(t_s)) {
    fuse(m);  // Counted as rejected; never buffered (a NaN key has no place in the order).
    return;
  }
  buffer_.push(m);
  if (t_s > newest_s_) newest_s_ = t_s;
}

OdometryEvent OdometryRunner::fuse(const Measurement& m) {
  if (wheels_only_) return wheels_only_->add_wheels(m.t_s, m.a, m.b);
  return m.source == 1 ? fusion_->add_imu(m.t_s, m.a) : fusion_->add_wheels(m.t_s, m.a, m.b);
}

std::vector<OdometryEstimate> OdometryRunner::release(bool flush) {
  std::vector<OdometryEstimate> out;
  const double until = newest_s_ - window_s_;
  while (!buffer_.empty() && (flush || buffer_.top().t_s <= until)) {
    const Measurement m = buffer_.top();
    buffer_.pop();
    const OdometryEvent event = fuse(m);
    // One estimate per stamp, after every measurement at that stamp.
    if (!buffer_.empty() && buffer_.top().t_s == m.t_s) continue;
    if (!given_out(event)) continue;
    const OdometryEstimate e = estimate();
    if (!(e.t_s > last_given_s_)) continue;
    out.push_back(e);
    last_given_s_ = e.t_s;
  }
  return out;
}

OdometryCounters OdometryRunner::counters() const {
  if (fusion_) return fusion_->counters();
  OdometryCounters c;
  c.wheels = wheels_only_->counters();
  return c;
}

OdometryEstimate OdometryRunner::estimate() const {
  return fusion_ ? fusion_->estimate() : wheels_only_->estimate();
}

}  // namespace dispel::pipeline
