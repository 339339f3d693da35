#pragma once
/// @file
/// `dispel filter`: the dynamic filter over a recording (a ROS 1 bag, an MRPT rawlog or a CARMEN
/// log), written as a bag with every input message plus the filtered scans and their labels. The
/// scans go through pipeline::ScanFilterRunner, as in the nodes.

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "dispel/core/dynamic_filter.hpp"
#include "dispel/io/recording_motion.hpp"
#include "dispel/jobs/job.hpp"

namespace dispel::jobs {

struct FilterJobOptions {
  std::string input;                          ///< .bag, .rawlog (MRPT), or .log / .clf (CARMEN).
  std::string output;                         ///< The bag to write.
  std::optional<std::string> config_path;     ///< YAML; DynamicFilterConfig{} without it.
  std::optional<DynamicFilterConfig> config;  ///< Used instead of config_path when given.
  std::string scan_topic = "/scan";
  /// "none": laser-only (each scan registered to the map of the earlier ones; needs
  /// registration.enabled). A recording without any odometry topic is filtered laser-only too.
  std::string odom_topic = "/odom";
  bool static_sensor = false;     ///< The sensor does not move: identity pose, no odometry.
  bool scale_to_scanner = false;  ///< Apply scale_to_scanner() with the recording's scanner.
  Compression compression = Compression::kNone;
  RecordingFormat format = RecordingFormat::kByName;  ///< Of the output.
  /// How far beyond the first or last odometry message a scan's pose may be taken from it.
  double odom_tolerance_s = 0.05;
};

/// What the job did.
/// One of the scans that cost the most CPU time, and what the filter did for it.
struct SlowScan {
  std::int64_t index = 0;  ///< 0-based, among the scans seen.
  double stamp_s = 0.0;
  double time_s = 0.0;      ///< Wall time.
  double cpu_time_s = 0.0;  ///< CPU time of the filtering thread.
  FilterEvent event = FilterEvent::kFiltered;
  ScanWork work;
};

struct FilterJobStats {
  bool laser_only = false;        ///< Filtered without odometry (registered scans only).
  std::string input_format;       ///< "rosbag", "MRPT rawlog" or "carmen".
  std::int64_t messages_in = 0;   ///< Messages (bag) or lines (CARMEN) read.
  std::int64_t messages_out = 0;  ///< Messages written.
  /// Messages not written, by topic: types that cannot be converted between the input's and the
  /// output's formats (a ROS 1 bag's /rosout into MCAP, say). See left_out_summary().
  std::map<std::string, std::int64_t> left_out;
  std::int64_t scans = 0;           ///< Scans seen.
  std::int64_t scans_filtered = 0;  ///< Scans the filter tracked and filtered.
  /// Passed through unchanged, by reason: bad_scan_<issue>, bad_pose, odometry_<lookup> (no pose
  /// at the scan's stamp), waiting_for_scan_period (--scale-to-scanner, the first scans of a
  /// scanner that states no period).
  std::map<std::string, std::int64_t> scans_skipped;
  FilterCounters counters;              ///< The filter's own counters.
  std::vector<double> scan_time_s;      ///< Processing time of each scan (wall), seconds.
  std::vector<double> scan_cpu_time_s;  ///< The same in CPU time of the filtering thread.
  /// The kSlowScansKept scans that cost the most CPU time, the costliest first.
  std::vector<SlowScan> slowest_scans;
  static constexpr std::size_t kSlowScansKept = 5;
  /// Per registered scan (registration on): RMS point-to-line residual (m), share of points
  /// with a correspondence, and degeneracy (weakest / strongest translation information).
  std::vector<double> registration_residual_m;
  std::vector<double> registration_inlier_share;
  std::vector<double> registration_degeneracy;
  DynamicFilterConfig config;  ///< The configuration used (scaled to the scanner if asked).
  std::optional<double> scan_period_s;  ///< The scanner's period, when it was needed and known.
  std::int64_t malformed_lines = 0;     ///< CARMEN only: skipped lines.
  /// Scans that reset the filter's tracks (a time gap above max_time_gap_s, time going back, a
  /// pose jump): each starts anew, so nothing on it is found moving.
  std::int64_t scans_reset = 0;
  /// More than half of the scans reset the filter or were passed through: the output is hardly
  /// filtered (a sparse or subsampled log, missing odometry). `warning` says why, in one line.
  bool mostly_unfiltered = false;
  std::string warning;
  /// CARMEN only: added to every stamp (1 s for a log that counts time from 0, else 0).
  double stamp_offset_s = 0.0;
  std::int64_t odometry_refused = 0;  ///< Odometry messages out of order or not finite.
};

/// Told once, before the scans are filtered, something the user should know (laser-only).
using Notice = std::function<void(const std::string&)>;

/// The configuration @p o names (its config, else the file at config_path, else the defaults).
/// @throws JobError for a file that cannot be read or holds a bad value
DynamicFilterConfig filter_config(const FilterJobOptions& o);

/// The road from a recording to the filter, shared by `dispel filter` and `dispel clean`: where
/// the sensor was at each scan (odometry and mount, a static sensor, or laser-only), with the
/// checks of --scale-to-scanner and laser-only, and the laser-only notice. @throws JobError
io::RecordingMotion read_scan_motion(const FilterJobOptions& o, io::RecordingReader& in,
                                     const std::atomic<bool>* cancel, const Notice& notice);

/// Runs the job. The output appears only when complete (written to "<output>.partial" and
/// renamed). @throws JobError, JobCancelled
FilterJobStats run_filter_job(const FilterJobOptions& options, const Progress& progress = {},
                              const std::atomic<bool>* cancel = nullptr, const Notice& notice = {});

}  // namespace dispel::jobs
