#pragma once
// `dispel filter`: a thin shell around dispel::jobs::run_filter_job.

#include <string>

#include "dispel/jobs/filter_job.hpp"

namespace dispel::apps {

struct FilterCommandOptions {
  jobs::FilterJobOptions job;
  std::string stats_path;  ///< Empty: no statistics file.
  std::string compression = "none";
};

/// Runs the job, prints a progress bar on a terminal and a summary on stdout, writes the
/// statistics. Returns the exit code: 0 done, 1 error, 130 interrupted.
int run_filter(FilterCommandOptions options);

}  // namespace dispel::apps
