#include "dispel/jobs/clean_job.hpp"

#include <gtest/gtest.h>
#include <sensor_msgs/LaserScan.h>

#include <cmath>
#include <cstdio>

#include "bag_contents.hpp"
#include "dispel/io/scenario_yaml.hpp"
#include "dispel/jobs/eval_job.hpp"
#include "dispel/jobs/sim_job.hpp"
#include "still_scanner_rates.hpp"
#include "test_files.hpp"

namespace dispel::jobs {
namespace {

using test::read_bag;
using test::source_path;
using test::temp_path;

// A scenario simulated with @p seed, filtered online and cleaned offline with @p filter's options
// (input and outputs set here), both evaluated against the simulator's ground truth, beam by beam
// and as maps (occupancy grids from the true poses, against the one without people).
struct OnlineAndClean {
  std::string sim_bag, filtered_bag, clean_bag;
  CleanJobStats stats;
  eval::Rates online, clean;
  MapQuality online_map, clean_map;
  ~OnlineAndClean() {
    for (const std::string& p : {sim_bag, filtered_bag, clean_bag}) std::remove(p.c_str());
  }
};

void filter_and_clean(const std::string& scenario_name, std::uint64_t seed, FilterJobOptions filter,
                      OnlineAndClean& out) {
  const sim::Scenario scenario =
      io::load_scenario(source_path("config/scenarios/" + scenario_name + ".yaml"));
  out.sim_bag = temp_path(scenario_name + "_sim.bag");
  out.filtered_bag = temp_path(scenario_name + "_filtered.bag");
  out.clean_bag = temp_path(scenario_name + "_clean.bag");
  simulate_to_recording(scenario, seed, scenario.duration_s, out.sim_bag);
  filter.input = out.sim_bag;
  filter.output = out.filtered_bag;
  run_filter_job(filter);
  CleanJobOptions c;
  c.filter = filter;
  c.filter.output = out.clean_bag;
  out.stats = run_clean_job(c);
  const Evaluation online =
      evaluate_recordings(out.sim_bag, out.filtered_bag, "/scan", eval::OccupancyGridConfig{});
  const Evaluation clean =
      evaluate_recordings(out.sim_bag, out.clean_bag, "/scan_clean", eval::OccupancyGridConfig{});
  out.online = online.rates;
  out.clean = clean.rates;
  out.online_map = *online.map;
  out.clean_map = *clean.map;
  // The map figures of each evaluation are those of the same oracle and raw maps.
  EXPECT_EQ(out.online_map.raw.wrongly_occupied, out.clean_map.raw.wrongly_occupied);
  EXPECT_EQ(out.online_map.result.reference_occupied, out.clean_map.result.reference_occupied);
  // Every scan but the last (whose last beams come after the last true pose) is in the maps.
  EXPECT_GE(out.online_map.scans, out.stats.scans - 1);
  // Neither filter takes a wall out of the map; neither adds a cell to it.
  EXPECT_LE(out.clean_map.result.lost_share(), 0.001);
  EXPECT_LE(out.online_map.result.lost_share(), 0.001);
  EXPECT_LE(out.clean_map.result.wrongly_occupied, out.clean_map.raw.wrongly_occupied);
  std::printf(
      "map cells wrongly occupied of %lld: raw %lld, online %lld, clean %lld; lost: online "
      "%lld, clean %lld\n",
      static_cast<long long>(out.clean_map.result.reference_occupied),
      static_cast<long long>(out.clean_map.raw.wrongly_occupied),
      static_cast<long long>(out.online_map.result.wrongly_occupied),
      static_cast<long long>(out.clean_map.result.wrongly_occupied),
      static_cast<long long>(out.online_map.result.lost),
      static_cast<long long>(out.clean_map.result.lost));
}

// People who stand for 10-20 s and then walk off (config/scenarios/stand_then_leave.yaml, seed
// 1), filtered online and cleaned offline: the cleaner removes far more of the people while they
// stand (the online filter cannot know yet that they will walk) and keeps the walls; legs at
// range, too few beams for an object, are followed from scan to scan and removed where they
// walked; a person who stood in no object (a few beams at range) is removed where a track set off
// from their place later. Measured: still people removed 0.087 online, 0.348 clean (0.285 before
// the set-off rule); moving 0.597, 0.794 (0.620 without the legs at range); walls kept 1.0000,
// 0.99996.
TEST(CleanJob, PeopleWhoStandAndThenWalkAwayAreRemovedBeforeTheyWalk) {
  FilterJobOptions f;
  f.scale_to_scanner = true;
  OnlineAndClean run;
  filter_and_clean("stand_then_leave", 1, f, run);
  const CleanJobStats& stats = run.stats;
  const CleanJobOptions c;  // The cleaner's defaults.
  EXPECT_EQ(stats.scans, 347);
  EXPECT_EQ(stats.counts.scans_with_pose, stats.scans);
  const eval::Rates& online = run.online;
  const eval::Rates& clean = run.clean;
  EXPECT_GT(clean.still_beams, 5000);
  EXPECT_GE(clean.still_removed_rate(), 0.3);
  EXPECT_GE(clean.still_removed_rate(), 3.0 * online.still_removed_rate());
  // Of them, those who walk off later (the rest walked in and stay to the end): 0.029 online,
  // 0.589 clean (0.453 before the set-off rule).
  EXPECT_GT(clean.still_moves_later_beams, 2000);
  EXPECT_GE(clean.still_moves_later_removed_rate(), 0.5);
  EXPECT_GE(clean.still_moves_later_removed_rate(), 10.0 * online.still_moves_later_removed_rate());
  EXPECT_GE(clean.rejection_rate(), online.rejection_rate() + 0.15);
  EXPECT_GT(stats.counts.walked_legs, 300);
  EXPECT_GE(clean.preservation_rate(), 0.9999);

  // Every scan has its cleaned copy and its labels; a beam is NaN exactly where it is removed.
  const test::BagContents out = read_bag(run.clean_bag);
  const auto& scans = out.scans.at("/scan");
  const auto& cleaned = out.scans.at("/scan_clean");
  const auto& labels = out.scans.at("/scan_clean_labels");
  ASSERT_EQ(cleaned.size(), scans.size());
  ASSERT_EQ(labels.size(), scans.size());
  std::int64_t removed_beams = 0;
  for (std::size_t k = 0; k < scans.size(); ++k) {
    ASSERT_EQ(cleaned[k].header.stamp, scans[k].header.stamp);
    ASSERT_EQ(labels[k].intensities.size(), scans[k].ranges.size());
    for (std::size_t b = 0; b < scans[k].ranges.size(); ++b) {
      const auto label = static_cast<CleanLabel>(static_cast<int>(labels[k].intensities[b]));
      const bool nan_now = std::isnan(cleaned[k].ranges[b]) && !std::isnan(scans[k].ranges[b]);
      ASSERT_EQ(nan_now, removed(label)) << "scan " << k << " beam " << b;
      removed_beams += removed(label) ? 1 : 0;
    }
  }
  EXPECT_EQ(removed_beams, stats.counts.removed());
  // The objects it reports: those that moved, with when, and how long they walked before the
  // online filter found them moving (or after).
  int moving = 0, walked_in = 0;
  for (const CleanedObject& o : stats.objects) {
    if (!o.moving) {
      EXPECT_EQ(o.walking_scans, 0);
      continue;
    }
    ++moving;
    walked_in += o.walking_scans > 0 ? 1 : 0;
    EXPECT_GE(o.dynamic_scans, c.clean.moving_min_scans);
    EXPECT_LE(o.first_seen_s, o.first_dynamic_s);
    EXPECT_LE(o.first_dynamic_s, o.last_dynamic_s);
    EXPECT_LE(o.walking_scans + o.dynamic_scans, o.scans);
  }
  EXPECT_GE(moving, 5);
  EXPECT_GE(walked_in, 1);
}

// The thesis's hall (config/scenarios/thesis_hall.yaml, seed 2: its mapping test): people walk
// and stand about a slow robot among pillars, walls out of range. Before a moving track's
// standing part was removed only where the scanner later saw through it, a pillar whose track
// had taken over a passer-by went with it: 0.61 of the static beams kept. Measured: walls kept
// 1.0000 online and clean; moving removed 0.936, 0.970; still people removed 0.738, 0.874. (0.982
// moving removed clean while a track's travel counted from where it was first seen: a walker's
// track dynamic in 10 scans, in which it moved 0.25 m, is now restored.)
TEST(CleanJob, TheThesisHallsStandingPeopleGoAndItsPillarsStay) {
  FilterJobOptions f;
  f.config_path = source_path("config/default_masked.yaml");
  OnlineAndClean run;
  filter_and_clean("thesis_hall", 2, f, run);
  const eval::Rates& online = run.online;
  const eval::Rates& clean = run.clean;
  EXPECT_GE(clean.preservation_rate(), 0.9999);
  EXPECT_GE(clean.rejection_rate(), 0.965);
  EXPECT_GT(clean.rejection_rate(), online.rejection_rate());
  EXPECT_GE(clean.still_removed_rate(), 0.85);
  EXPECT_GT(clean.still_removed_rate(), online.still_removed_rate() + 0.1);
  // The map from the true poses: of the 38 cells the pillars occupy, the people add 22 to the
  // unfiltered scans' map and 2 to either filter's (the rays through their places clear the rest).
  EXPECT_GT(run.clean_map.raw.wrongly_occupied, 5 * run.clean_map.result.wrongly_occupied);
  EXPECT_LE(run.clean_map.result.wrongly_occupied, run.online_map.result.wrongly_occupied);
}

// A real robot among no people (negative_2): every beam removed is a false removal. Cleaned:
// left 0.036 %, right 0.068 %, rear 0.022 % of the valid beams (the online filter 0.19 / 0.13 /
// 0.05 %; the target 0.1 %). Before a track's travel counted only while it was dynamic: 0.103 /
// 0.092 / 0.036 %: tracks of wall pieces dynamic for 3-6 scans, whose centroids then slid 1-4 m
// on the laser-only poses, counted as moving and kept their false removals.
TEST(CleanJob, RealRobotWithoutPeopleKeepsItsWalls) {
  for (const std::string laser : {"/left_scan", "/right_scan", "/rear_scan"}) {
    CleanJobOptions c;
    c.filter.input = source_path("data/leg_tracker/negative_2.bag");
    c.filter.output = temp_path("negative_2_clean" + laser.substr(1) + ".bag");
    c.filter.scan_topic = laser;
    const CleanJobStats stats = run_clean_job(c);
    EXPECT_TRUE(stats.laser_only);
    EXPECT_GT(stats.counts.valid_beams, 200000);
    const std::int64_t removed_beams = stats.counts.removed();
    EXPECT_LE(static_cast<double>(removed_beams),
              0.001 * static_cast<double>(stats.counts.valid_beams))
        << laser;
    std::remove(c.filter.output.c_str());
  }
}

// The shipped leg_tracker demo: a scanner that does not move, people walking past, some of them
// standing a while (test::walls_and_walkers tells walls from walkers). The online filter leaves
// the legs it never found moving: those too few beams for an object, those who came and stayed.
// With a static sensor the pose is exact, so the cleaner asks by default whether the scanner saw
// through a thing's place at another time (2 scans in a row, kStaticSensorThroughScans): measured
// walls kept 0.9999 and walkers removed 0.9914 (0.9453 with the rule off). While the registration
// aligned the still scanner's scans (people walking past turned it by 0.7 degrees), the rule, in
// its earlier form, kept 0.9979 of the walls; with the pose held, 1.0000.
TEST(CleanJob, AStillScannersWalkersGoAndItsWallsStay) {
  const auto clean = [](int through_scans, CleanJobStats& stats) {
    CleanJobOptions c;
    c.filter.input = source_path("data/leg_tracker/demo_stationary_simple_environment.bag");
    c.filter.output = temp_path("demo_clean_" + std::to_string(through_scans) + ".bag");
    c.filter.static_sensor = true;
    c.filter.scale_to_scanner = true;
    c.clean.through_min_scans = through_scans;
    stats = run_clean_job(c);
    const test::BagContents out = read_bag(c.filter.output);
    const auto& scans = out.scans.at("/scan");
    const auto& cleaned = out.scans.at("/scan_clean");
    const auto& labels = out.scans.at("/scan_clean_labels");
    EXPECT_EQ(cleaned.size(), scans.size());
    EXPECT_EQ(labels.size(), scans.size());
    const test::WallsAndWalkers rates =
        test::walls_and_walkers(scans, [&](std::size_t k, std::size_t i) {
          const bool gone = removed(static_cast<CleanLabel>(labels.at(k).intensities.at(i)));
          EXPECT_EQ(gone, std::isnan(cleaned.at(k).ranges.at(i)));
          return gone;
        });
    // The rule is written twice, here and in tools/static_recording_eval.py (the figure in the
    // docs): they must agree.
    const auto py =
        test::static_recording_eval_py(source_path(""), c.filter.output, "/scan_clean_labels");
    EXPECT_TRUE(py.has_value()) << "tools/static_recording_eval.py failed";
    if (py) {
      EXPECT_EQ(py->wall_beams, rates.wall_beams) << py->printed;
      EXPECT_EQ(py->walker_beams, rates.walker_beams) << py->printed;
      EXPECT_NEAR(py->walls_kept, rates.walls_kept_rate(), 0.5e-4) << py->printed;
      EXPECT_NEAR(py->walkers_removed, rates.walkers_removed_rate(), 0.5e-4) << py->printed;
    }
    std::remove(c.filter.output.c_str());
    return rates;
  };
  CleanJobStats by_sensor, off;
  const test::WallsAndWalkers d = clean(kThroughScansBySensor, by_sensor);
  const test::WallsAndWalkers o = clean(0, off);
  RecordProperty("walls_kept", std::to_string(d.walls_kept_rate()));
  RecordProperty("walkers_removed", std::to_string(d.walkers_removed_rate()));
  EXPECT_EQ(by_sensor.config.through_min_scans, kStaticSensorThroughScans);
  EXPECT_GT(by_sensor.counts.vacated, 1000);
  EXPECT_EQ(off.counts.vacated, 0);
  // The targets: walls kept >= 0.999, walkers removed >= 0.98.
  EXPECT_GE(d.walls_kept_rate(), 0.999);
  EXPECT_GE(d.walkers_removed_rate(), 0.98);
  EXPECT_GE(o.walls_kept_rate(), 0.999);
  EXPECT_LT(o.walkers_removed_rate(), d.walkers_removed_rate() - 0.03);
}

TEST(CleanJob, ACarmenLogIsAOneLineErrorAndWritesNothing) {
  CleanJobOptions c;
  c.filter.input = source_path("data/carmen/leg_tracker_from0.log");
  c.filter.output = temp_path("carmen_clean.bag");
  try {
    run_clean_job(c);
    FAIL() << "a CARMEN log was cleaned";
  } catch (const JobError& e) {
    EXPECT_NE(std::string(e.what()).find("write the CARMEN log as a bag"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(test::exists(c.filter.output));
}

}  // namespace
}  // namespace dispel::jobs
