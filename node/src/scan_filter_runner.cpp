#include "dispel/node/scan_filter_runner.hpp"

#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace dispel::node {

void ScanFilterRunnerOptions::validate() const {
  config.validate();
  if (!std::isfinite(scan_period_s) || scan_period_s < 0.0) {
    throw std::invalid_argument("scan_period_s must be a finite number >= 0, got " +
                                std::to_string(scan_period_s));
  }
}

ScanFilterRunner::ScanFilterRunner(ScanFilterRunnerOptions options)
    : options_((options.validate(), std::move(options))) {
  if (!options_.scale_to_scanner) filter_.emplace(options_.config);
}

const DynamicFilterConfig& ScanFilterRunner::config() const {
  return filter_ ? filter_->config() : options_.config;
}

FilterCounters ScanFilterRunner::filter_counters() const {
  return filter_ ? filter_->counters() : FilterCounters{};
}

void ScanFilterRunner::configure(double period_s) {
  filter_.emplace(scale_to_scanner(options_.config, angle_increment_rad_, period_s));
}

const FilterResult& ScanFilterRunner::process(const LaserScan& scan, double stated_period_s,
                                              const std::optional<Pose2>& sensor_pose) {
  const auto start = std::chrono::steady_clock::now();
  ++counts_.scans;
  if (!filter_) {
    // scale_to_scanner: the scanner's period from the options, the message, or two stamps.
    double period = options_.scan_period_s;
    if (!(period > 0.0) && std::isfinite(stated_period_s) && stated_period_s > 0.0) {
      period = stated_period_s;
    }
    if (!(period > 0.0) && first_stamp_s_ && scan.stamp_s > *first_stamp_s_) {
      period = scan.stamp_s - *first_stamp_s_;
    }
    if (period > 0.0 && std::isfinite(scan.angle_increment_rad) && scan.angle_increment_rad > 0.0) {
      angle_increment_rad_ = scan.angle_increment_rad;
      configure(period);
    } else {
      if (!first_stamp_s_ && std::isfinite(scan.stamp_s)) first_stamp_s_ = scan.stamp_s;
      // Passed through by a filter that is thrown away: the same labels as any pass-through.
      DynamicFilter(options_.config)
          .process(scan, Pose2{std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0}, result_);
      ++counts_.waiting_period;
    }
  }
  if (filter_) {
    const Pose2 pose =
        sensor_pose ? *sensor_pose : Pose2{std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0};
    filter_->process(scan, pose, result_);
    if (result_.event == FilterEvent::kRejectedScan) {
      ++counts_.rejected_scan;
    } else if (result_.event == FilterEvent::kRejectedPose) {
      ++counts_.no_pose;
    } else {
      ++counts_.filtered;
    }
    counts_.tracks = static_cast<std::int64_t>(filter_->track_count());
  }
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ++times_.count;
  times_.last_s = elapsed;
  times_sum_s_ += elapsed;
  times_.mean_s = times_sum_s_ / static_cast<double>(times_.count);
  if (elapsed > times_.max_s) times_.max_s = elapsed;
  return result_;
}

ScanTimes ScanFilterRunner::take_times() {
  const ScanTimes out = times_;
  times_ = ScanTimes{};
  times_.last_s = out.last_s;
  times_sum_s_ = 0.0;
  return out;
}

}  // namespace dispel::node
