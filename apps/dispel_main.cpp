// The dispel command line. Each subcommand is a thin adapter over the libraries.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "bench_command.hpp"
#ifdef DISPEL_HAVE_IO
#include "filter_command.hpp"
#include "odom_commands.hpp"
#include "render_command.hpp"
#include "sim_commands.hpp"
#endif
#ifdef DISPEL_HAVE_SLAM
#include "slam_command.hpp"
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
  eval_cmd->add_option("--plot", evaluation.plot,
                       "Also draw the latency histogram and the rates into FILE.png or .svg");

  dispel::apps::RenderCommandOptions render;
  std::string render_config;
  double render_from = 0.0, render_to = 0.0;
  CLI::App* render_cmd = app.add_subcommand(
      "render", "Draw a recording (filtered or not) as a map of all scans or one scan's objects");
  render_cmd->add_option("input", render.job.input, "IN.bag")->required();
  render_cmd->add_option("-o,--output", render.job.output, "OUT.png or OUT.svg to write")
      ->required();
  render_cmd->add_option("--view", render.job.view, "map (all scans) or scan (one scan)")
      ->capture_default_str();
  render_cmd
      ->add_option("--scan-index", render.job.scan_index,
                   "Scan view: which scan, 0-based among the scan topic's messages")
      ->capture_default_str();
  CLI::Option* from_opt = render_cmd->add_option(
      "--from", render_from, "Map view: first scan drawn, seconds from the recording's start");
  CLI::Option* to_opt = render_cmd->add_option(
      "--to", render_to, "Map view: last scan drawn, seconds from the recording's start");
  render_cmd
      ->add_option("--frame", render.job.frame,
                   "odom (odometry + laser mount) or truth (/ground_truth of dispel sim)")
      ->capture_default_str();
  render_cmd->add_option("--scan-topic", render.job.scan_topic, "LaserScan topic")
      ->capture_default_str();
  render_cmd->add_option("--odom-topic", render.job.odom_topic, "Odometry topic")
      ->capture_default_str();
  render_cmd->add_flag("--static-sensor", render.job.static_sensor,
                       "The sensor does not move (no odometry needed)");
  render_cmd->add_option("--config", render_config,
                         "Scan view: YAML configuration of the segmentation and filter");
  render_cmd->add_flag("--scale-to-scanner", render.job.scale_to_scanner,
                       "Scan view: as dispel filter --scale-to-scanner");
  render_cmd->add_option("--size", render.size, "Picture size WIDTHxHEIGHT (default 1600x1200)");

  dispel::apps::OdomCommandOptions odom;
  std::string odom_config, odom_model;
  CLI::App* odom_cmd =
      app.add_subcommand("odom", "Fuse wheel speeds and IMU yaw rate (UKF) into a trajectory CSV");
  odom_cmd->add_option("input", odom.job.input, "IN.bag (or give --wheels-csv)");
  odom_cmd->add_option("-o,--output", odom.job.output, "TRAJECTORY.csv to write")->required();
  odom_cmd->add_option("--model", odom_model, "ct, ct_euler, omni or dead_reckoning")
      ->check(CLI::IsMember({"ct", "ct_euler", "omni", "dead_reckoning"}));
  odom_cmd->add_option("--config", odom_config, "YAML with an odometry: section");
  odom_cmd->add_option("--wheels-csv", odom.job.wheels_csv, "W.csv with t,v_left,v_right");
  odom_cmd->add_option("--imu-csv", odom.job.imu_csv, "I.csv with t,yaw_rate");
  odom_cmd->add_option("--wheel-topic", odom.job.wheel_topic,
                       "JointState or Odometry topic (default: /wheels or the only one)");
  odom_cmd->add_option("--imu-topic", odom.job.imu_topic,
                       "Imu topic (default: the only one), or none");
  odom_cmd->add_option("--truth-topic", odom.job.truth_topic, "Odometry topic for --truth-csv")
      ->capture_default_str();
  odom_cmd->add_option("--truth-csv", odom.job.truth_csv,
                       "Also write the truth topic as t,x,y,yaw here");
  odom_cmd->add_flag("--json", odom.json, "Print statistics as JSON");

  dispel::apps::EvalTrajectoryOptions eval_trajectory;
  CLI::App* eval_trajectory_cmd = app.add_subcommand(
      "eval-trajectory", "Compare a trajectory CSV with a true one (t,x,y,yaw columns)");
  eval_trajectory_cmd->add_option("--truth", eval_trajectory.truth, "TRUTH.csv")->required();
  eval_trajectory_cmd->add_option("--estimate", eval_trajectory.estimate, "TRAJECTORY.csv")
      ->required();
  eval_trajectory_cmd
      ->add_option("--align-first", eval_trajectory.align_first_m,
                   "Move the estimate rigidly onto the truth over its first METRES of path "
                   "(for a truth in another frame, e.g. GPS)")
      ->check(CLI::NonNegativeNumber);
  eval_trajectory_cmd->add_flag("--json", eval_trajectory.json, "Print JSON");
#endif

#ifdef DISPEL_HAVE_SLAM
  dispel::apps::SlamCommandOptions slam;
  std::string slam_ini;
  slam.job.scan_topic.clear();
  CLI::App* slam_cmd = app.add_subcommand(
      "slam", "Run MRPT's ICP-SLAM over a recording's scans and odometry; write its trajectory");
  slam_cmd->add_option("input", slam.job.input, "IN.bag (raw, or filtered by dispel filter)")
      ->required();
  slam_cmd->add_option("-o,--output", slam.output, "TRAJECTORY.csv to write (t,x,y,yaw)")
      ->required();
  slam_cmd->add_option("--scan-topic", slam.job.scan_topic,
                       "LaserScan topic (default: /scan_filtered if the bag has it, else /scan)");
  slam_cmd->add_option("--odom-topic", slam.job.odom_topic, "Odometry topic (the motion input)")
      ->capture_default_str();
  slam_cmd->add_option("--engine-config", slam_ini,
                       "MRPT .ini over the defaults ([MappingApplication], [ICP], ...)");
  slam_cmd->add_option("--odom-csv", slam.odom_csv,
                       "Also write the odometry at the same scans as t,x,y,yaw here");
  slam_cmd->add_option("--save-map", slam.save_map,
                       "Also write the map as map_server MAP.yaml + MAP.pgm");
  std::vector<double> slam_initial_pose;
  slam_cmd->add_option("--map", slam.map,
                       "Localise in this map_server MAP.yaml (particle filter) instead of SLAM");
  slam_cmd
      ->add_option("--initial-pose", slam_initial_pose,
                   "With --map: the robot's pose X Y YAW (m, m, rad) in the map at the first "
                   "scan (default: the odometry pose)")
      ->expected(3);
  slam_cmd->add_option("--particles", slam.localization.filter.particles, "With --map: particles")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  slam_cmd
      ->add_option("--seed", slam.localization.filter.seed,
                   "With --map: the particle filter's random seed (same seed, same trajectory)")
      ->capture_default_str();
  slam_cmd->add_flag("--json", slam.json, "Print the counters as JSON");

  dispel::apps::ExperimentCommandOptions experiment;
  std::string experiment_config, experiment_ini;
  double experiment_duration = 0.0, experiment_yaw_deg = 10.0;
  CLI::App* experiment_cmd = app.add_subcommand(
      "experiment",
      "Simulate a scenario over many seeds; run SLAM on the raw, filtered and oracle scans and "
      "compare each with the truth");
  experiment_cmd->add_option("scenario", experiment.job.scenario, "SCENARIO.yaml")->required();
  experiment_cmd->add_option("--seeds", experiment.job.seeds, "How many seeds")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  experiment_cmd->add_option("--first-seed", experiment.job.first_seed, "The first seed")
      ->capture_default_str();
  CLI::Option* experiment_duration_opt = experiment_cmd->add_option(
      "--duration", experiment_duration, "Seconds per run (default: the scenario's)");
  experiment_duration_opt->check(CLI::PositiveNumber);
  experiment_cmd->add_option("--out", experiment.out_dir,
                             "Write runs.csv, summary.json and the trajectories here");
  experiment_cmd->add_flag("--json", experiment.json, "Print the summary as JSON");
  experiment_cmd->add_option("--config", experiment_config,
                             "The filter's YAML configuration (default: dispel's defaults)");
  experiment_cmd->add_option("--engine-config", experiment_ini, "MRPT .ini over the defaults");
  experiment_cmd
      ->add_option("--diverged-at", experiment.job.divergence_position_m,
                   "A run diverged when its position error ever exceeds this (m)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  experiment_cmd
      ->add_option("--diverged-at-yaw", experiment_yaw_deg,
                   "... or its yaw error ever exceeds this (deg)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  experiment_cmd->add_flag("--keep-bags", experiment.job.keep_bags,
                           "Keep the bags of each seed under OUT/bags/ (needs --out)");
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
    if (*odom_cmd) {
      if (!odom_config.empty()) odom.job.config_path = odom_config;
      if (!odom_model.empty()) odom.job.model = odom_model;
      return dispel::apps::run_odom(odom);
    }
    if (*eval_trajectory_cmd) return dispel::apps::run_eval_trajectory(eval_trajectory);
    if (*render_cmd) {
      if (!render_config.empty()) render.job.config_path = render_config;
      if (from_opt->count() > 0) render.job.from_s = render_from;
      if (to_opt->count() > 0) render.job.to_s = render_to;
      return dispel::apps::run_render(render);
    }
#endif
#ifdef DISPEL_HAVE_SLAM
    if (*slam_cmd) {
      if (!slam_ini.empty()) slam.job.engine_config_ini = slam_ini;
      if (!slam_initial_pose.empty()) {
        if (slam.map.empty()) {
          std::cerr << "dispel slam: --initial-pose needs --map\n";
          return 1;
        }
        slam.localization.initial_pose =
            dispel::Pose2{slam_initial_pose[0], slam_initial_pose[1], slam_initial_pose[2]};
      }
      return dispel::apps::run_slam(slam);
    }
    if (*experiment_cmd) {
      if (!experiment_config.empty()) experiment.job.filter_config = experiment_config;
      if (!experiment_ini.empty()) experiment.job.engine_config_ini = experiment_ini;
      if (experiment_duration_opt->count() > 0) experiment.job.duration_s = experiment_duration;
      experiment.job.divergence_yaw_rad = experiment_yaw_deg * 3.14159265358979323846 / 180.0;
      if (experiment.job.keep_bags && experiment.out_dir.empty()) {
        std::cerr << "dispel experiment: --keep-bags needs --out\n";
        return 1;
      }
      return dispel::apps::run_experiment(experiment);
    }
#endif
  } catch (const std::exception& e) {
    std::cerr << "dispel: " << e.what() << "\n";
    return 1;
  }
  std::cerr << "dispel: no command given\n" << app.help();
  return 1;
}
