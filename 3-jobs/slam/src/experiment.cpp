// `dispel experiment`: simulate, filter, run SLAM on each variant, compare with the truth.

#include "dispel/slam/experiment.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <optional>
#include <stdexcept>
#include <system_error>

#include "dispel/io/config_yaml.hpp"
#include "dispel/io/scenario_yaml.hpp"
#include "dispel/jobs/clean_job.hpp"
#include "dispel/jobs/eval_job.hpp"
#include "dispel/jobs/filter_job.hpp"
#include "dispel/jobs/sim_job.hpp"
#include "dispel/sim/simulator.hpp"
#include "dispel/slam/icp_slam.hpp"
#include "dispel/slam/localization.hpp"

namespace dispel::slam {
namespace {

using jobs::JobError;
namespace fs = std::filesystem;

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;

sim::Scenario load(const std::string& path) {
  try {
    return io::load_scenario(path);
  } catch (const std::exception& e) {
    throw JobError(e.what());
  }
}

DynamicFilterConfig filter_config(const ExperimentOptions& o, const sim::Scenario& scenario) {
  DynamicFilterConfig c = DynamicFilterConfig{};
  if (o.filter_config) {
    try {
      c = io::load_filter_config(*o.filter_config);
    } catch (const std::exception& e) {
      throw JobError(e.what());
    }
  }
  c.segmentation.masked_sectors.clear();
  for (const auto& [lo, hi] : scenario.lidar.masked_sectors_deg) {
    c.segmentation.masked_sectors.push_back({lo * kDegToRad, hi * kDegToRad});
  }
  return c;
}

// The recording with the scanner's range cut to @p limit_m: returns beyond it are no returns.
sim::SimulationOutput cut_range(const sim::SimulationOutput& full, double limit_m) {
  sim::SimulationOutput cut = full;
  if (!(limit_m > 0.0)) return cut;
  for (sim::ScanFrame& f : cut.scans) {
    for (std::size_t i = 0; i < f.scan.ranges_m.size(); ++i) {
      float& r = f.scan.ranges_m[i];
      if (std::isfinite(r) && r > limit_m) {
        r = std::numeric_limits<float>::infinity();
        f.truth[i] = sim::Truth::kNoReturn;
        f.actor[i] = 0;
      }
    }
  }
  return cut;
}

// The oracle: exactly the beams on moving actors removed (NaN, as `dispel filter` removes them),
// and with @p still_too those on actors standing still as well.
sim::SimulationOutput remove_actors(const sim::SimulationOutput& run, bool still_too) {
  sim::SimulationOutput oracle = run;
  for (sim::ScanFrame& f : oracle.scans) {
    for (std::size_t i = 0; i < f.scan.ranges_m.size(); ++i) {
      if (f.truth[i] == sim::Truth::kMoving || (still_too && f.truth[i] == sim::Truth::kStill)) {
        f.scan.ranges_m[i] = std::numeric_limits<float>::quiet_NaN();
      }
    }
  }
  return oracle;
}

std::vector<eval::TrajectoryPoint> truth_at_scans(const sim::SimulationOutput& run) {
  std::vector<eval::TrajectoryPoint> truth;
  truth.reserve(run.scans.size());
  for (const sim::ScanFrame& f : run.scans) {
    truth.push_back({f.scan.stamp_s, f.base_pose.x_m, f.base_pose.y_m, f.base_pose.yaw_rad});
  }
  return truth;
}

eval::TrajectoryErrors compare(const std::vector<eval::TrajectoryPoint>& reference,
                               const std::vector<eval::TrajectoryPoint>& estimate) {
  try {
    return eval::compare_trajectories(reference, estimate);
  } catch (const std::invalid_argument& e) {
    throw JobError(std::string("comparing trajectories: ") + e.what());
  }
}

void remove_quietly(const fs::path& p) {
  std::error_code ignored;
  fs::remove(p, ignored);
}

void check(const ExperimentOptions& o) {
  if (o.seeds < 1)
    throw JobError("--seeds must be at least 1 (got " + std::to_string(o.seeds) + ")");
  if (o.duration_s && !(*o.duration_s > 0.0 && std::isfinite(*o.duration_s))) {
    throw JobError("--duration must be a positive number of seconds");
  }
  if (!(o.divergence_position_m > 0.0) || !(o.divergence_yaw_rad > 0.0)) {
    throw JobError("the divergence thresholds must be positive");
  }
  if (o.work_dir.empty()) throw JobError("no work directory given");
  if (o.particles < 1) {
    throw JobError("--particles must be at least 1 (got " + std::to_string(o.particles) + ")");
  }
}

Statistic statistic(std::vector<double> v) {
  Statistic s;
  s.count = static_cast<int>(v.size());
  if (v.empty()) return s;
  double sum = 0.0;
  for (double x : v) sum += x;
  s.mean = sum / static_cast<double>(v.size());
  double ss = 0.0;
  for (double x : v) ss += (x - s.mean) * (x - s.mean);
  s.std = v.size() > 1 ? std::sqrt(ss / static_cast<double>(v.size() - 1)) : 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  s.median = n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  return s;
}

// Cells of two SLAM runs' grids match when their centres are this close: two cells, about the
// position error of a SLAM run that did not diverge here (0.02-0.06 m RMSE on the thesis hall).
constexpr double kMapToleranceM = 0.1;

}  // namespace

const Variant kTableOrder[kVariantCount] = {Variant::kRaw,
                                            Variant::kFilteredPoi,
                                            Variant::kFilteredPog,
                                            Variant::kCleaned,
                                            Variant::kOracle,
                                            Variant::kOracleStatic,
                                            Variant::kFullRange,
                                            Variant::kOdometry,
                                            Variant::kLocalizationRaw,
                                            Variant::kLocalizationFilteredPoi,
                                            Variant::kLocalizationFilteredPog,
                                            Variant::kLocalizationOracle};

const char* variant_name(Variant v) {
  switch (v) {
    case Variant::kRaw:
      return "raw";
    case Variant::kFilteredPoi:
      return "filtered_poi";
    case Variant::kFilteredPog:
      return "filtered_pog";
    case Variant::kOracle:
      return "oracle";
    case Variant::kFullRange:
      return "full_range";
    case Variant::kOdometry:
      return "odometry";
    case Variant::kLocalizationRaw:
      return "localization_raw";
    case Variant::kLocalizationFilteredPoi:
      return "localization_filtered_poi";
    case Variant::kLocalizationFilteredPog:
      return "localization_filtered_pog";
    case Variant::kLocalizationOracle:
      return "localization_oracle";
    case Variant::kCleaned:
      return "cleaned";
    case Variant::kOracleStatic:
      return "oracle_static";
  }
  return "?";
}

bool is_cut_slam_variant(Variant v) {
  return v == Variant::kRaw || v == Variant::kFilteredPoi || v == Variant::kFilteredPog ||
         v == Variant::kCleaned || v == Variant::kOracle || v == Variant::kOracleStatic;
}

bool is_localization_variant(Variant v) {
  return v == Variant::kLocalizationRaw || v == Variant::kLocalizationFilteredPoi ||
         v == Variant::kLocalizationFilteredPog || v == Variant::kLocalizationOracle;
}

ExperimentResult run_experiment(const ExperimentOptions& o, const ExperimentProgress& progress) {
  check(o);
  const sim::Scenario scenario = load(o.scenario);
  const DynamicFilterConfig poi = filter_config(o, scenario);
  engine_config(o.engine_config_ini);  // Refuse a bad engine configuration before simulating.
  DynamicFilterConfig pog = poi;
  pog.classification.presumption = Presumption::kGuilt;
  sim::Scenario full_scenario = scenario;
  full_scenario.lidar.range_limit_m = 0.0;

  ExperimentResult result;
  result.scenario_name = scenario.name;
  result.duration_s = o.duration_s ? *o.duration_s : scenario.duration_s;
  result.range_limit_m = scenario.lidar.range_limit_m;
  std::error_code ec;
  fs::create_directories(o.work_dir, ec);
  if (ec) throw JobError(o.work_dir + ": cannot create the directory (" + ec.message() + ")");

  for (int k = 0; k < o.seeds; ++k) {
    const std::uint64_t seed = o.first_seed + static_cast<std::uint64_t>(k);
    result.seeds.push_back(seed);
    const fs::path dir = fs::path(o.work_dir) / ("seed_" + std::to_string(seed));
    fs::create_directories(dir, ec);
    if (ec) throw JobError(dir.string() + ": cannot create the directory (" + ec.message() + ")");
    const auto bag = [&](const char* name) {
      return (dir / (std::string(name) + ".bag")).string();
    };

    // The recordings.
    const sim::SimulationOutput full = sim::simulate(full_scenario, seed, result.duration_s);
    const sim::SimulationOutput cut = cut_range(full, scenario.lidar.range_limit_m);
    jobs::write_simulation(full, full_scenario, bag("full_range"));
    jobs::write_simulation(cut, scenario, bag("raw"));
    jobs::write_simulation(remove_actors(cut, false), scenario, bag("oracle"));
    jobs::write_simulation(remove_actors(cut, true), scenario, bag("oracle_static"));
    jobs::FilterJobOptions filter;
    filter.input = bag("raw");
    filter.output = bag("filtered_poi");
    filter.config = poi;
    jobs::run_filter_job(filter);
    filter.output = bag("filtered_pog");
    filter.config = pog;
    jobs::run_filter_job(filter);
    if (o.clean) {
      jobs::CleanJobOptions clean;
      clean.filter = filter;
      clean.filter.config = poi;
      clean.filter.output = bag("cleaned");
      jobs::run_clean_job(clean);
    }
    result.truth.push_back(truth_at_scans(cut));
    const std::vector<eval::TrajectoryPoint>& truth = result.truth.back();

    // SLAM on each; full range first, as the others are compared with it.
    std::vector<Variant> order = {Variant::kFullRange,   Variant::kRaw,    Variant::kFilteredPoi,
                                  Variant::kFilteredPog, Variant::kOracle, Variant::kOracleStatic};
    if (o.clean) order.push_back(Variant::kCleaned);
    std::vector<ExperimentRun> runs(kVariantCount);
    std::vector<char> ran(kVariantCount, 0);
    std::vector<eval::TrajectoryPoint> odometry;
    // The filter's rates on this seed, once per filtered bag (SLAM and localisation share them).
    std::vector<std::optional<eval::Rates>> rates(kVariantCount);
    rates[static_cast<std::size_t>(Variant::kFilteredPoi)] =
        jobs::evaluate_bags(bag("raw"), bag("filtered_poi"));
    rates[static_cast<std::size_t>(Variant::kFilteredPog)] =
        jobs::evaluate_bags(bag("raw"), bag("filtered_pog"));
    if (o.clean) {
      rates[static_cast<std::size_t>(Variant::kCleaned)] =
          jobs::evaluate_bags(bag("raw"), bag("cleaned"), "/scan_clean");
    }
    const auto rates_of = [&](Variant v, ExperimentRun& run) {
      const std::optional<eval::Rates>& r = rates[static_cast<std::size_t>(v)];
      constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
      run.preservation_rate = r ? r->preservation_rate() : kNone;
      run.rejection_rate = r ? r->rejection_rate() : kNone;
      run.still_removed_rate = r ? r->still_removed_rate() : kNone;
      run.still_moves_later_removed_rate = r ? r->still_moves_later_removed_rate() : kNone;
    };
    const auto scan_topic = [](Variant v) {
      if (v == Variant::kCleaned) return "/scan_clean";
      return (v == Variant::kFilteredPoi || v == Variant::kFilteredPog) ? "/scan_filtered"
                                                                        : "/scan";
    };
    std::vector<GridMap> grids(kVariantCount);
    for (Variant v : order) {
      SlamOptions slam;
      slam.input = bag(variant_name(v));
      slam.scan_topic = scan_topic(v);
      slam.engine_config_ini = o.engine_config_ini;
      SlamResult r = run_icp_slam_full(slam);
      ExperimentRun& run = runs[static_cast<std::size_t>(v)];
      ran[static_cast<std::size_t>(v)] = 1;
      run.seed = seed;
      run.variant = v;
      run.trajectory = std::move(r.trajectory);
      rates_of(v, run);
      if (v == Variant::kRaw) odometry = std::move(r.odometry);
      grids[static_cast<std::size_t>(v)] = std::move(r.grid);
    }
    const GridMap& no_people = grids[static_cast<std::size_t>(Variant::kOracleStatic)];
    for (Variant v : order) {
      if (!is_cut_slam_variant(v)) continue;
      runs[static_cast<std::size_t>(v)].map =
          compare_grid_maps(no_people, grids[static_cast<std::size_t>(v)], kMapToleranceM);
    }
    // The oracle's map, the hall without the people walking, for the localisation.
    const GridMap map = std::move(grids[static_cast<std::size_t>(Variant::kOracle)]);
    ExperimentRun& odo = runs[static_cast<std::size_t>(Variant::kOdometry)];
    ran[static_cast<std::size_t>(Variant::kOdometry)] = 1;
    odo.seed = seed;
    odo.variant = Variant::kOdometry;
    odo.trajectory = std::move(odometry);
    rates_of(Variant::kOdometry, odo);

    // Localisation in the oracle's map, from the true start, one seed per run.
    if (o.localization) {
      for (Variant v :
           {Variant::kRaw, Variant::kFilteredPoi, Variant::kFilteredPog, Variant::kOracle}) {
        LocalizationOptions l;
        l.input = bag(variant_name(v));
        l.scan_topic = scan_topic(v);
        l.map = map;
        l.initial_pose = Pose2{truth.front().x_m, truth.front().y_m, truth.front().yaw_rad};
        l.filter.particles = o.particles;
        l.filter.seed = seed;
        const auto lv =
            static_cast<Variant>(static_cast<int>(Variant::kLocalizationRaw) + static_cast<int>(v));
        ExperimentRun& run = runs[static_cast<std::size_t>(lv)];
        ran[static_cast<std::size_t>(lv)] = 1;
        run.seed = seed;
        run.variant = lv;
        run.trajectory = run_pf_localization(l).trajectory;
        rates_of(v, run);
      }
    }

    const auto& reference = runs[static_cast<std::size_t>(Variant::kFullRange)].trajectory;
    for (const Variant v : kTableOrder) {
      const auto i = static_cast<std::size_t>(v);
      if (ran[i] == 0) continue;
      ExperimentRun& run = runs[i];
      run.against_truth = compare(truth, run.trajectory);
      run.diverged = run.against_truth.max_position_error_m > o.divergence_position_m ||
                     run.against_truth.max_yaw_error_rad > o.divergence_yaw_rad;
      if (is_cut_slam_variant(run.variant)) {
        run.against_full_range = compare(reference, run.trajectory);
      }
      if (progress) progress(run);
      result.runs.push_back(std::move(run));
    }
    if (!o.keep_bags) {
      for (Variant v : order) remove_quietly(bag(variant_name(v)));
      remove_quietly(dir);  // Only when empty.
    }
  }
  return result;
}

std::vector<VariantSummary> summarise(const ExperimentResult& result) {
  std::vector<VariantSummary> out;
  for (const Variant v : kTableOrder) {
    std::vector<double> p, x, y, yaw, worst, fx, fy, fyaw, pres, rej, still, still_later, wrong,
        lost;
    VariantSummary s;
    s.variant = v;
    for (const ExperimentRun& r : result.runs) {
      if (r.variant != v) continue;
      ++s.runs;
      if (r.diverged) ++s.diverged;
      p.push_back(r.against_truth.rmse_position_m);
      x.push_back(r.against_truth.rmse_x_m);
      y.push_back(r.against_truth.rmse_y_m);
      yaw.push_back(r.against_truth.rmse_yaw_rad);
      worst.push_back(r.against_truth.max_position_error_m);
      if (r.against_full_range) {
        fx.push_back(r.against_full_range->rmse_x_m);
        fy.push_back(r.against_full_range->rmse_y_m);
        fyaw.push_back(r.against_full_range->rmse_yaw_rad);
      }
      if (std::isfinite(r.preservation_rate)) pres.push_back(r.preservation_rate);
      if (std::isfinite(r.rejection_rate)) rej.push_back(r.rejection_rate);
      if (std::isfinite(r.still_removed_rate)) still.push_back(r.still_removed_rate);
      if (std::isfinite(r.still_moves_later_removed_rate)) {
        still_later.push_back(r.still_moves_later_removed_rate);
      }
      if (r.map && std::isfinite(r.map->wrongly_occupied_share())) {
        wrong.push_back(r.map->wrongly_occupied_share());
        lost.push_back(r.map->lost_share());
      }
    }
    if (s.runs == 0) continue;
    s.rmse_position_m = statistic(p);
    s.rmse_x_m = statistic(x);
    s.rmse_y_m = statistic(y);
    s.rmse_yaw_rad = statistic(yaw);
    s.max_position_error_m = statistic(worst);
    s.full_range_rmse_x_m = statistic(fx);
    s.full_range_rmse_y_m = statistic(fy);
    s.full_range_rmse_yaw_rad = statistic(fyaw);
    s.preservation_rate = statistic(pres);
    s.rejection_rate = statistic(rej);
    s.still_removed_rate = statistic(still);
    s.still_moves_later_removed_rate = statistic(still_later);
    s.map_wrongly_occupied_share = statistic(wrong);
    s.map_lost_share = statistic(lost);
    out.push_back(s);
  }
  return out;
}

}  // namespace dispel::slam
