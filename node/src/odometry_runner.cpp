#include "dispel/node/odometry_runner.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace dispel::node {
namespace {

double checked_window(double window_s) {
  if (!std::isfinite(window_s) || window_s < 0.0) {
    throw std::invalid_argument("reorder_window_s must be a finite number >= 0, got " +
                                std::to_string(window_s));
  }
  return window_s;
}

bool published(OdometryEvent event) {
  return event == OdometryEvent::kAccepted || event == OdometryEvent::kGated ||
         event == OdometryEvent::kGateOverridden;
}

}  // namespace

OdometryRunner::OdometryRunner(const OdometryConfig& config, double reorder_window_s)
    : fusion_(config),
      window_s_(checked_window(reorder_window_s)),
      newest_s_(-std::numeric_limits<double>::infinity()),
      last_published_s_(-std::numeric_limits<double>::infinity()) {}

void OdometryRunner::add_wheels(double t_s, double v_left_mps, double v_right_mps) {
  add(t_s, {false, v_left_mps, v_right_mps});
}

void OdometryRunner::add_imu(double t_s, double yaw_rate_radps) {
  add(t_s, {true, yaw_rate_radps, 0.0});
}

void OdometryRunner::add(double t_s, const Measurement& m) {
  if (!std::isfinite(t_s)) {
    fuse(t_s, m);  // Counted as rejected; never buffered (a NaN key has no place in the order).
    return;
  }
  buffer_.emplace(Key{t_s, m.imu ? 1 : 0}, m);
  if (t_s > newest_s_) newest_s_ = t_s;
}

OdometryEvent OdometryRunner::fuse(double t_s, const Measurement& m) {
  return m.imu ? fusion_.add_imu(t_s, m.a) : fusion_.add_wheels(t_s, m.a, m.b);
}

std::vector<OdometryEstimate> OdometryRunner::release(bool flush) {
  std::vector<OdometryEstimate> out;
  const double until = newest_s_ - window_s_;
  while (!buffer_.empty() && (flush || buffer_.begin()->first.first <= until)) {
    const double t_s = buffer_.begin()->first.first;
    const OdometryEvent event = fuse(t_s, buffer_.begin()->second);
    buffer_.erase(buffer_.begin());
    // One estimate per stamp, after every measurement at that stamp.
    if (!buffer_.empty() && buffer_.begin()->first.first == t_s) continue;
    if (!published(event)) continue;
    const OdometryEstimate e = fusion_.estimate();
    if (!(e.t_s > last_published_s_)) continue;
    out.push_back(e);
    last_published_s_ = e.t_s;
  }
  return out;
}

}  // namespace dispel::node
