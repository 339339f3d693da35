#pragma once
// Internal to dispel::slam: a recording opened for a run over its scans (the ICP-SLAM run and the
// particle-filter localisation read it alike), through the shared first pass. No MRPT here.

#include <functional>
#include <memory>
#include <string>

#include "dispel/core/laser_scan.hpp"
#include "dispel/io/recording_motion.hpp"

namespace dispel::slam::detail {

/// A recording with its odometry and laser mount.
struct SlamInput {
  std::unique_ptr<io::RecordingReader> recording;
  io::RecordingMotion motion;  ///< motion.scan_topic: the scan topic read.
};

/// Opens @p path and reads its first pass: @p scan_topic (LaserScan; empty: /scan_filtered when
/// the recording has it, else /scan), the odometry on @p odom_topic and the laser mount.
/// @throws jobs::JobError with a one-line message (not a file, not a bag, a missing topic, no
/// scans, no usable odometry, no laser mount).
SlamInput open_slam_input(const std::string& path, const std::string& scan_topic,
                          const std::string& odom_topic, double odom_tolerance_s);

/// Calls @p visit with every scan of the input's scan topic, in order; reading errors become
/// jobs::JobError naming the recording.
void for_each_scan(SlamInput& input, const std::function<void(const LaserScan&)>& visit);

}  // namespace dispel::slam::detail
