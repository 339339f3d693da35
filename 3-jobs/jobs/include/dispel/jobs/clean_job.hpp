#pragma once
/// @file
/// `dispel clean`: the offline two-pass filter. The online filter runs over the whole recording
/// (the same road as `dispel filter`: read_scan_motion(), pipeline::ScanFilterRunner), the
/// OfflineCleaner remembers what it found, and a second pass writes the recording with every
/// input message plus `<scan topic>_clean` (removed beams NaN) and `<scan topic>_clean_labels`
/// (intensities = CleanLabel values).

#include <atomic>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "dispel/core/offline_cleaner.hpp"
#include "dispel/jobs/filter_job.hpp"

namespace dispel::jobs {

/// CleanConfig::through_min_scans chosen by the sensor: kStaticSensorThroughScans with a sensor
/// that does not move (FilterJobOptions::static_sensor), else 0 (off). A static sensor's pose is
/// exact, so a place its beams passed through was free; on a moving robot a few centimetres of
/// pose error make a surface seen along it look seen through (docs/clean.md).
constexpr int kThroughScansBySensor = -1;
constexpr int kStaticSensorThroughScans = 2;

/// CleanConfig's defaults, with through_min_scans kThroughScansBySensor.
inline CleanConfig clean_defaults_by_sensor() {
  CleanConfig c;
  c.through_min_scans = kThroughScansBySensor;
  return c;
}

struct CleanJobOptions {
  /// The recording, the output, the configuration, the topics and the sensor as for `dispel
  /// filter` (a CARMEN log is not read: convert it with `dispel filter` first).
  FilterJobOptions filter;
  CleanConfig clean = clean_defaults_by_sensor();
};

/// @p options.clean with through_min_scans chosen by the sensor when it is kThroughScansBySensor,
/// and poses_exact with a static sensor.
CleanConfig clean_config(const CleanJobOptions& options);

struct CleanJobStats {
  std::string input_format;
  bool laser_only = false;
  std::int64_t messages_in = 0, messages_out = 0;
  std::map<std::string, std::int64_t> left_out;
  std::int64_t scans = 0;
  FilterCounters online;  ///< The online filter's counters (its first pass).
  CleanConfig config;     ///< What the cleaner ran with (clean_config()).
  CleanCounts counts;
  std::vector<CleanedObject> objects;
  double first_pass_s = 0.0, second_pass_s = 0.0;  ///< Wall time of each pass.
};

/// Runs the job. The output appears only when complete. @throws JobError, JobCancelled
CleanJobStats run_clean_job(const CleanJobOptions& options, const Progress& progress = {},
                            const std::atomic<bool>* cancel = nullptr, const Notice& notice = {});

}  // namespace dispel::jobs
