#include "slam_command.hpp"

#include <stdlib.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <system_error>

#include "dispel/io/atomic_file.hpp"
#include "dispel/io/csv.hpp"
#include "dispel/io/text.hpp"
#include "dispel/jobs/filter_job.hpp"
#include "dispel/jobs/odom_job.hpp"
#include "dispel/slam/grid_map.hpp"

namespace dispel::apps {

namespace {

// The counters both modes share, and the final pose.
// Runs @p run (either mode), writes its trajectory (and the odometry, when asked), then
// @p extra_output; false with a one-line message on failure.
template <typename Result, typename Run, typename Extra>
bool run_and_write(const SlamCommandOptions& o, Result& r, const Run& run,
                   const Extra& extra_output) {
  try {
    r = run();
    extra_output(r);
    if (!o.odom_csv.empty()) io::write_trajectory_csv(o.odom_csv, r.odometry);
    io::write_trajectory_csv(o.output, r.trajectory);
    return true;
  } catch (const std::exception& e) {
    std::cerr << "dispel slam: " << io::one_line(e.what()) << "\n";
    return false;
  }
}

template <typename Result>
nlohmann::ordered_json counters_json(const char* mode, const Result& r) {
  const eval::TrajectoryPoint& last = r.trajectory.back();
  nlohmann::ordered_json j;
  j["mode"] = mode;
  j["scan_topic"] = r.scan_topic;
  j["scans"] = r.scans;
  j["scans_used"] = r.scans_used;
  j["scans_no_odometry"] = r.scans_no_odometry;
  j["scans_bad"] = r.scans_bad;
  j["beams_invalid"] = r.beams_invalid;
  j["odometry_refused"] = r.odometry_refused;
  j["final"] = {{"t", last.t_s}, {"x", last.x_m}, {"y", last.y_m}, {"yaw", last.yaw_rad}};
  return j;
}

int run_localization(const SlamCommandOptions& o) {
  slam::LocalizationResult r;
  slam::LocalizationOptions l = o.localization;
  l.input = o.job.input;
  l.scan_topic = o.job.scan_topic;
  l.odom_topic = o.job.odom_topic;
  l.map_yaml = o.map;
  if (!run_and_write(
          o, r, [&] { return slam::run_pf_localization(l); }, [](const auto&) {})) {
    return 1;
  }
  const eval::TrajectoryPoint& last = r.trajectory.back();
  if (o.json) {
    nlohmann::ordered_json j = counters_json("localization", r);
    j["final_position_std_m"] = r.position_std_m.back();
    std::cout << j.dump(2) << std::endl;
    return 0;
  }
  std::printf(
      "dispel slam (MRPT particle-filter localisation in %s, %d particles, seed %llu, on %s): "
      "%lld of %lld scans used, %lld beams invalid; final pose x %.3f m, y %.3f m, yaw %.4f rad "
      "(std %.3f m)\nwrote %s (%zu rows)\n",
      o.map.c_str(), l.filter.particles, static_cast<unsigned long long>(l.filter.seed),
      r.scan_topic.c_str(), static_cast<long long>(r.scans_used), static_cast<long long>(r.scans),
      static_cast<long long>(r.beams_invalid), last.x_m, last.y_m, last.yaw_rad,
      r.position_std_m.back(), o.output.c_str(), r.trajectory.size());
  return 0;
}

}  // namespace

int run_slam(const SlamCommandOptions& o) {
  if (!o.map.empty()) {
    if (!o.save_map.empty()) {
      std::cerr << "dispel slam: --save-map builds a map by SLAM; it cannot go with --map\n";
      return 1;
    }
    return run_localization(o);
  }
  slam::SlamResult r;
  const auto save_map = [&](const slam::SlamResult& result) {
    if (!o.save_map.empty()) slam::write_map_yaml(result.grid, o.save_map);
  };
  if (!run_and_write(
          o, r, [&] { return slam::run_icp_slam_full(o.job); }, save_map))
    return 1;
  const eval::TrajectoryPoint& last = r.trajectory.back();
  if (o.json) {
    nlohmann::ordered_json j = counters_json("slam", r);
    j["map_points"] = r.map_points.size();
    std::cout << j.dump(2) << std::endl;
    return 0;
  }
  std::printf(
      "dispel slam (MRPT ICP-SLAM on %s): %lld of %lld scans used (%lld without odometry, %lld "
      "unusable), %lld beams invalid; %zu map points; final pose x %.3f m, y %.3f m, yaw %.4f "
      "rad\nwrote %s (%zu rows)%s%s\n",
      r.scan_topic.c_str(), static_cast<long long>(r.scans_used), static_cast<long long>(r.scans),
      static_cast<long long>(r.scans_no_odometry), static_cast<long long>(r.scans_bad),
      static_cast<long long>(r.beams_invalid), r.map_points.size(), last.x_m, last.y_m,
      last.yaw_rad, o.output.c_str(), r.trajectory.size(), o.save_map.empty() ? "" : ", ",
      o.save_map.c_str());
  return 0;
}

}  // namespace dispel::apps

namespace dispel::apps {
namespace {

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

// A statistic over no values (a rejection rate where nothing moved) is null.
nlohmann::ordered_json statistic_json(const slam::Statistic& s) {
  if (s.count == 0) return nullptr;
  return {{"mean", s.mean}, {"std", s.std}, {"median", s.median}};
}

nlohmann::ordered_json summary_json(const slam::ExperimentResult& r,
                                    const std::vector<slam::VariantSummary>& summary,
                                    const slam::ExperimentOptions& o) {
  nlohmann::ordered_json j;
  j["scenario"] = r.scenario_name;
  j["seeds"] = r.seeds;
  j["duration_s"] = r.duration_s;
  j["range_limit_m"] = r.range_limit_m;
  j["divergence"] = {{"max_position_error_m", o.divergence_position_m},
                     {"max_yaw_error_rad", o.divergence_yaw_rad}};
  nlohmann::ordered_json variants = nlohmann::ordered_json::object();
  nlohmann::ordered_json reference = nlohmann::ordered_json::object();
  nlohmann::ordered_json thesis = nlohmann::ordered_json::object();
  nlohmann::ordered_json localization = nlohmann::ordered_json::object();
  for (const slam::VariantSummary& s : summary) {
    nlohmann::ordered_json v;
    v["runs"] = s.runs;
    v["rmse_position_m"] = statistic_json(s.rmse_position_m);
    v["rmse_x_m"] = statistic_json(s.rmse_x_m);
    v["rmse_y_m"] = statistic_json(s.rmse_y_m);
    v["rmse_yaw_rad"] = statistic_json(s.rmse_yaw_rad);
    v["max_position_error_m"] = statistic_json(s.max_position_error_m);
    v["diverged"] = s.diverged;
    if (s.preservation_rate.count > 0) {
      v["preservation_rate"] = statistic_json(s.preservation_rate);
      v["rejection_rate"] = statistic_json(s.rejection_rate);
      v["still_removed_rate"] = statistic_json(s.still_removed_rate);
      v["still_moves_later_removed_rate"] = statistic_json(s.still_moves_later_removed_rate);
    }
    if (s.map_wrongly_occupied_share.count > 0) {
      v["map"] = {{"wrongly_occupied_share", statistic_json(s.map_wrongly_occupied_share)},
                  {"lost_share", statistic_json(s.map_lost_share)}};
    }
    const char* name = slam::variant_name(s.variant);
    if (slam::is_localization_variant(s.variant)) {
      localization[name] = v;
    } else if (!slam::is_cut_slam_variant(s.variant)) {
      reference[name] = v;
    } else {
      variants[name] = v;
      thesis[name] = {{"rmse_x_m", statistic_json(s.full_range_rmse_x_m)},
                      {"rmse_y_m", statistic_json(s.full_range_rmse_y_m)},
                      {"rmse_yaw_rad", statistic_json(s.full_range_rmse_yaw_rad)}};
    }
  }
  j["variants"] = variants;
  j["reference"] = reference;
  j["against_full_range"] = thesis;
  if (!localization.empty()) j["localization"] = localization;
  return j;
}

// JSON has no NaN: a rate the variant does not have is null.
nlohmann::ordered_json number_or_null(double v) {
  return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
}

nlohmann::ordered_json errors_json(const eval::TrajectoryErrors& e) {
  return {{"rmse_position_m", e.rmse_position_m},
          {"rmse_x_m", e.rmse_x_m},
          {"rmse_y_m", e.rmse_y_m},
          {"rmse_yaw_rad", e.rmse_yaw_rad},
          {"max_position_error_m", e.max_position_error_m},
          {"max_yaw_error_rad", e.max_yaw_error_rad},
          {"final_position_error_m", e.final_position_error_m}};
}

// The per-run figures: {"runs": [{"seed", "variant", "against_truth": {...}, "diverged",
// "against_full_range": {...} or null, "preservation_rate", "rejection_rate"}]}.
nlohmann::ordered_json runs_json(const slam::ExperimentResult& r) {
  nlohmann::ordered_json runs = nlohmann::ordered_json::array();
  for (const slam::ExperimentRun& run : r.runs) {
    nlohmann::ordered_json j;
    j["seed"] = run.seed;
    j["variant"] = slam::variant_name(run.variant);
    j["against_truth"] = errors_json(run.against_truth);
    j["diverged"] = run.diverged;
    j["against_full_range"] =
        run.against_full_range ? errors_json(*run.against_full_range) : nlohmann::ordered_json();
    j["preservation_rate"] = number_or_null(run.preservation_rate);
    j["rejection_rate"] = number_or_null(run.rejection_rate);
    j["still_removed_rate"] = number_or_null(run.still_removed_rate);
    j["still_moves_later_removed_rate"] = number_or_null(run.still_moves_later_removed_rate);
    j["map"] = run.map
                   ? nlohmann::ordered_json{{"oracle_occupied_cells", run.map->reference_occupied},
                                            {"occupied_cells", run.map->evaluated_occupied},
                                            {"wrongly_occupied_cells", run.map->wrongly_occupied},
                                            {"lost_cells", run.map->lost}}
                   : nlohmann::ordered_json();
    runs.push_back(j);
  }
  return {{"scenario", r.scenario_name}, {"runs", runs}};
}

// runs.csv, runs.json, summary.json and every trajectory, each written whole or not at all.
void write_outputs(const std::string& dir, const slam::ExperimentResult& r,
                   const nlohmann::ordered_json& summary) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(fs::path(dir) / "trajectories", ec);
  if (ec) throw jobs::JobError(dir + ": cannot create the directory (" + ec.message() + ")");
  {
    io::AtomicFile file((fs::path(dir) / "runs.csv").string());
    std::FILE* f = std::fopen(file.temp_path().c_str(), "w");
    if (f == nullptr) throw jobs::JobError(dir + "/runs.csv: cannot write the file");
    std::fprintf(f,
                 "seed,variant,rmse_position_m,rmse_x_m,rmse_y_m,rmse_yaw_rad,"
                 "max_position_error_m,max_yaw_error_rad,final_position_error_m,diverged,"
                 "full_range_rmse_x_m,full_range_rmse_y_m,full_range_rmse_yaw_rad,"
                 "preservation_rate,rejection_rate,still_removed_rate,"
                 "still_moves_later_removed_rate,oracle_occupied_cells,wrongly_occupied_cells,"
                 "lost_cells\n");
    for (const slam::ExperimentRun& run : r.runs) {
      const eval::TrajectoryErrors& e = run.against_truth;
      std::fprintf(f, "%llu,%s,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%d,",
                   static_cast<unsigned long long>(run.seed), slam::variant_name(run.variant),
                   e.rmse_position_m, e.rmse_x_m, e.rmse_y_m, e.rmse_yaw_rad,
                   e.max_position_error_m, e.max_yaw_error_rad, e.final_position_error_m,
                   run.diverged ? 1 : 0);
      if (run.against_full_range) {
        std::fprintf(f, "%.6f,%.6f,%.6f,", run.against_full_range->rmse_x_m,
                     run.against_full_range->rmse_y_m, run.against_full_range->rmse_yaw_rad);
      } else {
        std::fprintf(f, ",,,");
      }
      const auto rate = [f](double v, const char* end) {
        if (std::isfinite(v)) std::fprintf(f, "%.6f", v);
        std::fputs(end, f);
      };
      rate(run.preservation_rate, ",");
      rate(run.rejection_rate, ",");
      rate(run.still_removed_rate, ",");
      rate(run.still_moves_later_removed_rate, ",");
      if (run.map) {
        std::fprintf(f, "%lld,%lld,%lld\n", static_cast<long long>(run.map->reference_occupied),
                     static_cast<long long>(run.map->wrongly_occupied),
                     static_cast<long long>(run.map->lost));
      } else {
        std::fprintf(f, ",,\n");
      }
    }
    const bool ok = std::fflush(f) == 0 && std::ferror(f) == 0;
    std::fclose(f);
    if (!ok) throw jobs::JobError(dir + "/runs.csv: writing failed");
    file.commit();
  }
  const auto write_json = [&](const char* name, const nlohmann::ordered_json& j) {
    io::AtomicFile file((fs::path(dir) / name).string());
    std::ofstream out(file.temp_path());
    out << j.dump(2) << "\n";
    out.close();
    if (!out) throw jobs::JobError(dir + "/" + name + ": writing failed");
    file.commit();
  };
  write_json("summary.json", summary);
  write_json("runs.json", runs_json(r));
  for (std::size_t k = 0; k < r.seeds.size(); ++k) {
    const std::string prefix =
        (fs::path(dir) / "trajectories" / ("seed_" + std::to_string(r.seeds[k]) + "_")).string();
    io::write_trajectory_csv(prefix + "truth.csv", r.truth[k]);
  }
  for (const slam::ExperimentRun& run : r.runs) {
    io::write_trajectory_csv(
        (fs::path(dir) / "trajectories" /
         ("seed_" + std::to_string(run.seed) + "_" + slam::variant_name(run.variant) + ".csv"))
            .string(),
        run.trajectory);
  }
}

std::string mean_std(const slam::Statistic& s, double scale, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f ± %.*f", decimals, s.mean * scale, decimals, s.std * scale);
  return buf;
}

void print_tables(const slam::ExperimentResult& r, const std::vector<slam::VariantSummary>& summary,
                  const slam::ExperimentOptions& o) {
  std::printf(
      "\n%s, %zu seeds, %.0f s each, range cut to %.1f m; RMSE against the true pose, mean ± std "
      "over seeds\ndiverged: the position error ever above %.2f m or the yaw error above %.1f "
      "deg\n\n",
      r.scenario_name.c_str(), r.seeds.size(), r.duration_s, r.range_limit_m,
      o.divergence_position_m, o.divergence_yaw_rad * kRadToDeg);
  std::printf("%-25s %-17s %-17s %-17s %-15s %-17s %s\n", "variant", "position (m)", "x (m)",
              "y (m)", "yaw (deg)", "largest (m)", "diverged");
  for (const slam::VariantSummary& s : summary) {
    std::printf("%-25s %-17s %-17s %-17s %-15s %-17s %d of %d\n", slam::variant_name(s.variant),
                mean_std(s.rmse_position_m, 1.0, 3).c_str(), mean_std(s.rmse_x_m, 1.0, 3).c_str(),
                mean_std(s.rmse_y_m, 1.0, 3).c_str(),
                mean_std(s.rmse_yaw_rad, kRadToDeg, 2).c_str(),
                mean_std(s.max_position_error_m, 1.0, 3).c_str(), s.diverged, s.runs);
  }
  std::printf("\nThe thesis's protocol (its Table 4.1): RMSE against the full-range SLAM run\n\n");
  std::printf("%-14s %-17s %-17s %-15s\n", "variant", "x (m)", "y (m)", "yaw (deg)");
  for (const slam::VariantSummary& s : summary) {
    if (!slam::is_cut_slam_variant(s.variant)) continue;
    std::printf("%-14s %-17s %-17s %-15s\n", slam::variant_name(s.variant),
                mean_std(s.full_range_rmse_x_m, 1.0, 3).c_str(),
                mean_std(s.full_range_rmse_y_m, 1.0, 3).c_str(),
                mean_std(s.full_range_rmse_yaw_rad, kRadToDeg, 2).c_str());
  }
  std::printf(
      "\nThe maps: each run's occupancy grid against oracle_static's (no people; cells matched "
      "within 0.1 m),\nas shares of its occupied cells, mean ± std over seeds\n\n");
  std::printf("%-14s %-21s %-17s\n", "variant", "wrongly occupied", "lost");
  for (const slam::VariantSummary& s : summary) {
    if (s.map_wrongly_occupied_share.count == 0) continue;
    std::printf("%-14s %-21s %-17s\n", slam::variant_name(s.variant),
                mean_std(s.map_wrongly_occupied_share, 1.0, 4).c_str(),
                mean_std(s.map_lost_share, 1.0, 4).c_str());
  }
  for (const slam::VariantSummary& s : summary) {
    if (s.preservation_rate.count == 0) continue;
    std::printf("\n%s: kept %.4f of the static beams", slam::variant_name(s.variant),
                s.preservation_rate.mean);
    if (s.rejection_rate.count > 0) {
      std::printf(", removed %.4f of the moving", s.rejection_rate.mean);
    } else {
      std::printf("; nothing moved");
    }
    if (s.still_removed_rate.count > 0) {
      std::printf(" and %.4f of those of people standing still", s.still_removed_rate.mean);
      if (s.still_moves_later_removed_rate.count > 0) {
        std::printf(" (%.4f of those seen moving later)", s.still_moves_later_removed_rate.mean);
      }
    }
  }
  std::printf("\n");
}

}  // namespace

int run_experiment(const ExperimentCommandOptions& options) {
  namespace fs = std::filesystem;
  slam::ExperimentOptions o = options.job;
  std::string temp_dir;
  if (!options.out_dir.empty()) {
    o.work_dir = (fs::path(options.out_dir) / "bags").string();
  } else {
    std::string pattern = (fs::temp_directory_path() / "dispel-experiment-XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr) {
      std::cerr << "dispel experiment: cannot create a temporary directory\n";
      return 1;
    }
    temp_dir = o.work_dir = pattern;
  }
  int status = 0;
  try {
    const slam::ExperimentResult r = slam::run_experiment(o, [&](const slam::ExperimentRun& run) {
      if (options.json) return;
      std::fprintf(stderr, "seed %llu %-25s RMSE %.3f m, %.2f deg%s\n",
                   static_cast<unsigned long long>(run.seed), slam::variant_name(run.variant),
                   run.against_truth.rmse_position_m, run.against_truth.rmse_yaw_rad * kRadToDeg,
                   run.diverged ? " (diverged)" : "");
    });
    const std::vector<slam::VariantSummary> summary = slam::summarise(r);
    const nlohmann::ordered_json j = summary_json(r, summary, o);
    if (!options.out_dir.empty()) write_outputs(options.out_dir, r, j);
    if (options.json) {
      std::cout << j.dump(2) << std::endl;
    } else {
      print_tables(r, summary, o);
      if (!options.out_dir.empty()) {
        std::printf("wrote %s/runs.csv, runs.json, summary.json, trajectories/\n",
                    options.out_dir.c_str());
      }
    }
  } catch (const std::exception& e) {
    std::cerr << "dispel experiment: " << io::one_line(e.what()) << "\n";
    status = 1;
  }
  if (!temp_dir.empty()) {
    std::error_code ignored;
    fs::remove_all(temp_dir, ignored);
  } else if (!options.job.keep_bags && !options.out_dir.empty()) {
    std::error_code ignored;
    fs::remove(fs::path(options.out_dir) / "bags", ignored);  // Only when empty.
  }
  return status;
}

}  // namespace dispel::apps

#include "slam_cli.hpp"

namespace dispel::apps {

int run_slam_command(SlamCli& cli) {
  if (cli.slam_cmd != nullptr && *cli.slam_cmd) {
    SlamCommandOptions& o = cli.slam;
    if (!cli.slam_ini.empty()) o.job.engine_config_ini = cli.slam_ini;
    if (!cli.initial_pose.empty()) {
      if (o.map.empty()) {
        std::cerr << "dispel slam: --initial-pose needs --map\n";
        return 1;
      }
      o.localization.initial_pose =
          Pose2{cli.initial_pose[0], cli.initial_pose[1], cli.initial_pose[2]};
    }
    return run_slam(o);
  }
  ExperimentCommandOptions& o = cli.experiment;
  if (!cli.experiment_config.empty()) o.job.filter_config = cli.experiment_config;
  if (!cli.experiment_ini.empty()) o.job.engine_config_ini = cli.experiment_ini;
  if (cli.experiment_duration->count() > 0) o.job.duration_s = cli.experiment_duration_s;
  o.job.divergence_yaw_rad = cli.experiment_yaw_deg * kPi / 180.0;
  if (o.job.keep_bags && o.out_dir.empty()) {
    std::cerr << "dispel experiment: --keep-bags needs --out\n";
    return 1;
  }
  return run_experiment(o);
}

}  // namespace dispel::apps
