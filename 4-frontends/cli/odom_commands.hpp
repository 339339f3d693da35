#pragma once
// `dispel odom` and `dispel eval-trajectory`: thin shells around dispel::io and dispel::eval.

#include <string>

#include "dispel/jobs/odom_job.hpp"

namespace dispel::apps {

struct OdomCommandOptions {
  jobs::OdomJobOptions job;
  bool json = false;  ///< Print the statistics as JSON instead of a summary line.
};
int run_odom(const OdomCommandOptions& options);

struct EvalTrajectoryOptions {
  std::string truth;
  std::string estimate;
  double align_first_m = 0.0;
  bool json = false;
};
int run_eval_trajectory(const EvalTrajectoryOptions& options);

}  // namespace dispel::apps
