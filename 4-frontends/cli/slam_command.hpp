#pragma once
// `dispel slam`: a thin shell around dispel::slam.

#include <string>

#include "dispel/slam/experiment.hpp"
#include "dispel/slam/icp_slam.hpp"
#include "dispel/slam/localization.hpp"

namespace dispel::apps {

struct SlamCommandOptions {
  slam::SlamOptions job;
  std::string output;    ///< TRAJECTORY.csv (t,x,y,yaw).
  std::string odom_csv;  ///< Optional: the odometry at the same scans, as t,x,y,yaw.
  std::string save_map;  ///< SLAM: also write the map as map_server YAML + PGM here.
  /// Given: localise in this map (particle filter) instead of SLAM.
  std::string map;
  slam::LocalizationOptions localization;  ///< Its options (input and topics from job).
  bool json = false;                       ///< Print the counters as JSON.
};
int run_slam(const SlamCommandOptions& options);

struct ExperimentCommandOptions {
  slam::ExperimentOptions job;  ///< work_dir: set by the command.
  std::string out_dir;          ///< Per-run CSV, JSON and trajectories; empty: none.
  bool json = false;            ///< Print the summary as JSON instead of tables.
};
int run_experiment(const ExperimentCommandOptions& options);

}  // namespace dispel::apps
