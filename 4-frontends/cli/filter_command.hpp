#pragma once
// `dispel filter`, `dispel clean` and `dispel convert`: thin shells around dispel::jobs::
// run_filter_job, run_clean_job and run_convert_job.

#include <string>

#include "dispel/jobs/clean_job.hpp"
#include "dispel/jobs/convert_job.hpp"
#include "dispel/jobs/filter_job.hpp"
#include "dispel/pipeline/resident_heap.hpp"

namespace dispel::apps {

struct FilterCommandOptions {
  jobs::FilterJobOptions job;
  std::string stats_path;  ///< Empty: no statistics file.
  std::string compression = "none";
  /// Heap made resident before the first scan (pipeline::reserve_resident_heap); 0: none.
  int resident_heap_mb = static_cast<int>(pipeline::kDefaultResidentHeapBytes >> 20);
};

/// Runs the job, prints a progress bar on a terminal and a summary on stdout, writes the
/// statistics. Returns the exit code: 0 done, 1 error, 130 interrupted.
int run_filter(FilterCommandOptions options);

struct CleanCommandOptions {
  jobs::CleanJobOptions job;
  std::string stats_path;  ///< Empty: no statistics file.
  std::string compression = "none";
};

/// Runs `dispel clean`: prints a summary on stdout, writes the statistics (with one entry per
/// object). Returns the exit code as run_filter() does.
int run_clean(CleanCommandOptions options);

/// "none", "bz2", "lz4" or "zstd" as jobs::Compression.
jobs::Compression compression_named(const std::string& name);

/// Runs the conversion; prints what it wrote, and the messages left out as a warning. Returns the
/// exit code as run_filter() does.
int run_convert(const jobs::ConvertJobOptions& options);

}  // namespace dispel::apps
