#pragma once
/// @file
/// `dispel experiment`: localisation with and without the filter, through a real SLAM engine,
/// against exact ground truth, over many simulated runs.
///
/// For each seed the scenario is simulated once at the scanner's full range; the range cut of the
/// scenario (lidar.range_limit_m) is then applied to that recording, as the thesis cut its
/// recordings. Six SLAM runs follow (MRPT's ICP-SLAM, run_icp_slam_full()), each over a bag:
///   raw           the cut scans as they are
///   filtered_poi  the cut scans after `dispel filter` (presumption of innocence)
///   filtered_pog  the same with presumption of guilt
///   oracle        the cut scans with exactly the beams on moving actors removed (ground truth)
///   oracle_static the cut scans with every beam on an actor removed, moving or standing still:
///                 the map a recording without people would make
///   full_range    the uncut scans (the thesis's reference)
/// With ExperimentOptions::clean a sixth SLAM run follows:
///   cleaned       the cut scans after `dispel clean` (the offline filter, with the same
///                 configuration as filtered_poi and the cleaner's defaults)
/// Each trajectory is compared with the true pose, and the cut runs also with full_range's
/// trajectory (the thesis's own protocol, its Table 4.1). The wheel odometry the engine is given
/// is compared with the truth too, as a baseline. The occupancy grid of each cut SLAM run is
/// compared with oracle_static's (compare_grid_maps(): cells wrongly occupied, cells lost).

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "dispel/eval/map_quality.hpp"
#include "dispel/eval/trajectory_error.hpp"

namespace dispel::slam {

/// The SLAM variants, in table order.
enum class Variant {
  kRaw,
  kFilteredPoi,
  kFilteredPog,
  kOracle,
  kFullRange,
  kOdometry,
  // With ExperimentOptions::localization: particle-filter localisation of the same scans in the
  // map the oracle's SLAM run built (a map made earlier without the people).
  kLocalizationRaw,
  kLocalizationFilteredPoi,
  kLocalizationFilteredPog,
  kLocalizationOracle,
  kCleaned,       ///< With ExperimentOptions::clean: SLAM on the output of `dispel clean`.
  kOracleStatic,  ///< Every actor's beams removed.
};
inline constexpr int kVariantCount = 12;
/// The variants in the order of the tables: the cut SLAM runs (raw, filtered_poi, filtered_pog,
/// cleaned, oracle, oracle_static), full_range, odometry, then the localisation runs.
extern const Variant kTableOrder[kVariantCount];
/// "raw", "filtered_poi", "filtered_pog", "oracle", "full_range", "odometry",
/// "localization_raw" ... "localization_oracle", "cleaned" and "oracle_static".
const char* variant_name(Variant v);
/// The SLAM runs on the cut scans (raw, filtered_poi, filtered_pog, cleaned, oracle,
/// oracle_static): the ones the thesis's protocol compares with full_range.
bool is_cut_slam_variant(Variant v);
/// The localisation runs.
bool is_localization_variant(Variant v);

struct ExperimentOptions {
  std::string scenario;              ///< SCENARIO.yaml.
  int seeds = 10;                    ///< How many seeds.
  std::uint64_t first_seed = 1;      ///< Seeds first_seed .. first_seed + seeds - 1.
  std::optional<double> duration_s;  ///< Overrides the scenario's.
  /// The filter's YAML configuration (default: dispel's defaults). Either way the scenario's
  /// masked sectors are given to the filter, as a user configures them for the sensor.
  std::optional<std::string> filter_config;
  std::optional<std::string> engine_config_ini;  ///< MRPT .ini over the engine's defaults.
  /// Where the bags of a seed are written while it runs (removed after it unless keep_bags).
  std::string work_dir;
  bool keep_bags = false;
  /// Also localise each of raw, filtered_poi, filtered_pog and oracle with MRPT's particle filter
  /// in the map of the oracle's SLAM run (0.05 m grid), from the true start pose, seeded with the
  /// seed.
  bool localization = false;
  int particles = 500;  ///< For the localisation runs.
  /// Also `dispel clean` over the cut scans, and SLAM on its output (the variant cleaned).
  bool clean = false;
  /// A run diverged when its position error against the truth ever exceeds this ...
  double divergence_position_m = 0.5;
  /// ... or its yaw error ever exceeds this.
  double divergence_yaw_rad = 0.1745329251994330;  // 10 degrees
};

/// One variant of one seed.
struct ExperimentRun {
  std::uint64_t seed = 0;
  Variant variant = Variant::kRaw;
  eval::TrajectoryErrors against_truth;
  /// Against full_range's trajectory (the thesis's protocol); only for the cut SLAM runs.
  std::optional<eval::TrajectoryErrors> against_full_range;
  bool diverged = false;
  /// Filtered and cleaned variants: the filter's rates on this seed (dispel eval), the share of
  /// the beams on actors standing still that it removed too, and of those of them on actors the
  /// scanner sees moving later (what an offline filter can know to remove); NaN otherwise.
  double preservation_rate = 0.0;
  double rejection_rate = 0.0;
  double still_removed_rate = 0.0;
  double still_moves_later_removed_rate = 0.0;
  /// The cut SLAM runs: this run's occupancy grid against oracle_static's.
  std::optional<eval::MapComparison> map;
  /// The trajectory (t, x, y, yaw; in the world frame of the simulation).
  std::vector<eval::TrajectoryPoint> trajectory;
};

struct ExperimentResult {
  std::string scenario_name;
  std::vector<std::uint64_t> seeds;
  double duration_s = 0.0;
  double range_limit_m = 0.0;  ///< The cut (0: none; then raw equals full_range).
  /// Per seed: the true pose at each scan.
  std::vector<std::vector<eval::TrajectoryPoint>> truth;
  std::vector<ExperimentRun> runs;  ///< Seed by seed, variants in table order.
};

/// Called after each run with it (for progress lines).
using ExperimentProgress = std::function<void(const ExperimentRun&)>;

/// Runs the experiment. @throws dispel::jobs::JobError (bad scenario, configuration or options).
ExperimentResult run_experiment(const ExperimentOptions& options,
                                const ExperimentProgress& progress = {});

/// Mean and sample standard deviation (0 for one value) of a figure over seeds, and its median.
struct Statistic {
  double mean = 0.0;
  double std = 0.0;
  double median = 0.0;
  int count = 0;  ///< Values it is over (0: none, e.g. a rejection rate where nothing moved).
};

/// One variant over all seeds.
struct VariantSummary {
  Variant variant = Variant::kRaw;
  int runs = 0;
  int diverged = 0;
  Statistic rmse_position_m, rmse_x_m, rmse_y_m, rmse_yaw_rad, max_position_error_m;
  /// The thesis's protocol: the same figures against full_range (runs without it: zeros).
  Statistic full_range_rmse_x_m, full_range_rmse_y_m, full_range_rmse_yaw_rad;
  /// Filtered variants only.
  Statistic preservation_rate, rejection_rate, still_removed_rate, still_moves_later_removed_rate;
  /// The cut SLAM runs: shares of oracle_static's grid's occupied cells.
  Statistic map_wrongly_occupied_share, map_lost_share;
};

/// Summaries in table order (every variant that ran).
std::vector<VariantSummary> summarise(const ExperimentResult& result);

}  // namespace dispel::slam
