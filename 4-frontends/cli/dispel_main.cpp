// The dispel command line. Each subcommand is a thin adapter over the libraries.
#include <CLI/CLI.hpp>
#include <csignal>
#include <exception>
#include <iostream>

#include "bench_command.hpp"
#include "cli_validators.hpp"
#ifdef DISPEL_HAVE_IO
#include "cli_common.hpp"
#include "filter_command.hpp"
#include "odom_commands.hpp"
#include "render_command.hpp"
#include "sim_commands.hpp"
#endif
#ifdef DISPEL_HAVE_SLAM
#include "slam_cli.hpp"
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
      "bench",
      "Measure segmentation, the whole filter (the thesis's and dispel's default), the free-space "
      "grid, the reference DBSCAN and an odometry step, at 768 to 1000000 beams");
  bench_cmd->add_flag("--json", bench.json,
                      R"(Print {"results": [{"name", "beams", "median_ns"}]})");
  bench_cmd
      ->add_option("--filter", bench.filter,
                   "Regular expression on case names: segmentation, filter_pipeline, "
                   "filter_pipeline_default, filter_pipeline_sparse, free_space_add_scan, "
                   "reference_dbscan, "
                   "reference_dbscan_grid, "
                   "odometry_ct_step, odometry_omni_step (e.g. segmentation/1617)")
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
      "filter",
      "Remove moving objects from the scans of a recording (ROS 1 bag, rosbag2 MCAP, MRPT rawlog "
      "or CARMEN log)");
  filter_cmd
      ->add_option("input", filter.job.input, "IN.bag, an MRPT IN.rawlog, or a CARMEN .log/.clf")
      ->required();
  filter_cmd->add_option("-o,--output", filter.job.output, "OUT.bag to write")->required();
  // filter and clean: the online filter's configuration, the topics and the sensor.
  const auto add_filter_options = [](CLI::App* command, dispel::jobs::FilterJobOptions& job,
                                     std::string& config) {
    command->add_option("--config", config, "YAML configuration (see config/default.yaml)");
    command->add_option("--scan-topic", job.scan_topic, "LaserScan topic")->capture_default_str();
    command
        ->add_option("--odom-topic", job.odom_topic,
                     "Odometry topic; none: laser-only (also when the recording has none)")
        ->capture_default_str();
    command->add_flag("--static-sensor", job.static_sensor,
                      "The sensor does not move (no odometry needed)");
    command->add_flag("--scale-to-scanner", job.scale_to_scanner,
                      "Carry N_min, L_d and L_s over from the thesis's scanner to this one");
  };
  // filter, clean and convert: how the output is compressed.
  const auto add_compression_option = [](CLI::App* command, std::string& compression) {
    command
        ->add_option("--compression", compression,
                     "Output compression: bz2 or lz4 for a ROS 1 bag, zstd or lz4 for MCAP")
        ->check(CLI::IsMember({"none", "bz2", "lz4", "zstd"}))
        ->capture_default_str();
  };
  add_filter_options(filter_cmd, filter.job, config_path);
  filter_cmd->add_option("--stats", filter.stats_path, "Write statistics as JSON here");
  filter_cmd
      ->add_option("--resident-heap-mb", filter.resident_heap_mb,
                   "Heap made resident before the first scan, so that no scan waits for memory "
                   "touched the first time; 0: none")
      ->check(CLI::Range(0, 4096))
      ->capture_default_str();
  add_compression_option(filter_cmd, filter.compression);
  std::string filter_format = "auto";
  // filter and convert: the output's format, by its name or as asked.
  const auto add_format_option = [](CLI::App* command, std::string& format) {
    command
        ->add_option("--format", format,
                     "Output format: auto (by name: .bag ROS 1; .mcap, .db3 or a folder "
                     "rosbag2), ros1, mcap or sqlite3")
        ->check(CLI::IsMember({"auto", "ros1", "mcap", "sqlite3"}))
        ->capture_default_str();
  };
  add_format_option(filter_cmd, filter_format);

  dispel::apps::CleanCommandOptions clean;
  std::string clean_config;
  CLI::App* clean_cmd = app.add_subcommand(
      "clean",
      "Offline: remove from a whole recording what moved, from the first scan it was seen until "
      "it last moved (writes <scan topic>_clean; docs/clean.md)");
  clean_cmd
      ->add_option("input", clean.job.filter.input,
                   "IN: .bag, .mcap, .db3, a rosbag2 folder, .rawlog")
      ->required();
  clean_cmd->add_option("-o,--output", clean.job.filter.output, "OUT to write")->required();
  add_filter_options(clean_cmd, clean.job.filter, clean_config);
  clean_cmd->add_option("--stats", clean.stats_path,
                        "Write statistics (and each object) as JSON here");
  add_compression_option(clean_cmd, clean.compression);
  clean_cmd
      ->add_option("--moving-scans", clean.job.clean.moving_min_scans,
                   "An object moved when the online filter found it moving in this many scans...")
      ->capture_default_str();
  clean_cmd
      ->add_option("--moving-travel", clean.job.clean.moving_min_travel_m,
                   "...and it travelled this far (m) while found moving")
      ->capture_default_str();
  clean_cmd
      ->add_option(
          "--moved-from", clean.job.clean.moved_from_m,
          "...and its beams in other scans are removed within this distance (m) of where it moved")
      ->capture_default_str();
  clean_cmd
      ->add_option("--leg-walk", clean.job.clean.leg_walk_m,
                   "Legs at range (beams in no object) linked from scan to scan are removed when "
                   "they walked this far (m); 0: off")
      ->capture_default_str();
  clean_cmd
      ->add_option("--leg-gap", clean.job.clean.leg_max_gap_s,
                   "...linking a leg across at most this time (s) without it")
      ->capture_default_str();
  clean_cmd
      ->add_option("--through-scans", clean.job.clean.through_min_scans,
                   "A small thing (or no object) is removed when this many scans saw through its "
                   "place, 1-20 s later or earlier, before one hit it (--static-sensor: in a "
                   "row, past scans that hit it); 0: off; -1: 2 with --static-sensor, else off")
      ->capture_default_str();
  clean_cmd
      ->add_option("--through-horizon", clean.job.clean.through_horizon_s,
                   "...within this many seconds of it")
      ->capture_default_str();
  clean_cmd
      ->add_option("--free-margin", clean.job.clean.free_margin_m,
                   "Seeing through a place: returns from at least this far (m) beyond it")
      ->capture_default_str();
  clean_cmd
      ->add_option("--max-width", clean.job.clean.max_width_m,
                   "The cleaner removes only objects at most this wide (m), and beams in no object")
      ->capture_default_str();
  std::string clean_format = "auto";
  add_format_option(clean_cmd, clean_format);

  dispel::jobs::ConvertJobOptions convert;
  std::string convert_compression = "none";
  CLI::App* convert_cmd = app.add_subcommand(
      "convert",
      "Write a recording in another format: ROS 1 bag (.bag) or rosbag2 (.mcap, .db3, or a bag "
      "folder)");
  convert_cmd
      ->add_option("input", convert.input, "IN: .bag, .mcap, .db3, a rosbag2 folder, .rawlog")
      ->required();
  convert_cmd
      ->add_option("-o,--output", convert.output, "OUT.bag, OUT.mcap, OUT.db3 or a new folder OUT")
      ->required();
  add_compression_option(convert_cmd, convert_compression);
  std::string convert_format = "auto";
  add_format_option(convert_cmd, convert_format);

  dispel::apps::SimOptions sim;
  CLI::App* sim_cmd =
      app.add_subcommand("sim", "Simulate a scenario into a bag with ground truth per beam");
  sim_cmd->add_option("scenario", sim.scenario, "SCENARIO.yaml (see config/scenarios/)")
      ->required();
  sim_cmd->add_option("-o,--output", sim.output, "OUT.bag to write")->required();
  sim_cmd->add_option("--seed", sim.seed, "Random seed (same seed, same bag)")
      ->capture_default_str();
  sim_cmd->add_option("--duration", sim.duration_s, "Seconds to simulate (default: the scenario's)")
      ->check(dispel::apps::positive_number());

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
  eval_cmd->add_flag("--map", evaluation.map,
                     "Also the map quality: occupancy grids from the true poses, the result's "
                     "and the unfiltered scans' against the oracle's (cells wrongly occupied, "
                     "cells lost)");
  eval_cmd
      ->add_option("--map-resolution", evaluation.map_resolution_m, "Map cell edge (m) for --map")
      ->check(dispel::apps::positive_number())
      ->capture_default_str();

  dispel::apps::RenderCommandOptions render;
  std::string render_config;
  double render_from = 0.0, render_to = 0.0;
  CLI::App* render_cmd = app.add_subcommand(
      "render", "Draw a recording (filtered or not) as a map of all scans or one scan's objects");
  render_cmd->add_option("input", render.job.input, "IN.bag or an MRPT IN.rawlog")->required();
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
      ->check(dispel::apps::non_negative_number());
  eval_trajectory_cmd->add_flag("--json", eval_trajectory.json, "Print JSON");
#endif

#ifdef DISPEL_HAVE_SLAM
  // Defined here for parsing and help; run by dispel-slam (which links MRPT, slow to load).
  dispel::apps::SlamCli slam;
  dispel::apps::add_slam_commands(app, slam);
#endif

  const auto one_line = [](const std::string& what) {
#ifdef DISPEL_HAVE_IO
    return dispel::apps::error_line(what);
#else
    return what;
#endif
  };
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    // One line, the usage exit code (2) for every kind of bad command line.
    std::string where = "dispel";
    for (const CLI::App* sub : app.get_subcommands()) where += " " + sub->get_name();
    std::string what = e.what();
    while (!what.empty() && (what.back() == '\n' || what.back() == ' ')) what.pop_back();
    std::cerr << where << ": " << one_line(what) << " (see " << where << " --help)\n";
    return 2;
  }
#ifdef DISPEL_HAVE_IO
  // A file-size limit (ulimit -f) makes a write fail with EFBIG, reported as any write error,
  // instead of killing the program with its output half-written.
  std::signal(SIGXFSZ, SIG_IGN);
  for (const CLI::App* sub : app.get_subcommands()) {
    try {
      dispel::apps::check_command_line(*sub);
    } catch (const dispel::apps::UsageError& e) {
      std::cerr << "dispel " << sub->get_name() << ": " << one_line(e.what()) << " (see dispel "
                << sub->get_name() << " --help)\n";
      return dispel::apps::kUsageExitCode;
    } catch (const std::exception& e) {
      std::cerr << "dispel " << sub->get_name() << ": " << one_line(e.what()) << "\n";
      return 1;
    }
  }
#endif
  try {
    if (*bench_cmd) return dispel::apps::run_bench(bench);
#ifdef DISPEL_HAVE_IO
    if (*filter_cmd) {
      if (!config_path.empty()) filter.job.config_path = config_path;
      filter.job.format = dispel::jobs::recording_format_named(filter_format);
      return dispel::apps::run_filter(filter);
    }
    if (*clean_cmd) {
      if (!clean_config.empty()) clean.job.filter.config_path = clean_config;
      clean.job.filter.format = dispel::jobs::recording_format_named(clean_format);
      return dispel::apps::run_clean(clean);
    }
    if (*sim_cmd) return dispel::apps::run_sim(sim);
    if (*convert_cmd) {
      convert.compression = dispel::apps::compression_named(convert_compression);
      convert.format = dispel::jobs::recording_format_named(convert_format);
      return dispel::apps::run_convert(convert);
    }
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
    if (dispel::apps::slam_command_chosen(slam)) return dispel::apps::exec_dispel_slam(argc, argv);
#endif
  } catch (const std::exception& e) {
    std::cerr << "dispel: " << one_line(e.what()) << "\n";
    return 1;
  }
  std::cerr << "dispel: no command given\n" << app.help();
  return 1;
}
