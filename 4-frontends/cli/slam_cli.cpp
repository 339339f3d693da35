#include "slam_cli.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <iostream>
#include <string>

#include "cli_validators.hpp"

namespace dispel::apps {

void add_slam_commands(CLI::App& app, SlamCli& cli) {
  cli.slam.job.scan_topic.clear();
  cli.slam_cmd = app.add_subcommand(
      "slam", "Run MRPT's ICP-SLAM over a recording's scans and odometry; write its trajectory");
  cli.slam_cmd
      ->add_option("input", cli.slam.job.input,
                   "IN.bag or an MRPT IN.rawlog (raw, or a bag filtered by dispel filter)")
      ->required();
  cli.slam_cmd->add_option("-o,--output", cli.slam.output, "TRAJECTORY.csv to write (t,x,y,yaw)")
      ->required();
  cli.slam_cmd->add_option(
      "--scan-topic", cli.slam.job.scan_topic,
      "LaserScan topic (default: /scan_filtered if the bag has it, else /scan)");
  cli.slam_cmd
      ->add_option("--odom-topic", cli.slam.job.odom_topic, "Odometry topic (the motion input)")
      ->capture_default_str();
  cli.slam_cmd->add_option("--engine-config", cli.slam_ini,
                           "MRPT .ini over the defaults ([MappingApplication], [ICP], ...)");
  cli.slam_cmd->add_option("--odom-csv", cli.slam.odom_csv,
                           "Also write the odometry at the same scans as t,x,y,yaw here");
  cli.slam_cmd->add_option("--save-map", cli.slam.save_map,
                           "Also write the map as map_server MAP.yaml + MAP.pgm");
  cli.slam_cmd->add_option(
      "--map", cli.slam.map,
      "Localise in this map_server MAP.yaml (particle filter) instead of SLAM");
  cli.slam_cmd
      ->add_option("--initial-pose", cli.initial_pose,
                   "With --map: the robot's pose X Y YAW (m, m, rad) in the map at the first "
                   "scan (default: the odometry pose)")
      ->expected(3);
  cli.slam_cmd
      ->add_option("--particles", cli.slam.localization.filter.particles, "With --map: particles")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  cli.slam_cmd
      ->add_option("--seed", cli.slam.localization.filter.seed,
                   "With --map: the particle filter's random seed (same seed, same trajectory)")
      ->capture_default_str();
  cli.slam_cmd->add_flag("--json", cli.slam.json, "Print the counters as JSON");

  cli.experiment_cmd = app.add_subcommand(
      "experiment",
      "Simulate a scenario over many seeds; run SLAM on the raw, filtered and oracle scans and "
      "compare each with the truth");
  cli.experiment_cmd->add_option("scenario", cli.experiment.job.scenario, "SCENARIO.yaml")
      ->required();
  cli.experiment_cmd->add_option("--seeds", cli.experiment.job.seeds, "How many seeds")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cli.experiment_cmd->add_option("--first-seed", cli.experiment.job.first_seed, "The first seed")
      ->capture_default_str();
  cli.experiment_duration = cli.experiment_cmd->add_option(
      "--duration", cli.experiment_duration_s, "Seconds per run (default: the scenario's)");
  cli.experiment_duration->check(positive_number());
  cli.experiment_cmd->add_option("--out", cli.experiment.out_dir,
                                 "Write runs.csv, summary.json and the trajectories here");
  cli.experiment_cmd->add_flag("--json", cli.experiment.json, "Print the summary as JSON");
  cli.experiment_cmd->add_option("--config", cli.experiment_config,
                                 "The filter's YAML configuration (default: dispel's defaults)");
  cli.experiment_cmd->add_option("--engine-config", cli.experiment_ini,
                                 "MRPT .ini over the defaults");
  cli.experiment_cmd
      ->add_option("--diverged-at", cli.experiment.job.divergence_position_m,
                   "A run diverged when its position error ever exceeds this (m)")
      ->check(positive_number())
      ->capture_default_str();
  cli.experiment_cmd
      ->add_option("--diverged-at-yaw", cli.experiment_yaw_deg,
                   "... or its yaw error ever exceeds this (deg)")
      ->check(positive_number())
      ->capture_default_str();
  cli.experiment_cmd->add_flag(
      "--localization", cli.experiment.job.localization,
      "Also localise raw, filtered and oracle scans (particle filter) in the oracle's SLAM map");
  cli.experiment_cmd
      ->add_option("--particles", cli.experiment.job.particles, "With --localization: particles")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  cli.experiment_cmd->add_flag(
      "--clean", cli.experiment.job.clean,
      "Also run dispel clean (the offline filter) and SLAM on its output: the variant cleaned");
  cli.experiment_cmd->add_flag("--keep-bags", cli.experiment.job.keep_bags,
                               "Keep the bags of each seed under OUT/bags/ (needs --out)");
}

bool slam_command_chosen(const SlamCli& cli) {
  return (cli.slam_cmd != nullptr && *cli.slam_cmd) ||
         (cli.experiment_cmd != nullptr && *cli.experiment_cmd);
}

int exec_dispel_slam(int argc, char** argv) {
  (void)argc;
  std::string self(4096, '\0');
  const ssize_t n = ::readlink("/proc/self/exe", self.data(), self.size() - 1);
  std::string path = "dispel-slam";
  if (n > 0) {
    self.resize(static_cast<std::size_t>(n));
    path = self.substr(0, self.find_last_of('/') + 1) + "dispel-slam";
  }
  argv[0] = path.data();
  ::execv(path.c_str(), argv);
  std::cerr << "dispel: cannot run " << path << " (" << std::strerror(errno)
            << "); it carries dispel slam and dispel experiment and is installed next to dispel\n";
  return 1;
}

}  // namespace dispel::apps
