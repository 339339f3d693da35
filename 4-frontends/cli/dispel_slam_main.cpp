// dispel-slam: `dispel slam` and `dispel experiment`, which `dispel` hands over to this program
// so that only they load MRPT. Run directly it takes the same arguments.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "slam_cli.hpp"

#ifndef DISPEL_VERSION
#define DISPEL_VERSION "unknown"
#endif

int main(int argc, char** argv) {
  CLI::App app{"dispel slam and dispel experiment (SLAM and localisation through MRPT)"};
  app.set_version_flag("--version", DISPEL_VERSION);
  app.require_subcommand(1, 1);
  app.name("dispel");
  dispel::apps::SlamCli cli;
  dispel::apps::add_slam_commands(app, cli);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    return dispel::apps::run_slam_command(cli);
  } catch (const std::exception& e) {
    std::cerr << "dispel: " << e.what() << "\n";
    return 1;
  }
}
