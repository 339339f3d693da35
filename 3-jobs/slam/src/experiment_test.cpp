#include "dispel/slam/experiment.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include "dispel/jobs/job.hpp"
#include "test_files.hpp"

namespace dispel::slam {
namespace {

using test::source_path;
using test::temp_path;

const char* kScenario = "config/scenarios/thesis_hall_slam.yaml";

// The shipped SLAM scenario with @p replace's (from, to) edits, written to a temporary file.
std::string edited_scenario(const std::string& name,
                            const std::vector<std::pair<std::string, std::string>>& replace) {
  std::ifstream in(source_path(kScenario));
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  for (const auto& [from, to] : replace) {
    const auto at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) s.replace(at, from.size(), to);
  }
  const std::string path = temp_path(name);
  std::ofstream(path) << s;
  return path;
}

ExperimentOptions options(const std::string& scenario, int seeds, double duration_s,
                          const std::string& work) {
  ExperimentOptions o;
  o.scenario = scenario;
  o.seeds = seeds;
  o.duration_s = duration_s;
  o.work_dir = temp_path(work);
  return o;
}

const ExperimentRun& find(const ExperimentResult& r, std::uint64_t seed, Variant v) {
  for (const ExperimentRun& run : r.runs) {
    if (run.seed == seed && run.variant == v) return run;
  }
  throw std::logic_error("no such run");
}

const VariantSummary& find(const std::vector<VariantSummary>& s, Variant v) {
  for (const VariantSummary& x : s) {
    if (x.variant == v) return x;
  }
  throw std::logic_error("no such variant");
}

bool same_trajectory(const std::vector<eval::TrajectoryPoint>& a,
                     const std::vector<eval::TrajectoryPoint>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].t_s != b[i].t_s || a[i].x_m != b[i].x_m || a[i].y_m != b[i].y_m ||
        a[i].yaw_rad != b[i].yaw_rad) {
      return false;
    }
  }
  return true;
}

// The hall with nobody in it, range cut as shipped: the oracle removes nothing, so it is the raw
// run exactly; the engine localises on the pillars and machines alone; the filter keeps the hall.
TEST(Experiment, InAnEmptyHallTheOracleIsTheRawRunAndSlamLocalises) {
  const std::string scenario = edited_scenario("empty_slam_hall.yaml", {{"count: 12", "count: 0"}});
  const ExperimentResult r = run_experiment(options(scenario, 1, 20.0, "experiment_empty"));
  ASSERT_EQ(r.seeds, std::vector<std::uint64_t>{1});
  ASSERT_EQ(r.runs.size(), 7u);  // No localisation or cleaned runs unless asked for.
  ASSERT_EQ(r.truth.size(), 1u);
  EXPECT_EQ(r.truth[0].size(), 401u);  // 20 s at 20 Hz.
  const ExperimentRun& raw = find(r, 1, Variant::kRaw);
  const ExperimentRun& oracle = find(r, 1, Variant::kOracle);
  EXPECT_TRUE(same_trajectory(raw.trajectory, oracle.trajectory));
  EXPECT_EQ(raw.trajectory.size(), 401u);
  for (Variant v : {Variant::kRaw, Variant::kFilteredPoi, Variant::kFilteredPog, Variant::kOracle,
                    Variant::kFullRange}) {
    const ExperimentRun& run = find(r, 1, v);
    EXPECT_LT(run.against_truth.rmse_position_m, 0.05) << variant_name(v);
    EXPECT_LT(run.against_truth.rmse_yaw_rad, 0.01) << variant_name(v);
    EXPECT_FALSE(run.diverged) << variant_name(v);
    EXPECT_EQ(run.against_truth.compared, 401) << variant_name(v);
  }
  EXPECT_GE(find(r, 1, Variant::kFilteredPoi).preservation_rate, 0.99);
  EXPECT_TRUE(std::isnan(find(r, 1, Variant::kFilteredPoi).rejection_rate));  // Nothing moves.
  EXPECT_TRUE(std::isnan(raw.preservation_rate));
  // The thesis's protocol: every cut run is compared with the full-range run, which is not.
  EXPECT_TRUE(raw.against_full_range.has_value());
  EXPECT_FALSE(find(r, 1, Variant::kFullRange).against_full_range.has_value());
  EXPECT_FALSE(find(r, 1, Variant::kOdometry).against_full_range.has_value());
}

// Without a range cut the raw run is the full-range run; two runs of one seed are identical.
TEST(Experiment, WithoutARangeCutRawIsTheFullRangeRunAndRunsRepeat) {
  const std::string scenario =
      edited_scenario("uncut_slam_hall.yaml",
                      {{"range_limit_m: 5.5", "range_limit_m: 0"}, {"count: 12", "count: 3"}});
  const ExperimentResult a = run_experiment(options(scenario, 1, 8.0, "experiment_uncut_a"));
  const ExperimentResult b = run_experiment(options(scenario, 1, 8.0, "experiment_uncut_b"));
  EXPECT_EQ(a.range_limit_m, 0.0);
  EXPECT_TRUE(same_trajectory(find(a, 1, Variant::kRaw).trajectory,
                              find(a, 1, Variant::kFullRange).trajectory));
  EXPECT_NEAR(find(a, 1, Variant::kRaw).against_full_range->rmse_x_m, 0.0, 1e-12);
  for (std::size_t i = 0; i < a.runs.size(); ++i) {
    EXPECT_TRUE(same_trajectory(a.runs[i].trajectory, b.runs[i].trajectory))
        << variant_name(a.runs[i].variant);
  }
}

// The reduced form of the thesis-hall experiment that fits in CI (the full one: README,
// "Localisation with and without the filter"): on the shipped scenario people pull raw SLAM off,
// and the filter takes most of that away.
TEST(Experiment, PeopleMoveRawSlamAndTheFilterRestoresIt) {
  ExperimentOptions o = options(source_path(kScenario), 2, 60.0, "experiment_hall");
  o.first_seed = 1;
  o.localization = true;
  o.clean = true;
  const ExperimentResult r = run_experiment(o);
  const std::vector<VariantSummary> s = summarise(r);
  const double raw = find(s, Variant::kRaw).rmse_position_m.mean;
  const double poi = find(s, Variant::kFilteredPoi).rmse_position_m.mean;
  const double oracle = find(s, Variant::kOracle).rmse_position_m.mean;
  EXPECT_GT(raw, 2.0 * oracle) << "raw " << raw << " oracle " << oracle;
  EXPECT_LT(poi, 0.5 * raw) << "poi " << poi << " raw " << raw;
  EXPECT_LT(poi, 1.5 * oracle) << "poi " << poi << " oracle " << oracle;
  EXPECT_GE(find(s, Variant::kFilteredPoi).rejection_rate.mean, 0.85);
  EXPECT_GE(find(s, Variant::kFilteredPoi).preservation_rate.mean, 0.99);
  // Localisation in a map made without the people (the oracle's): the same picture (measured
  // 0.060, 0.023 and 0.028 m).
  const double loc_raw = find(s, Variant::kLocalizationRaw).rmse_position_m.mean;
  const double loc_poi = find(s, Variant::kLocalizationFilteredPoi).rmse_position_m.mean;
  const double loc_oracle = find(s, Variant::kLocalizationOracle).rmse_position_m.mean;
  EXPECT_LT(loc_poi, loc_raw / 1.5) << "poi " << loc_poi << " raw " << loc_raw;
  EXPECT_LT(loc_poi, 1.5 * loc_oracle) << "poi " << loc_poi << " oracle " << loc_oracle;
  EXPECT_EQ(find(s, Variant::kLocalizationRaw).diverged, 0);
  EXPECT_FALSE(find(r, 1, Variant::kLocalizationRaw).against_full_range.has_value());

  // dispel clean: it removes far more of the people standing still, and SLAM on its output is as
  // good as on the oracle's.
  const VariantSummary& cleaned = find(s, Variant::kCleaned);
  const VariantSummary& filtered = find(s, Variant::kFilteredPoi);
  EXPECT_EQ(cleaned.runs, 2);
  EXPECT_GE(cleaned.preservation_rate.mean, 0.999);
  EXPECT_GT(cleaned.still_removed_rate.mean, filtered.still_removed_rate.mean + 0.15);
  // Of them, those of the people seen moving later: what an offline filter can know to remove.
  EXPECT_GT(cleaned.still_moves_later_removed_rate.mean,
            filtered.still_moves_later_removed_rate.mean + 0.15);
  EXPECT_LT(cleaned.rmse_position_m.mean, 1.5 * oracle);
  // The maps against the one without people (oracle_static's): people leave many cells in raw
  // SLAM's map, few in the filtered one, fewer in the cleaned one. Measured: wrongly occupied
  // raw 1.061, filtered_poi 0.286, filtered_pog 0.148, cleaned 0.112, oracle 0.315 (it keeps the
  // people standing still); lost at most 0.005.
  const auto wrong = [&](Variant v) { return find(s, v).map_wrongly_occupied_share.mean; };
  EXPECT_EQ(wrong(Variant::kOracleStatic), 0.0);
  EXPECT_EQ(find(s, Variant::kOracleStatic).map_lost_share.mean, 0.0);
  std::printf(
      "map wrongly occupied: raw %.4f poi %.4f pog %.4f cleaned %.4f oracle %.4f; lost: raw %.4f "
      "poi %.4f cleaned %.4f oracle %.4f\n",
      wrong(Variant::kRaw), wrong(Variant::kFilteredPoi), wrong(Variant::kFilteredPog),
      wrong(Variant::kCleaned), wrong(Variant::kOracle), find(s, Variant::kRaw).map_lost_share.mean,
      find(s, Variant::kFilteredPoi).map_lost_share.mean,
      find(s, Variant::kCleaned).map_lost_share.mean,
      find(s, Variant::kOracle).map_lost_share.mean);
  EXPECT_GT(wrong(Variant::kRaw), 5.0 * wrong(Variant::kCleaned));
  EXPECT_LT(wrong(Variant::kCleaned), wrong(Variant::kFilteredPoi));
  EXPECT_FALSE(find(r, 1, Variant::kCleaned).against_full_range->compared == 0);
}

TEST(Experiment, SummariesAreMeansStandardDeviationsMediansAndDivergenceCounts) {
  ExperimentResult r;
  r.seeds = {1, 2, 3};
  const double raw_rmse[] = {0.1, 0.3, 0.2};
  for (int k = 0; k < 3; ++k) {
    ExperimentRun run;
    run.seed = r.seeds[static_cast<std::size_t>(k)];
    run.variant = Variant::kRaw;
    run.against_truth.rmse_position_m = raw_rmse[k];
    run.against_truth.rmse_yaw_rad = 0.01 * (k + 1);
    run.diverged = k == 1;
    run.preservation_rate = run.rejection_rate = std::nan("");
    r.runs.push_back(run);
    run.variant = Variant::kFilteredPoi;
    run.against_truth.rmse_position_m = 0.05;
    run.diverged = false;
    run.preservation_rate = 0.99;
    run.rejection_rate = 0.9 + 0.01 * k;
    run.against_full_range = eval::TrajectoryErrors{};
    run.against_full_range->rmse_x_m = 0.02 * (k + 1);
    r.runs.push_back(run);
  }
  const std::vector<VariantSummary> s = summarise(r);
  ASSERT_EQ(s.size(), 2u);
  const VariantSummary& raw = find(s, Variant::kRaw);
  EXPECT_EQ(raw.runs, 3);
  EXPECT_EQ(raw.diverged, 1);
  EXPECT_NEAR(raw.rmse_position_m.mean, 0.2, 1e-12);
  EXPECT_NEAR(raw.rmse_position_m.std, 0.1, 1e-12);  // Sample standard deviation.
  EXPECT_NEAR(raw.rmse_position_m.median, 0.2, 1e-12);
  EXPECT_NEAR(raw.rmse_yaw_rad.mean, 0.02, 1e-12);
  EXPECT_EQ(raw.rejection_rate.count, 0);  // None: not a filtered variant.
  EXPECT_EQ(raw.rmse_position_m.count, 3);
  const VariantSummary& poi = find(s, Variant::kFilteredPoi);
  EXPECT_EQ(poi.diverged, 0);
  EXPECT_NEAR(poi.rmse_position_m.std, 0.0, 1e-12);
  EXPECT_NEAR(poi.rejection_rate.mean, 0.91, 1e-12);
  EXPECT_NEAR(poi.full_range_rmse_x_m.mean, 0.04, 1e-12);
}

TEST(ExperimentBadInput, IsRefusedWithAClearMessage) {
  const auto message = [](const ExperimentOptions& o) {
    try {
      run_experiment(o);
    } catch (const jobs::JobError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  ExperimentOptions o = options(source_path(kScenario), 0, 5.0, "experiment_bad");
  EXPECT_NE(message(o).find("--seeds"), std::string::npos) << message(o);
  o.seeds = 1;
  o.duration_s = -1.0;
  EXPECT_NE(message(o).find("--duration"), std::string::npos) << message(o);
  o.duration_s = 5.0;
  o.scenario = temp_path("no_such_scenario.yaml");
  EXPECT_NE(message(o).find("no_such_scenario.yaml"), std::string::npos) << message(o);
  o.scenario = source_path(kScenario);
  o.filter_config = temp_path("no_such_config.yaml");
  EXPECT_NE(message(o).find("no_such_config.yaml"), std::string::npos) << message(o);
  o.filter_config.reset();
  o.engine_config_ini = temp_path("no_such_engine.ini");
  EXPECT_NE(message(o).find("no_such_engine.ini"), std::string::npos) << message(o);
}

}  // namespace
}  // namespace dispel::slam
