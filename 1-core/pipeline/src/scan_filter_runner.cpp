#include "dispel/pipeline/scan_filter_runner.hpp"

#include <chrono>
#include <cmath>
#include <ctime>
#include <stdexcept>
#include <string>

namespace dispel::pipeline {

namespace {

// CPU time of the calling thread (POSIX), seconds; 0 where the clock is not available.
double thread_cpu_time_s() {
  timespec t{};
  if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t) != 0) return 0.0;
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

}  // namespace

void ScanFilterRunnerOptions::validate() const {
  config.validate();
  if (!std::isfinite(scan_period_s) || scan_period_s < 0.0) {
    throw std::invalid_argument("scan_period_s must be a finite number >= 0, got " +
                                std::to_string(scan_period_s));
  }
}

ScanFilterRunner::ScanFilterRunner(ScanFilterRunnerOptions options)
    : options_((options.validate(), std::move(options))), period_(options_.scan_period_s) {
  if (options_.static_sensor) options_.config.registration.align = false;
  if (options_.scale_to_scanner) {
    free_space_.emplace(options_.config.free_space);
  } else {
    filter_.emplace(options_.config);
  }
}

const DynamicFilterConfig& ScanFilterRunner::config() const {
  return filter_ ? filter_->config() : options_.config;
}

FilterCounters ScanFilterRunner::filter_counters() const {
  return filter_ ? filter_->counters() : FilterCounters{};
}

const FilterResult& ScanFilterRunner::process(const LaserScan& scan, double stated_period_s,
                                              const std::optional<Pose2>& sensor_pose) {
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = thread_cpu_time_s();
  last_outcome_ = run(scan, stated_period_s, sensor_pose);
  ++counts_.scans;
  switch (last_outcome_) {
    case ScanOutcome::kFiltered:
      ++counts_.filtered;
      break;
    case ScanOutcome::kNoPose:
      ++counts_.no_pose;
      break;
    case ScanOutcome::kBadPose:
      ++counts_.bad_pose;
      break;
    case ScanOutcome::kBadScan:
      ++counts_.rejected_scan;
      break;
    case ScanOutcome::kWaitingForPeriod:
      ++counts_.waiting_period;
      break;
  }
  if (filter_) counts_.tracks = static_cast<std::int64_t>(filter_->track_count());
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  last_cpu_s_ = thread_cpu_time_s() - cpu_start;
  ++times_.count;
  times_.last_s = elapsed;
  times_sum_s_ += elapsed;
  times_.mean_s = times_sum_s_ / static_cast<double>(times_.count);
  if (elapsed > times_.max_s) times_.max_s = elapsed;
  return result_;
}

ScanOutcome ScanFilterRunner::run(const LaserScan& scan, double stated_period_s,
                                  const std::optional<Pose2>& sensor_pose) {
  if (!filter_) {
    // scale_to_scanner: the first scan with a valid angle increment once the period is known.
    const std::optional<double> period = period_.add(scan.stamp_s, stated_period_s);
    if (period && std::isfinite(scan.angle_increment_rad) && scan.angle_increment_rad > 0.0) {
      filter_.emplace(scale_to_scanner(options_.config, scan.angle_increment_rad, *period),
                      std::move(*free_space_));
      free_space_.reset();
    } else {
      const bool bad = check_scan(scan) != ScanIssue::kNone;
      DynamicFilter::pass_through_unfiltered(
          scan, bad ? FilterEvent::kRejectedScan : FilterEvent::kNoPose, result_);
      return ScanOutcome::kWaitingForPeriod;
    }
  }
  filter_->process(scan, sensor_pose, result_);
  switch (result_.event) {
    case FilterEvent::kRejectedScan:
      return ScanOutcome::kBadScan;
    case FilterEvent::kRejectedPose:
      return ScanOutcome::kBadPose;
    case FilterEvent::kNoPose:
      return ScanOutcome::kNoPose;
    default:
      return ScanOutcome::kFiltered;
  }
}

ScanTimes ScanFilterRunner::take_times() {
  const ScanTimes out = times_;
  times_ = ScanTimes{};
  times_.last_s = out.last_s;
  times_sum_s_ = 0.0;
  return out;
}

}  // namespace dispel::pipeline
