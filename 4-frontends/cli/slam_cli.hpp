#pragma once
// The command lines of `dispel slam` and `dispel experiment`. `dispel` defines them (for parsing
// and help) and hands a chosen one to the dispel-slam program next to it, which links MRPT: MRPT
// and the libraries it pulls in take about 0.4 s to load, which every other command is spared.

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "slam_command.hpp"

namespace dispel::apps {

struct SlamCli {
  SlamCommandOptions slam;
  std::string slam_ini;
  std::vector<double> initial_pose;
  ExperimentCommandOptions experiment;
  std::string experiment_config;
  std::string experiment_ini;
  double experiment_duration_s = 0.0;
  double experiment_yaw_deg = 10.0;
  CLI::App* slam_cmd = nullptr;
  CLI::App* experiment_cmd = nullptr;
  CLI::Option* experiment_duration = nullptr;
};

/// Adds the `slam` and `experiment` subcommands to @p app, writing into @p cli.
void add_slam_commands(CLI::App& app, SlamCli& cli);

/// Whether the parsed command line chose one of them.
bool slam_command_chosen(const SlamCli& cli);

/// Runs the chosen one (dispel-slam only: it links dispel::slam). Returns the exit code.
int run_slam_command(SlamCli& cli);

/// Replaces this process by dispel-slam (found next to this executable) with the same arguments.
/// Returns only on failure, with exit code 1 and a message.
int exec_dispel_slam(int argc, char** argv);

}  // namespace dispel::apps
