#pragma once
/// @file
/// `dispel filter`: run the dynamic filter over a recording (a ROS 1 bag or a CARMEN log) and
/// write a bag with every input message plus the filtered scans and their labels.

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "dispel/core/dynamic_filter.hpp"

namespace dispel::io {

enum class Compression { kNone, kBz2, kLz4 };

struct FilterJobOptions {
  std::string input;                          ///< .bag, or .log / .clf (CARMEN).
  std::string output;                         ///< The bag to write.
  std::optional<std::string> config_path;     ///< YAML; default_config() without it.
  std::optional<DynamicFilterConfig> config;  ///< Used instead of config_path when given.
  std::string scan_topic = "/scan";
  std::string odom_topic = "/odom";
  bool static_sensor = false;     ///< The sensor does not move: identity pose, no odometry.
  bool scale_to_scanner = false;  ///< Apply scale_to_scanner() with the recording's scanner.
  Compression compression = Compression::kNone;
  /// How far beyond the first or last odometry message a scan's pose may be taken from it.
  double odom_tolerance_s = 0.05;
};

/// What the job did.
struct FilterJobStats {
  std::string input_format;                           ///< "rosbag" or "carmen".
  std::int64_t messages_in = 0;                       ///< Messages (bag) or lines (CARMEN) read.
  std::int64_t messages_out = 0;                      ///< Messages written.
  std::int64_t scans = 0;                             ///< Scans seen.
  std::int64_t scans_filtered = 0;                    ///< Scans the filter tracked and filtered.
  std::map<std::string, std::int64_t> scans_skipped;  ///< Passed through unchanged, by reason.
  FilterCounters counters;                            ///< The filter's own counters.
  std::vector<double> scan_time_s;                    ///< Processing time of each scan, seconds.
  DynamicFilterConfig config;                         ///< The configuration used.
  std::int64_t malformed_lines = 0;                   ///< CARMEN only: skipped lines.
  std::int64_t odometry_refused = 0;  ///< Odometry messages out of order or not finite.
};

/// A recording or configuration that cannot be processed; what() is one line.
class JobError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Thrown when @p cancel became true; the output is not written.
class JobCancelled : public std::runtime_error {
 public:
  JobCancelled() : std::runtime_error("interrupted") {}
};

/// Called now and then with the fraction done, in [0, 1].
using Progress = std::function<void(double)>;

/// Runs the job. The output appears only when complete (written to "<output>.partial" and
/// renamed). @throws JobError, JobCancelled
FilterJobStats run_filter_job(const FilterJobOptions& options, const Progress& progress = {},
                              const std::atomic<bool>* cancel = nullptr);

}  // namespace dispel::io
