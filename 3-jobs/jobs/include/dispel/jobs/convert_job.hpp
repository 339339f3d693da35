#pragma once
/// @file
/// `dispel convert`: a recording into another format (ROS 1 bag, rosbag2 MCAP) or another
/// compression, every message in time order. Messages of the same format are copied byte for
/// byte; between formats the recording model's types are converted (the planar parts dispel
/// keeps: see recording.hpp) and the other types are left out and counted.

#include <atomic>
#include <cstdint>
#include <map>
#include <string>

#include "dispel/jobs/job.hpp"

namespace dispel::jobs {

struct ConvertJobOptions {
  std::string input;   ///< Any recording open_recording() reads.
  std::string output;  ///< Its format by name (create_recording()).
  Compression compression = Compression::kNone;
  RecordingFormat format = RecordingFormat::kByName;
};

struct ConvertJobStats {
  std::string input_format;
  std::int64_t messages_in = 0;
  std::int64_t messages_out = 0;
  std::map<std::string, std::int64_t> left_out;  ///< By topic (left_out_summary()).
};

/// @throws JobError, JobCancelled (nothing is left at the output then)
ConvertJobStats run_convert_job(const ConvertJobOptions& options, const Progress& progress = {},
                                const std::atomic<bool>* cancel = nullptr);

}  // namespace dispel::jobs
