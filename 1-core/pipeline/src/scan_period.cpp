#include "dispel/pipeline/scan_period.hpp"

#include <algorithm>
#include <cmath>

namespace dispel::pipeline {

ScanPeriod::ScanPeriod(double given_s) {
  if (given_s > 0.0) period_ = given_s;
}

std::optional<double> ScanPeriod::add(double stamp_s, double stated_period_s) {
  if (period_) return period_;
  if (std::isfinite(stated_period_s) && stated_period_s > 0.0) {
    period_ = stated_period_s;
    return period_;
  }
  if (!std::isfinite(stamp_s)) return std::nullopt;
  if (last_stamp_s_ && stamp_s > *last_stamp_s_) intervals_.push_back(stamp_s - *last_stamp_s_);
  if (!last_stamp_s_ || stamp_s > *last_stamp_s_) last_stamp_s_ = stamp_s;
  if (static_cast<int>(intervals_.size()) >= kIntervals) {
    std::sort(intervals_.begin(), intervals_.end());
    const std::size_t n = intervals_.size();
    period_ = n % 2 == 1 ? intervals_[n / 2] : 0.5 * (intervals_[n / 2 - 1] + intervals_[n / 2]);
  }
  return period_;
}

}  // namespace dispel::pipeline
