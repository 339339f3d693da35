#pragma once
/// @file
/// The part of a live filter node that is not middleware: the dynamic filter fed one scan at a
/// time as it arrives, with the configuration carried over to the scanner on the first scans
/// (`scale_to_scanner`), scans without a sensor pose passed through, and counts and processing
/// times for diagnostics. A ROS 1 or ROS 2 node converts messages and calls process().

#include <cstdint>
#include <optional>

#include "dispel/core/dynamic_filter.hpp"

namespace dispel::node {

struct ScanFilterRunnerOptions {
  /// The filter's configuration (as parsed from YAML).
  DynamicFilterConfig config = default_config();
  /// Carry N_min, L_d and L_s over to the scanner (scale_to_scanner() in the core), as
  /// `dispel filter --scale-to-scanner` does.
  bool scale_to_scanner = false;
  /// The scanner's period for scale_to_scanner (s). 0: the period the first scan states
  /// (sensor_msgs/LaserScan scan_time), or, if it states none, the time between the first two
  /// scans (the first one is then passed through unfiltered).
  double scan_period_s = 0.0;

  /// Throws std::invalid_argument naming the first bad field (the configuration's own, or
  /// scan_period_s).
  void validate() const;
};

/// Running totals since the runner was made.
struct ScanFilterCounts {
  std::int64_t scans = 0;           ///< Scans given to process().
  std::int64_t filtered = 0;        ///< Tracked and filtered (FilterEvent other than rejections).
  std::int64_t no_pose = 0;         ///< Passed through unchanged: no sensor pose.
  std::int64_t rejected_scan = 0;   ///< Passed through unchanged: the scan failed check_scan().
  std::int64_t waiting_period = 0;  ///< Passed through: the scanner's period was not known yet.
  std::int64_t tracks = 0;          ///< Live tracks after the last scan.
};

/// Processing times of the scans since the last take_times(), in seconds.
struct ScanTimes {
  std::int64_t count = 0;
  double last_s = 0.0;
  double mean_s = 0.0;
  double max_s = 0.0;
};

/// Feeds the dynamic filter one scan at a time. Not thread-safe.
class ScanFilterRunner {
 public:
  /// @throws std::invalid_argument if options.validate() does.
  explicit ScanFilterRunner(ScanFilterRunnerOptions options);

  /// Filters @p scan with the sensor pose in the fixed frame at its stamp. @p stated_period_s is
  /// the period the scan message states (0 when it states none). Without a pose the scan is
  /// passed through unchanged (FilterEvent::kRejectedPose, labels "no object" or "invalid") and
  /// counted, exactly as `dispel filter` does with a scan it has no odometry for.
  const FilterResult& process(const LaserScan& scan, double stated_period_s,
                              const std::optional<Pose2>& sensor_pose);

  /// The configuration in use; before the first scan under scale_to_scanner, the unscaled one.
  const DynamicFilterConfig& config() const;
  /// Whether the configuration is final (scaled to the scanner when asked).
  bool configured() const { return filter_.has_value(); }
  const ScanFilterCounts& counts() const { return counts_; }
  /// The filter's own counters (zero before the first filtered scan).
  FilterCounters filter_counters() const;
  /// Processing times since the previous call; resets them.
  ScanTimes take_times();

 private:
  void configure(double period_s);  // Makes the filter, scaled to the scanner.

  ScanFilterRunnerOptions options_;
  std::optional<DynamicFilter> filter_;
  std::optional<double> first_stamp_s_;  // Of a scan passed through while waiting for the period.
  double angle_increment_rad_ = 0.0;
  FilterResult result_;
  ScanFilterCounts counts_;
  ScanTimes times_;
  double times_sum_s_ = 0.0;
};

}  // namespace dispel::node
