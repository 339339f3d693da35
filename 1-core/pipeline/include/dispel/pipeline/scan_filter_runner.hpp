#pragma once
/// @file
/// The one road from scans to the dynamic filter, for `dispel filter`, `dispel render` and the
/// nodes alike: the filter fed one scan at a time as it arrives, with the configuration carried
/// over to the scanner on the first scans (`scale_to_scanner`, with the period of ScanPeriod),
/// scans without a sensor pose passed through, and counts and processing times. A front end
/// converts its messages, finds the sensor pose, and calls process().

#include <cstdint>
#include <optional>

#include "dispel/core/dynamic_filter.hpp"
#include "dispel/pipeline/scan_period.hpp"

namespace dispel::pipeline {

struct ScanFilterRunnerOptions {
  /// The filter's configuration (as parsed from YAML).
  DynamicFilterConfig config;
  /// Carry N_min, L_d and L_s over to the scanner (scale_to_scanner() in the core): the angle
  /// increment of the first scan with a valid one, the period by ScanPeriod's rule.
  bool scale_to_scanner = false;
  /// The scanner's period for scale_to_scanner (s); 0: learnt from the scans (ScanPeriod).
  double scan_period_s = 0.0;
  /// The sensor does not move (`--static-sensor`): the pose given is the identity, exact, and the
  /// registration does not align the scans (RegistrationConfig::align false).
  bool static_sensor = false;

  /// Throws std::invalid_argument naming the first bad field (the configuration's own, or
  /// scan_period_s).
  void validate() const;
};

/// What the runner did with one scan.
enum class ScanOutcome : std::uint8_t {
  kFiltered,          ///< Tracked and filtered (any FilterEvent but the pass-throughs).
  kNoPose,            ///< Passed through unchanged: no sensor pose (FilterEvent::kNoPose).
  kBadPose,           ///< Passed through unchanged: the pose is not finite.
  kBadScan,           ///< Passed through unchanged: the scan failed check_scan().
  kWaitingForPeriod,  ///< Passed through unchanged: scale_to_scanner, scanner not known yet.
};

/// Running totals since the runner was made.
struct ScanFilterCounts {
  std::int64_t scans = 0;           ///< Scans given to process().
  std::int64_t filtered = 0;        ///< ScanOutcome::kFiltered.
  std::int64_t no_pose = 0;         ///< ScanOutcome::kNoPose.
  std::int64_t bad_pose = 0;        ///< ScanOutcome::kBadPose.
  std::int64_t rejected_scan = 0;   ///< ScanOutcome::kBadScan.
  std::int64_t waiting_period = 0;  ///< ScanOutcome::kWaitingForPeriod.
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

  /// Filters @p scan with the sensor pose in the fixed frame at its stamp, or std::nullopt when
  /// none is known. @p stated_period_s is the period the scan message states (0 when it states
  /// none). A scan that is passed through (see ScanOutcome) comes back unchanged, its valid beams
  /// labelled "no object" and the others "invalid"; while waiting for the period its event is
  /// kRejectedScan or kNoPose (the filter had neither a usable scan nor a configuration).
  const FilterResult& process(const LaserScan& scan, double stated_period_s,
                              const std::optional<Pose2>& sensor_pose);

  /// What the last process() did, and how long it took (s): wall time, and the CPU time of the
  /// calling thread (less than the wall time when the thread was preempted: a slow scan that did
  /// ordinary work was kept waiting by the machine, not by the filter).
  ScanOutcome last_outcome() const { return last_outcome_; }
  double last_time_s() const { return times_.last_s; }
  double last_cpu_time_s() const { return last_cpu_s_; }

  /// The configuration in use; before the first scan under scale_to_scanner, the unscaled one.
  const DynamicFilterConfig& config() const;
  /// Whether the configuration is final (scaled to the scanner when asked).
  bool configured() const { return filter_.has_value(); }
  /// The scanner's period once known: given, or learnt under scale_to_scanner (without it the
  /// filter needs none and none is learnt).
  std::optional<double> scan_period_s() const { return period_.period(); }
  const ScanFilterCounts& counts() const { return counts_; }
  /// The filter's own counters (zero before the first filtered scan).
  FilterCounters filter_counters() const;
  /// Processing times since the previous call; resets them.
  ScanTimes take_times();

 private:
  ScanOutcome run(const LaserScan& scan, double stated_period_s,
                  const std::optional<Pose2>& sensor_pose);

  ScanFilterRunnerOptions options_;
  ScanPeriod period_;
  std::optional<DynamicFilter> filter_;
  // scale_to_scanner: the free-space window, made with the runner so that the first scan does not
  // pay for it (16 MiB zeroed: 11-24 ms), and handed to the filter made at the first scan.
  std::optional<FreeSpaceMap> free_space_;
  FilterResult result_;
  ScanOutcome last_outcome_ = ScanOutcome::kFiltered;
  ScanFilterCounts counts_;
  ScanTimes times_;
  double times_sum_s_ = 0.0;
  double last_cpu_s_ = 0.0;
};

}  // namespace dispel::pipeline
