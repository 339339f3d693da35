#include "dispel/pipeline/odometry_runner.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace dispel::pipeline {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

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
      newest_s_(-kInf),
      last_given_s_(-kInf),
      latest_s_{-kInf, -kInf},
      waiting_{true, engine == OdometryEngine::kFusion},
      last_arrival_s_{-kInf, -kInf},
      pending_since_s_(-kInf) {
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
  const auto k = static_cast<std::size_t>(source);
  OdometryArrivals& arr = arrivals_[k];
  ++arr.count;
  if (std::isfinite(t_s)) {
    if (t_s < latest_s_[k]) {
      ++arr.out_of_order;
      arr.largest_lag_in_source_s = std::max(arr.largest_lag_in_source_s, latest_s_[k] - t_s);
    }
    if (t_s < newest_s_) arr.largest_lag_s = std::max(arr.largest_lag_s, newest_s_ - t_s);
    latest_s_[k] = std::max(latest_s_[k], t_s);
    newest_s_ = std::max(newest_s_, t_s);
  }
  if (source == 1 && engine_ == OdometryEngine::kDeadReckoning) return;  // The wheels alone.
  if (!arrived_since_release_[0] && !arrived_since_release_[1]) {
    empty_before_arrivals_ = buffer_.empty();
  }
  arrived_since_release_[k] = true;
  const Measurement m{t_s, source, next_seq_++, a, b};
  if (!std::isfinite(t_s)) {
    fuse(m);  // Counted as rejected; never buffered (a NaN key has no place in the order).
    return;
  }
  waiting_[k] = true;
  buffer_.push(m);
}

OdometryEvent OdometryRunner::fuse(const Measurement& m) {
  if (wheels_only_) return wheels_only_->add_wheels(m.t_s, m.a, m.b);
  return m.source == 1 ? fusion_->add_imu(m.t_s, m.a) : fusion_->add_wheels(m.t_s, m.a, m.b);
}

double OdometryRunner::horizon() const {
  if (window_s_ == kInf) return -kInf;  // Nothing before a flush.
  double slowest = kInf;                // No source waited for: everything.
  for (std::size_t k = 0; k < kSources; ++k) {
    if (waiting_[k]) slowest = std::min(slowest, latest_s_[k]);
  }
  return slowest - window_s_;
}

std::vector<OdometryEstimate> OdometryRunner::release(bool flush) {
  std::vector<OdometryEstimate> out;
  const double until = horizon();
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

std::vector<OdometryEstimate> OdometryRunner::release_at(double now_s, double source_timeout_s) {
  if (std::isnan(source_timeout_s) || source_timeout_s < 0.0) {
    throw std::invalid_argument("source_timeout_s must be a number >= 0, got " +
                                std::to_string(source_timeout_s));
  }
  for (std::size_t k = 0; k < kSources; ++k) {
    if (!arrived_since_release_[k]) continue;
    if (!empty_before_arrivals_ && std::isfinite(last_arrival_s_[k])) {
      const double gap = now_s - std::max(last_arrival_s_[k], pending_since_s_);
      arrivals_[k].longest_gap_s = std::max(arrivals_[k].longest_gap_s, gap);
    }
    last_arrival_s_[k] = now_s;
  }
  if ((arrived_since_release_[0] || arrived_since_release_[1]) && empty_before_arrivals_) {
    pending_since_s_ = now_s;
  }
  arrived_since_release_ = {false, false};
  if (!buffer_.empty()) {
    for (std::size_t k = 0; k < kSources; ++k) {
      // Quiet since its last measurement, or since measurements began to wait for it.
      const double quiet_since = std::max(last_arrival_s_[k], pending_since_s_);
      if (waiting_[k] && now_s - quiet_since >= source_timeout_s) {
        waiting_[k] = false;
        ++quiet_count_[k];
      }
    }
  }
  return release(false);
}

void OdometryRunner::stop_waiting_for(OdometrySource source) { waiting_[index(source)] = false; }

OdometryCounters OdometryRunner::counters() const {
  if (fusion_) return fusion_->counters();
  OdometryCounters c;
  c.wheels = wheels_only_->counters();
  return c;
}

std::int64_t OdometryRunner::late(OdometrySource source) const {
  const OdometryCounters c = counters();
  const auto& counts = source == OdometrySource::kWheels ? c.wheels : c.imu;
  return counts[static_cast<std::size_t>(OdometryEvent::kRejectedOutOfOrder)];
}

OdometryEstimate OdometryRunner::estimate() const {
  return fusion_ ? fusion_->estimate() : wheels_only_->estimate();
}

}  // namespace dispel::pipeline
