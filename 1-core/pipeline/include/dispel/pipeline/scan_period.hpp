#pragma once
/// @file
/// The scanner's period by one rule for every road from scans to the filter (`dispel filter`,
/// `dispel render`, the nodes): what `--scale-to-scanner` carries the thesis's counts over with.

#include <optional>
#include <vector>

namespace dispel::pipeline {

/// Learns the time between scans from the scans as they come:
///  1. the period given by the user (> 0), if any;
///  2. else the period the first scan that states one states (sensor_msgs/LaserScan scan_time,
///     finite and > 0);
///  3. else the median of the first kIntervals intervals between increasing stamps, so one
///     dropped or doubled scan does not change it (the first kIntervals scans go by before it is
///     known).
/// Stamps that are not finite or not later than the previous one are passed over.
class ScanPeriod {
 public:
  static constexpr int kIntervals = 3;

  /// @p given_s: the period given by the user, 0 when none. Must be finite and >= 0 (checked by
  /// the callers' options).
  explicit ScanPeriod(double given_s = 0.0);

  /// Takes one scan's stamp and stated period (0 when it states none); returns the period once it
  /// is known (and from then on the same value).
  std::optional<double> add(double stamp_s, double stated_period_s);

  /// The period, once known.
  std::optional<double> period() const { return period_; }

 private:
  std::optional<double> period_;
  std::optional<double> last_stamp_s_;
  std::vector<double> intervals_;
};

}  // namespace dispel::pipeline
