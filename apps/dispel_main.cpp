// The dispel command line. Each subcommand is a thin adapter over the libraries.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "bench_command.hpp"
#ifdef DISPEL_HAVE_IO
#include "filter_command.hpp"
#include "sim_commands.hpp"
#endif

#ifndef DISPEL_VERSION
#define DISPEL_VERSION "unknown"
#endif

int main(int argc, char** argv) {
  CLI::App app{"dispel: removes moving objects from 2D LiDAR scans before SLAM sees them"};
  app.set_version_flag("--version", DISPEL_VERSION);
  app.require_subcommand(0, 1);

  dispel::apps::BenchOptions bench;
  CLI::App* bench_cmd = app.add_subcommand(
      "bench", "Measure segmentation and the reference DBSCAN at 1617 to 1000000 beams");
  bench_cmd->add_flag("--json", bench.json,
                      R"(Print {"results": [{"name", "beams", "median_ns"}]})");
  bench_cmd
      ->add_option("--filter", bench.filter,
                   "Regular expression on case names such as segmentation/1617/...")
      ->capture_default_str();
  bench_cmd->add_option("--repetitions", bench.repetitions, "Repetitions per case (median taken)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  bench_cmd->add_option("--min-time", bench.min_time_s, "Minimum seconds per repetition")
      ->check(CLI::Range(0.001, 60.0))
      ->capture_default_str();

#ifdef DISPEL_HAVE_IO
  dispel::apps::FilterCommandOptions filter;
  std::string config_path;
  CLI::App* filter_cmd = app.add_subcommand(
      "filter", "Remove moving objects from the scans of a recording (ROS 1 bag or CARMEN log)");
  filter_cmd->add_option("input", filter.job.input, "IN.bag, or a CARMEN .log/.clf")->required();
  filter_cmd->add_option("-o,--output", filter.job.output, "OUT.bag to write")->required();
  filter_cmd->add_option("--config", config_path, "YAML configuration (see config/default.yaml)");
  filter_cmd->add_option("--scan-topic", filter.job.scan_topic, "LaserScan topic")
      ->capture_default_str();
  filter_cmd->add_option("--odom-topic", filter.job.odom_topic, "Odometry topic")
      ->capture_default_str();
  filter_cmd->add_flag("--static-sensor", filter.job.static_sensor,
                       "The sensor does not move (no odometry needed)");
  filter_cmd->add_flag("--scale-to-scanner", filter.job.scale_to_scanner,
                       "Carry N_min, L_d and L_s over from the thesis's scanner to this one");
  filter_cmd->add_option("--stats", filter.stats_path, "Write statistics as JSON here");
  filter_cmd->add_option("--compression", filter.compression, "Output bag compression")
      ->check(CLI::IsMember({"none", "bz2", "lz4"}))
      ->capture_default_str();

  dispel::apps::SimOptions sim;
  CLI::App* sim_cmd =
      app.add_subcommand("sim", "Simulate a scenario into a bag with ground truth per beam");
  sim_cmd->add_option("scenario", sim.scenario, "SCENARIO.yaml (see config/scenarios/)")
      ->required();
  sim_cmd->add_option("-o,--output", sim.output, "OUT.bag to write")->required();
  sim_cmd->add_option("--seed", sim.seed, "Random seed (same seed, same bag)")
      ->capture_default_str();
  sim_cmd->add_option("--duration", sim.duration_s, "Seconds to simulate (default: the scenario's)")
      ->check(CLI::PositiveNumber);

  dispel::apps::EvalOptions evaluation;
  CLI::App* eval_cmd =
      app.add_subcommand("eval", "Compare a filtered bag with the simulator's ground truth");
  eval_cmd->add_option("--truth", evaluation.truth, "SIM.bag from dispel sim")->required();
  eval_cmd->add_option("--result", evaluation.result, "FILTERED.bag from dispel filter")
      ->required();
  eval_cmd->add_option("--scan-topic", evaluation.scan_topic, "LaserScan topic")
      ->capture_default_str();
  eval_cmd->add_flag("--json", evaluation.json, "Print JSON");
#endif

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (*bench_cmd) return dispel::apps::run_bench(bench);
#ifdef DISPEL_HAVE_IO
    if (*filter_cmd) {
      if (!config_path.empty()) filter.job.config_path = config_path;
      return dispel::apps::run_filter(filter);
    }
    if (*sim_cmd) return dispel::apps::run_sim(sim);
    if (*eval_cmd) return dispel::apps::run_eval(evaluation);
#endif
  } catch (const std::exception& e) {
    std::cerr << "dispel: " << e.what() << "\n";
    return 1;
  }
  std::cerr << "dispel: no command given\n" << app.help();
  return 1;
}
