#pragma once
/// @file
/// The filter node's work on one scan, without ROS's publishers, subscribers or tf: the ROS 1
/// message converted, given to the shared runner (pipeline::ScanFilterRunner, the one `dispel
/// filter` uses) with the sensor pose the node found, and the two messages it publishes made.
/// Testable without a ROS master; the node adds only the middleware around it.

#include <sensor_msgs/LaserScan.h>

#include <optional>

#include "dispel/core/pose2.hpp"
#include "dispel/pipeline/scan_filter_runner.hpp"

namespace dispel::ros1 {

class FilterNodeCore {
 public:
  /// @throws std::invalid_argument if options.validate() does.
  explicit FilterNodeCore(pipeline::ScanFilterRunnerOptions options)
      : runner_(std::move(options)) {}

  /// What the node publishes for one scan.
  struct Output {
    sensor_msgs::LaserScan filtered;  ///< On scan_filtered: removed beams NaN.
    sensor_msgs::LaserScan labels;    ///< On scan_labels: intensities = beam labels.
    const FilterResult* result;       ///< Valid until the next process().
  };

  /// Filters @p msg with the laser's pose in the fixed frame at its stamp (std::nullopt: none
  /// known, the scan is published unfiltered). @p stamp_s replaces a zero header stamp (the
  /// node's receive time), as drivers without a clock leave it.
  Output process(const sensor_msgs::LaserScan& msg, double stamp_s,
                 const std::optional<Pose2>& sensor_pose);

  const pipeline::ScanFilterRunner& runner() const { return runner_; }
  pipeline::ScanFilterRunner& runner() { return runner_; }

 private:
  pipeline::ScanFilterRunner runner_;
};

}  // namespace dispel::ros1
