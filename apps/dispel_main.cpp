// The dispel command line. Each subcommand is a thin adapter over the libraries.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "bench_command.hpp"

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

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (*bench_cmd) return dispel::apps::run_bench(bench);
  } catch (const std::exception& e) {
    std::cerr << "dispel: " << e.what() << "\n";
    return 1;
  }
  std::cerr << "dispel: no command given\n" << app.help();
  return 1;
}
