// The simulator's scenarios load, its bags hold the topics docs/simulator.md lists, and sim ->
// filter -> eval runs end to end.
#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <functional>
#include <map>
#include <utility>
#include <vector>

#include "dispel/io/scenario_yaml.hpp"
#include "dispel/jobs/eval_job.hpp"
#include "dispel/jobs/filter_job.hpp"
#include "dispel/jobs/sim_job.hpp"
#include "test_files.hpp"

namespace dispel::jobs {
namespace {

using namespace dispel::io;  // The formats the tests write and read.

std::string scenario_path(const std::string& name) {
  return std::string(DISPEL_SOURCE_DIR) + "/config/scenarios/" + name + ".yaml";
}

TEST(ScenarioYaml, ShippedScenariosLoadAndValidate) {
  for (const char* name :
       {"thesis_hall", "empty_hall", "busy_corridor", "warehouse_forklift", "office_corridors",
        "warehouse_aisles", "office_corridors_slam", "cluttered_hall", "office_revisits",
        "person_following", "person_following_stops"}) {
    const sim::Scenario s = load_scenario(scenario_path(name));
    EXPECT_EQ(s.name, name);
    // Every scripted actor goes past the furniture, pillars and walls, not through them.
    EXPECT_NO_THROW(sim::run_duration(s, 0.0)) << name;
  }
  const sim::Scenario thesis = load_scenario(scenario_path("thesis_hall"));
  EXPECT_EQ(thesis.lidar.range_limit_m, 5.5);
  EXPECT_EQ(thesis.lidar.masked_sectors_deg.size(), 2u);
  ASSERT_TRUE(thesis.robot.lawnmower.has_value());
  EXPECT_EQ(thesis.random_people.count, 6);
  EXPECT_TRUE(load_scenario(scenario_path("empty_hall")).actors.empty());
  const sim::Clutter clutter = load_scenario(scenario_path("cluttered_hall")).world.clutter;
  EXPECT_EQ(clutter.count, 150);
  EXPECT_EQ(clutter.area_max, Eigen::Vector2d(39.0, 23.0));
  EXPECT_EQ(clutter.min_radius_m, 0.02);
  EXPECT_EQ(clutter.max_radius_m, 0.15);
  EXPECT_EQ(clutter.return_share, 0.6);
  EXPECT_EQ(clutter.keep_clear_m, 1.0);
  const sim::RoughWalls office =
      *load_scenario(scenario_path("office_corridors")).world.rough_walls;
  EXPECT_EQ(office.low_things_min_radius_m, 0.075);  // Defaults.
  EXPECT_EQ(office.low_things_max_seen_within_m, 2.0);
  const sim::RoughWalls revisits =
      *load_scenario(scenario_path("office_revisits")).world.rough_walls;
  EXPECT_EQ(revisits.low_things_min_radius_m, 0.2);
  EXPECT_EQ(revisits.low_things_max_radius_m, 0.3);
  EXPECT_EQ(revisits.low_things_min_seen_within_m, 2.0);
  EXPECT_EQ(revisits.low_things_max_seen_within_m, 3.5);
  const sim::Scenario stops = load_scenario(scenario_path("person_following_stops"));
  ASSERT_EQ(stops.robot.stops.size(), 2u);
  ASSERT_EQ(stops.actors.at(0).stops.size(), 2u);
  EXPECT_LT(stops.actors[0].stops[0].at_s, stops.robot.stops[0].at_s);
}

TEST(ScenarioYaml, UnknownKeysAndBadValuesNameTheKey) {
  const auto expect_error = [](const std::string& yaml, const std::string& expected) {
    try {
      parse_scenario(yaml, "s.yaml");
      ADD_FAILURE() << yaml;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  };
  expect_error("lidar: {range_limt_m: 5}", "unknown key 'lidar.range_limt_m'");
  expect_error("lidar:\n  range_limit_m: 5\n  range_limit_m: 6\n",
               "key 'lidar.range_limit_m' is given twice");
  expect_error("lidar: {resolution_deg: 0}", "lidar.resolution_deg must be");
  expect_error("actors: [{type: dragon, standing: [0, 0]}]", "actors[0].type must be");
  expect_error("actors: [{type: person}]", "actors[0] needs waypoints or standing");
  expect_error("world: {walls: [[0, 0, 1]]}", "world.walls[0] must be a list of 4 numbers");
  expect_error("robot: {speed_mps: fast}", "robot.speed_mps must be a number");
  expect_error("world: {clutter: {count: 5, area: [0, 0, 1]}}",
               "world.clutter.area must be a list of 4 numbers");
  expect_error("world: {clutter: {count: 5, area: [0, 0, 1, 1], return_share: 2}}",
               "world.clutter.return_share must be");
  expect_error("world: {clutter: {cuont: 5}}", "unknown key 'world.clutter.cuont'");
  expect_error("lidar: {speckle: 0.1, speckle_range_m: [4]}",
               "lidar.speckle_range_m must be a list of 2 numbers");
  expect_error("lidar: {speckle: 1.5}", "lidar.speckle must be");
  const sim::Scenario speckled = parse_scenario(
      "lidar: {range_max_m: 5.6, speckle: 0.016, speckle_range_m: [4.0, 5.6], "
      "speckle_beams_max: 3}",
      "s.yaml");
  EXPECT_EQ(speckled.lidar.speckle, 0.016);
  EXPECT_EQ(speckled.lidar.speckle_range_m, std::make_pair(4.0, 5.6));
  EXPECT_EQ(speckled.lidar.speckle_beams_max, 3);
  const sim::Scenario dark =
      parse_scenario("lidar: {range_max_m: 5.6, dark_share: 0.5, dark_reach_m: 5.0}", "s.yaml");
  EXPECT_EQ(dark.lidar.dark_share, 0.5);
  EXPECT_EQ(dark.lidar.dark_reach_m, 5.0);
  expect_error("lidar: {range_max_m: 5.6, dark_share: 0.5, dark_reach_m: 9}",
               "lidar.dark_reach_m must be");
  const sim::Scenario bumpy = parse_scenario(
      "lidar: {height_m: 0.3, bumps_per_min: 4, bump_tilt_deg: 8, bump_s: 0.5}", "s.yaml");
  EXPECT_EQ(bumpy.lidar.height_m, 0.3);
  EXPECT_EQ(bumpy.lidar.bumps_per_min, 4.0);
  EXPECT_EQ(bumpy.lidar.bump_tilt_deg, 8.0);
  EXPECT_EQ(bumpy.lidar.bump_s, 0.5);
  expect_error("lidar: {bumps_per_min: 4, bump_tilt_deg: 8}", "lidar.height_m must be");
  expect_error("lidar: {height_m: 0.3, bumps_per_min: 4, bump_tilt_deg: 8, bump_s: 20}",
               "lidar.bump_s must be");
  const sim::Scenario stopping = parse_scenario(
      "robot: {waypoints: [[5, 0]], stops: [[2, 10], [30, 5]]}\n"
      "actors: [{type: person, waypoints: [[1, 1], [4, 1]], stops: [[1.5, 10.5]]}]\n",
      "s.yaml");
  ASSERT_EQ(stopping.robot.stops.size(), 2u);
  EXPECT_EQ(stopping.robot.stops[1].at_s, 30.0);
  EXPECT_EQ(stopping.robot.stops[1].for_s, 5.0);
  ASSERT_EQ(stopping.actors.at(0).stops.size(), 1u);
  EXPECT_EQ(stopping.actors[0].stops[0].for_s, 10.5);
  EXPECT_EQ(parse_scenario("gait: planted", "s.yaml").gait, sim::Gait::kPlanted);
  EXPECT_EQ(parse_scenario("name: x", "s.yaml").gait, sim::Gait::kSway);
  expect_error("gait: run", "gait must be sway or planted, got 'run'");
  expect_error("robot: {stops: [[2]]}", "robot.stops[0] must be a list of 2 numbers");
  expect_error("robot: {stops: 3}", "robot.stops must be a list of [at_s, for_s]");
  expect_error("robot: {stops: [[2, 0]]}", "robot.stops[0].for_s must be");
  expect_error("actors: [{type: person, waypoints: [[1, 1], [4, 1]], stops: [[-1, 2]]}]",
               "actors[0].stops[0].at_s must be");
  expect_error("world: {rough_walls: {low_things_radius_m: [0.2]}}",
               "world.rough_walls.low_things_radius_m must be a list of 2 numbers");
  expect_error("world: {rough_walls: {low_things_seen_within_m: [3, 2]}}",
               "world.rough_walls.low_things_seen_within_m must be");
  expect_error("world: {rough_walls: {glass_returns_within_deg: 90}}",
               "world.rough_walls.glass_returns_within_deg must be");
  const sim::Scenario glass = parse_scenario(
      "world: {rough_walls: {glass_share: 0.2, glass_returns_within_deg: 5}}", "s.yaml");
  ASSERT_TRUE(glass.world.rough_walls.has_value());
  EXPECT_EQ(glass.world.rough_walls->glass_returns_within_deg, 5.0);
  // Issue 16: NaN and infinite walls and noise were accepted.
  expect_error("world: {walls: [[0, 0, .nan, 1]]}",
               "world.walls[0][2] must be a finite number, got '.nan'");
  expect_error("world: {walls: [[0, 0, .inf, 1]]}", "world.walls[0][2] must be a finite number");
  expect_error("lidar: {range_noise_m: -.inf}", "lidar.range_noise_m must be a finite number");
  expect_error("", "s.yaml: the scenario file is empty");
  expect_error("# nothing\n", "s.yaml: the scenario file is empty");
  expect_error("[1, 2]", "s.yaml: the file must be a mapping");
  // An echoed value is cut: a 1 MB word gives a short line.
  try {
    parse_scenario("robot: {speed_mps: " + std::string(1000000, 'x') + "}", "s.yaml");
    ADD_FAILURE();
  } catch (const ConfigError& e) {
    EXPECT_LT(std::string(e.what()).size(), 200u) << e.what();
  }
}

TEST(SimPipeline, SimulatedBagHasEveryTopicAndFiltersAndEvaluates) {
  sim::Scenario s = load_scenario(scenario_path("thesis_hall"));
  const sim::SimulationOutput run = sim::simulate(s, 7, 10.0);
  const std::string bag_path = test::temp_dir() + "/sim.bag";
  write_simulation(run, s, bag_path);
  std::map<std::string, int> count;
  {
    rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
    rosbag::View view(bag);
    for (const rosbag::MessageInstance& m : view) ++count[m.getTopic()];
  }
  EXPECT_EQ(count["/scan"], 201);
  EXPECT_EQ(count["/scan_truth"], 201);
  EXPECT_EQ(count["/scan_truth_actor"], 201);
  EXPECT_EQ(count["/odom"], 501);
  EXPECT_EQ(count["/wheels"], 501);
  EXPECT_EQ(count["/imu"], 501);
  EXPECT_EQ(count["/ground_truth"], 501);
  EXPECT_EQ(count["/tf_static"], 1);

  FilterJobOptions o;
  o.input = bag_path;
  o.output = test::temp_dir() + "/sim_filtered.bag";
  o.config_path = std::string(DISPEL_SOURCE_DIR) + "/config/default_masked.yaml";
  const FilterJobStats stats = run_filter_job(o);
  EXPECT_EQ(stats.scans_filtered, 201);
  const eval::Rates r = evaluate_bags(bag_path, o.output);
  EXPECT_EQ(r.scans, 201);
  EXPECT_GT(r.static_beams, 1000);
  EXPECT_GT(r.moving_beams, 1000);
  EXPECT_GE(r.preservation_rate(), 0.99);
  EXPECT_GT(r.rejection_rate(), 0.0);
  EXPECT_THROW(evaluate_bags(o.output + ".nope", o.output), JobError);
  const std::string real =
      std::string(DISPEL_SOURCE_DIR) + "/data/leg_tracker/demo_stationary_simple_environment.bag";
  EXPECT_THROW(evaluate_bags(real, o.output), JobError);  // A recording has no truth.
  EXPECT_THROW(evaluate_bags(bag_path, real), JobError);  // Not filtered.
  std::remove(bag_path.c_str());
  std::remove(o.output.c_str());
}

std::string file_bytes(const std::string& path) {
  std::string bytes;
  if (FILE* f = std::fopen(path.c_str(), "rb")) {
    char buffer[65536];
    for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, f)) > 0;) bytes.append(buffer, n);
    std::fclose(f);
  }
  return bytes;
}

// `dispel sim` streams the run into the bag as it is made: the same bytes as the run held in
// memory and then written (one writer class for both), with the same counts.
TEST(SimPipeline, AStreamedBagIsTheHeldRunsBag) {
  const sim::Scenario s = load_scenario(scenario_path("thesis_hall"));
  const std::string held = test::temp_dir() + "/held.bag";
  const std::string streamed = test::temp_dir() + "/streamed.bag";
  const sim::SimulationOutput run = sim::simulate(s, 3, 5.0);
  write_simulation(run, s, held);
  const SimulationSummary summary = simulate_to_recording(s, 3, 5.0, streamed);
  EXPECT_EQ(summary.scans, static_cast<std::int64_t>(run.scans.size()));
  EXPECT_EQ(summary.actor_count, run.actor_count);
  std::array<std::int64_t, 4> beams{};
  for (const sim::ScanFrame& f : run.scans) {
    for (const sim::Truth t : f.truth) ++beams[static_cast<std::size_t>(t)];
  }
  EXPECT_EQ(summary.beams, beams);
  EXPECT_GT(beams[static_cast<std::size_t>(sim::Truth::kMoving)], 0);
  const std::string a = file_bytes(held);
  EXPECT_GT(a.size(), 100000u);
  EXPECT_TRUE(a == file_bytes(streamed)) << "the streamed bag differs from the held run's";
  std::remove(held.c_str());
  std::remove(streamed.c_str());
}

// A run whose bag would not fit on the disk is refused before any work, in one line naming the
// duration and both sizes, and nothing is written.
TEST(SimPipeline, ARunThatWouldNotFitOnTheDiskIsRefusedBeforeAnyWork) {
  const sim::Scenario s = load_scenario(scenario_path("thesis_hall"));
  const std::string path = test::temp_dir() + "/too_long.bag";
  // The estimate: 1618 beams at 20 Hz and 50 Hz of samples, 0.76 MB per second before LZ4, about
  // 0.16 MB after it (an upper bound: this scenario's bags compress to 0.03 MB per second).
  const double per_second = estimate_recording_bytes(s, 1000.0) / 1000.0;
  EXPECT_GT(per_second, 0.1e6);
  EXPECT_LT(per_second, 0.3e6);
  try {
    simulate_to_recording(s, 1, 1e9, path);
    ADD_FAILURE() << "a run of 1e9 s was started";
  } catch (const JobError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("--duration 1e+09 s would write a bag of about ", 0), 0u) << what;
    EXPECT_NE(what.find(" TB, but "), std::string::npos) << what;
    EXPECT_NE(what.find(" free"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  struct stat st {};
  EXPECT_NE(::stat(path.c_str(), &st), 0);
  EXPECT_NE(::stat((path + ".partial").c_str(), &st), 0);
  // Stamps a bag cannot hold are refused by the simulator's own rule, by name.
  EXPECT_THROW(simulate_to_recording(s, 1, 5e9, path), JobError);
}

// The targets of the simulator issue, on the thesis's scenario (three seeds, one minute each):
// dispel's default configuration keeps >= 99 % of the static beams, removes >= 90 % of the moving
// ones and finds a walker within a second (median); the thesis's filter, run on the same bags,
// does not. Also the empty hall: with nobody there, every removed beam is a false positive.
// A robot that drives (1 m/s) along rough office corridors with a 768-beam 7.5 Hz scanner mounted
// off-centre and yawed, beams over the sweep, drifting odometry: the walls that slide along the
// robot as it passes them used to become "walkers" (preservation 0.895 on seed 1 before the
// registration and the map's explanation; 0.41 on a real robot). Seed 1, the whole minute:
// measured 0.9983 kept and 0.897 removed (0.9963 and 0.897 before a dynamic track that stood
// still alone became static again, 0.9989 and 0.817 before free space was asked about a walker's
// hidden leg, below; 0.998 and 0.83 while a walker walked through a low thing and
// brushed through a cabinet; 0.993 and 0.82 before the simulated robot rounded its corners; the
// issue's targets are 0.995 and 0.90: the rejection target is not reached, docs/results.md).
// A shipped moving scenario, simulated (seed 1 unless told), filtered with dispel's default
// scaled to its scanner and evaluated, and also with the default changed by each of @p variants;
// the bags are removed.
using ConfigChange = std::function<void(DynamicFilterConfig&)>;
struct FilteredScenario {
  FilterJobStats stats;
  eval::Rates rates;
  std::vector<eval::Rates> variant_rates;
};
FilteredScenario simulate_and_filter(
    const char* scenario, const std::vector<ConfigChange>& variants = {}, int seed = 1,
    const std::function<void(FilterJobOptions&)>& options = {},
    const std::function<void(sim::Scenario&)>& change_scenario = {}) {
  const std::string dir = test::temp_dir();
  sim::Scenario s = load_scenario(scenario_path(scenario));
  if (change_scenario) change_scenario(s);
  const std::string bag = dir + "/" + scenario + ".bag";
  write_simulation(sim::simulate(s, seed), s, bag);
  FilterJobOptions o;
  o.input = bag;
  o.output = dir + "/" + scenario + "_filtered.bag";
  o.scale_to_scanner = true;
  if (options) options(o);
  FilteredScenario out{run_filter_job(o), evaluate_bags(bag, o.output), {}};
  for (const ConfigChange& change : variants) {
    o.config = DynamicFilterConfig{};
    change(*o.config);
    run_filter_job(o);
    out.variant_rates.push_back(evaluate_bags(bag, o.output));
  }
  std::remove(bag.c_str());
  std::remove(o.output.c_str());
  return out;
}

// The walker who walks beside the robot at its pace (0.8-1.0 m to its right for 24 s) hides one
// leg behind the other for seconds at a time. The hidden leg's track, static since the leg last
// stood, is too old for free space to be asked about it; when the leg steps out into space seen
// free beside the leg tracked as dynamic, free space is asked all the same
// (free_space.mark_beside_dynamic). Without it the leg was kept for about 3 scans at every such
// step: 0.817 removed against 0.897 (and 0.9990 kept against 0.9983). Since far points within
// three beam spacings join (segmentation.cluster_gap_spacings) the default removes 0.909 and
// 0.888 without the rule (0.887 and 0.835 with eps alone).
// When that walker's route ends, a leg's dynamic track, lost for a few scans with its gate
// widened, was matched to a low thing first seen up close nearby and stayed dynamic while it
// stood (still_scans_to_static), its beams never learned by the map: 0.9963 kept without
// classification.still_alone_to_static_s (a dynamic track that stood still for 1 s where it was
// seen again after scans unseen, with no dynamic track beside it, is static again), 0.9983 with
// it. Both were while free space was traced along the beams as placed from the scan's stamp,
// not as the registration de-skewed them: at a corner the end of each sweep then lay off the
// walls of the next scans. Traced along the de-skewed beams: 0.9995 kept, and 0.9994 without
// that rule (docs/results.md, "Free space along the de-skewed beams").
TEST(SimPipeline, DrivingRobotAlongRoughCorridorsKeepsItsWalls) {
  const FilteredScenario office = simulate_and_filter(
      "office_corridors",
      {[](DynamicFilterConfig& c) { c.free_space.mark_beside_dynamic = false; },
       [](DynamicFilterConfig& c) { c.classification.still_alone_to_static_s = 0.0; }});
  EXPECT_GE(office.rates.preservation_rate(), 0.999);
  EXPECT_GE(office.rates.rejection_rate(), 0.85);
  const eval::Rates& without_beside = office.variant_rates.at(0);
  EXPECT_GE(without_beside.preservation_rate(), 0.995);
  EXPECT_GE(office.rates.rejection_rate() - without_beside.rejection_rate(), 0.015);
  const eval::Rates& without_still = office.variant_rates.at(1);
  EXPECT_GE(without_still.preservation_rate(), 0.999);
  // The first scans may fall back to the odometry while the map is young (measured: 461 of 462
  // registered; 443 of 457 before the robot rounded its corners).
  EXPECT_GE(static_cast<double>(office.stats.counters.scans_registered),
            0.95 * static_cast<double>(office.stats.scans));
  EXPECT_EQ(office.stats.counters.scans_without_odometry, 0);
}

// A robot following a walker outdoors, laser-only (person_following.yaml: 86 degrees of view,
// 5.6 m, a few trees and posts in range, the walker 1.7 m ahead half of what the scanner sees),
// filtered as `dispel filter --odom-topic none` does (not scaled). The scans register on 20-40
// points. Without the three laser-only rules the registered pose slid sideways and turned (1 m/s
// sideways and 14-20 degrees/s within 2 s of a straight drive), a run of fallbacks carried a
// guessed turn on until the pose had turned a full circle, and the walker ahead held the robot
// back; the map then slid past everything. Seed 4, the whole 90 s: measured 0.951 of the static
// beams kept and 0.783 of the moving removed, 0.550 and 0.885 without the rules (seeds 1-10:
// 0.880 and 0.882 with, 0.718 and 0.894 without; docs/results.md). Since a free-space verdict
// whose track jumps farther than a walker gets is refuted at once (December 7, seventh session),
// 0.952 and 0.783 with the rules and 0.772 and 0.872 without (why the variant gains is not
// traced).
TEST(SimPipeline, ALaserOnlyRobotFollowingAWalkerKeepsItsBackground) {
  const FilteredScenario following =
      simulate_and_filter("person_following", {[](DynamicFilterConfig& c) {
                            c.registration.lateral_noise_mps = 0.0;
                            c.registration.fallback_turn_decay_s = 0.0;
                            c.registration.leave_out_moving = false;
                          }},
                          4, [](FilterJobOptions& o) {
                            o.odom_topic = "none";
                            o.scale_to_scanner = false;
                          });
  EXPECT_GE(following.rates.preservation_rate(), 0.93);
  EXPECT_GE(following.rates.rejection_rate(), 0.7);
  EXPECT_GT(following.stats.counters.registration_held_sideways, 0);
  EXPECT_EQ(following.stats.counters.scans_without_odometry, following.stats.scans);
  EXPECT_LE(following.variant_rates.at(0).preservation_rate(), 0.85);
}

// What N_min by width cost outdoors. person_following_outdoor_1 (a real robot outdoors, 5.6 m
// scanner) returns 1-4 beams at 4-5.6 m among beams with no return, in one scan and not the next:
// about one beam in 60 of those with no return starts such a run. With segmentation.min_width_m
// 0.1 the real recording kept 0.836 of its background (0.960 without); the simulator, until it had
// speckle, kept everything either way. With the recording's speckle the scenario showed the loss
// (seed 1, with the wheel odometry: 0.9989 kept by the default, 0.9080 with the option). A thing
// below min_points is now an object only where the two scans before it had a return within
// 0.3 m (a walker's legs; not a sporadic return): measured 0.9975 with the option. (Since
// December 7 N_min falls only within 0.8 of range_max, short of most of the speckle.)
TEST(SimPipeline, SpeckleOutdoorsIsNotTakenForFarLegs) {
  const FilteredScenario outdoors = simulate_and_filter(
      "person_following", {[](DynamicFilterConfig& c) { c.segmentation.min_width_m = 0.1; }}, 1,
      [](FilterJobOptions& o) { o.scale_to_scanner = false; },
      [](sim::Scenario& s) {
        s.lidar.speckle = 0.016;
        s.lidar.speckle_range_m = {4.0, 5.6};
      });
  EXPECT_GE(outdoors.rates.preservation_rate(), 0.99);
  EXPECT_GE(outdoors.variant_rates.at(0).preservation_rate(), 0.99);
  // And the option still removes more of the walkers (measured 0.927 -> 0.960).
  EXPECT_GT(outdoors.variant_rates.at(0).rejection_rate(), outdoors.rates.rejection_rate());
}

// The office driven twice round (200 s) with larger low things, which a tilted scan plane sees
// only up close: beams passed over where they stand. One first hit beside a walker is in space
// seen free and beside a dynamic track, so free space marks it however old its track is
// (free_space.mark_beside_dynamic); 0.4 s later it has not moved. It is static again: what marked
// it (standing beside a walker) does not also confirm it, as it does a walker's planted foot.
// Seed 3: measured 0.9963 of the static beams kept (0.9909 when the walker beside it confirmed
// it; 0.9922 without classification.still_alone_to_static_s; 0.9932 before either rule).
TEST(SimPipeline, ALowThingFirstSeenBesideAWalkerIsNotConfirmedByTheWalker) {
  const FilteredScenario revisits = simulate_and_filter("office_revisits", {}, 3);
  EXPECT_GE(revisits.rates.preservation_rate(), 0.995);
  EXPECT_GE(revisits.rates.rejection_rate(), 0.85);  // Measured 0.879.
}

// A warehouse aisle at 1 m/s (seed 1, the whole minute). A cart drives to and fro along the end
// aisle, its long side to the robot: the side slides along itself, and the robot first sees it
// at 10-11 m, in pieces kept as static. The registered map learned its trail, and the cart's
// side was then explained by its own earlier passes and kept (1838 of its 3817 beams removed;
// 0.52 of all moving beams, 0.9990 of the static ones kept). A voxel hit again where the scanner
// has long seen through is started afresh: 2309 of the cart's, 0.605 and 0.9997 (with the mixed
// pixels at removed edges removed too, tracking.remove_edge_pixels: 2372, 0.631).
// The pieces at 10-11 m were the segmentation's: the cart seen at a slant there has its points
// 6-27 cm apart, beyond eps (0.1 m). Joined within three beam spacings
// (segmentation.cluster_gap_spacings; 18 cm at 10 m), the cart is one object tracked as it
// crosses: measured 0.771 of the moving beams removed and 1.0000 of the static kept; 0.581 and
// 0.9998 with eps alone. Other seeds go the other way: on seed 2 the cart at 10 m, one object cut
// by a rack's end, stays static (0.698 -> 0.537; five seeds 0.626 -> 0.633,
// docs/dynamic_filter.md). The target (0.90 removed) is not reached.
TEST(SimPipeline, AWarehouseCartIsNotExplainedByItsOwnEarlierPasses) {
  const FilteredScenario aisles = simulate_and_filter(
      "warehouse_aisles",
      {[](DynamicFilterConfig& c) { c.segmentation.cluster_gap_spacings = 0.0; }});
  EXPECT_GE(aisles.rates.preservation_rate(), 0.9995);
  EXPECT_GE(aisles.rates.rejection_rate(), 0.72);
  const eval::Rates& eps_only = aisles.variant_rates.at(0);
  EXPECT_GE(eps_only.preservation_rate(), 0.9995);
  EXPECT_GE(eps_only.rejection_rate(), 0.55);
  EXPECT_GE(aisles.rates.rejection_rate() - eps_only.rejection_rate(), 0.1);
  EXPECT_GT(aisles.stats.counters.map_voxels_restarted, 0);
}

// The warehouse aisle at 1.5 m/s (seed 2). The cart drives to and fro along the end aisle, its
// long side to the robot, and the map explains it by its own earlier passes. An explained object
// gives no motion evidence: a static surface's outline slides as the sensor moves. But it slides
// along the surface only as fast as the sensor moves along it, and here the robot drives towards
// the aisle, across the cart's line: the cart's side, its outline its own at both ends, moves
// along itself at 1 m/s and the sensor along it at about 0 (registration.slide_tolerance_mps).
// Measured 0.803 of the moving beams removed (the cart 3515 of its 4457 beams), 0.746 with the
// tolerance 0 (2988); 0.9996 of the static beams kept either way. Those figures are with eps
// alone (segmentation.cluster_gap_spacings 0), as this test runs: with the default the cart is
// one object at 10 m, tracked on its far passes, and the map no longer explains it on this seed
// (0.886 removed with the tolerance and without; 0.810 and 0.754 with eps alone, measured
// December 7).
TEST(SimPipeline, ACartExplainedByItsOwnPassesMovesUnlikeASlidingOutline) {
  const FilteredScenario aisles = simulate_and_filter(
      "warehouse_aisles", {[](DynamicFilterConfig& c) {
        c.segmentation.cluster_gap_spacings = 0.0;
        c.registration.slide_tolerance_mps = 0.0;
      }},
      2,
      [](FilterJobOptions& o) {
        o.config = DynamicFilterConfig{};
        o.config->segmentation.cluster_gap_spacings = 0.0;
      },
      [](sim::Scenario& s) { s.robot.speed_mps = 1.5; });
  const eval::Rates& without = aisles.variant_rates.at(0);
  EXPECT_GE(aisles.rates.preservation_rate(), 0.9993);
  EXPECT_GE(without.preservation_rate(), 0.9993);
  EXPECT_GE(aisles.rates.rejection_rate(), 0.78);
  EXPECT_LE(without.rejection_rate(), 0.76);
}

// An open hall whose walls are mostly out of range, full of small things whose returns flicker,
// people crossing it far from the robot. The default keeps the clutter (it never moves). With eps
// alone it missed many of the walkers: each leg is 2-3 beams at 5-10 m, under N_min, and only
// those first seen nearer were followed out there through their fragments (measured over five
// seeds: 0.9994 kept, 0.63 removed; 0.38 before they were followed). A walker's two legs are
// 10-25 cm apart: within three beam spacings out there (segmentation.cluster_gap_spacings: 15 cm at
// 8 m) they are one object of 4-6 beams. N_min falling with range (segmentation.min_width_m 0.1,
// off by default: on real recordings it removes far clutter, docs/dynamic_filter.md) adds the
// single legs. Seed 1, measured: 0.861 removed by the default, 0.62 with eps alone, 0.911 with
// min_width_m.
TEST(SimPipeline, AnOpenClutteredHallKeepsItsClutterAndFarWalkersAreObjectsWithinBeamSpacings) {
  const std::string dir = test::temp_dir();
  const sim::Scenario hall = load_scenario(scenario_path("cluttered_hall"));
  const std::string bag = dir + "/hall.bag";
  write_simulation(sim::simulate(hall, 1), hall, bag);
  const std::vector<ConfigChange> configs = {
      [](DynamicFilterConfig&) {},
      [](DynamicFilterConfig& c) { c.segmentation.cluster_gap_spacings = 0.0; },
      [](DynamicFilterConfig& c) { c.segmentation.min_width_m = 0.1; }};
  std::vector<double> removed;
  for (std::size_t k = 0; k < configs.size(); ++k) {
    FilterJobOptions o;
    o.input = bag;
    o.output = dir + "/hall_filtered.bag";
    o.scale_to_scanner = true;
    o.config = DynamicFilterConfig{};
    configs[k](*o.config);
    run_filter_job(o);
    const eval::Rates r = evaluate_bags(bag, o.output);
    EXPECT_GE(r.preservation_rate(), 0.995) << "configuration " << k;
    removed.push_back(r.rejection_rate());
    std::remove(o.output.c_str());
  }
  EXPECT_GE(removed[0], 0.80);
  EXPECT_LT(removed[1], 0.75);
  EXPECT_GE(removed[0] - removed[1], 0.15);
  EXPECT_GE(removed[2], 0.85);
  std::remove(bag.c_str());
}

// At 1.5 m/s the simulated robot used to swing 2.5 m wide at the office's corners, through the
// outer wall, and scan the building from outside (the walls "lost" at 1.5 m/s, docs/results.md).
// It now slows for corners and turns in before them; a run that drives through a wall is refused.
TEST(SimPipeline, TheShippedRobotsStayInTheirCorridorsAtEverySpeed) {
  for (const char* name : {"office_corridors", "warehouse_aisles"}) {
    sim::Scenario s = load_scenario(scenario_path(name));
    s.robot.speed_mps = 1.5;
    double min_x = 1e9, max_x = -1e9, min_y = 1e9, max_y = -1e9;
    sim::SimulationSink sink;
    sink.sensor = [&](const sim::SensorSample& k) {
      min_x = std::min(min_x, k.true_pose.x_m);
      max_x = std::max(max_x, k.true_pose.x_m);
      min_y = std::min(min_y, k.true_pose.y_m);
      max_y = std::max(max_y, k.true_pose.y_m);
    };
    ASSERT_NO_THROW(sim::simulate(s, 2, 0.0, sink)) << name;
    if (std::string(name) == "office_corridors") {
      // The corridors' outer walls are at x = -1.1 and 31.1, y = -1.1 and 15.1.
      EXPECT_GT(min_x, -1.1 + 0.3);
      EXPECT_LT(max_x, 31.1 - 0.3);
      EXPECT_GT(min_y, -1.1 + 0.3);
      EXPECT_LT(max_y, 15.1 - 0.3);
    }
  }
}

TEST(SimPipeline, DefaultConfigurationMeetsTheTargetsOnTheThesisHall) {
  const std::string dir = test::temp_dir();
  const auto filter_and_evaluate = [&](const std::string& bag, const std::string& config) {
    FilterJobOptions o;
    o.input = bag;
    o.output = dir + "/targets_filtered.bag";
    o.config_path = std::string(DISPEL_SOURCE_DIR) + "/config/" + config;
    run_filter_job(o);
    const eval::Rates r = evaluate_bags(bag, o.output);
    std::remove(o.output.c_str());
    return r;
  };
  eval::Rates ours, thesis;
  std::vector<double> median_latency;
  const sim::Scenario hall = load_scenario(scenario_path("thesis_hall"));
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const std::string bag = dir + "/targets_hall.bag";
    write_simulation(sim::simulate(hall, seed), hall, bag);
    const eval::Rates a = filter_and_evaluate(bag, "default_masked.yaml");
    const eval::Rates b = filter_and_evaluate(bag, "thesis_masked.yaml");
    std::remove(bag.c_str());
    for (auto [sum, one] : {std::pair{&ours, &a}, std::pair{&thesis, &b}}) {
      sum->static_beams += one->static_beams;
      sum->static_kept += one->static_kept;
      sum->moving_beams += one->moving_beams;
      sum->moving_removed += one->moving_removed;
    }
    median_latency.push_back(a.latency_median_s());
    EXPECT_GE(a.preservation_rate(), 0.99) << "seed " << seed;
  }
  EXPECT_GE(ours.preservation_rate(), 0.99);
  EXPECT_GE(ours.rejection_rate(), 0.90);
  std::sort(median_latency.begin(), median_latency.end());
  EXPECT_LT(median_latency[1], 1.0);
  EXPECT_LT(thesis.rejection_rate(), 0.6);  // Measured about 0.46.
  RecordProperty("preservation_rate", std::to_string(ours.preservation_rate()));
  RecordProperty("rejection_rate", std::to_string(ours.rejection_rate()));

  const sim::Scenario empty = load_scenario(scenario_path("empty_hall"));
  const std::string bag = dir + "/targets_empty.bag";
  write_simulation(sim::simulate(empty, 1), empty, bag);
  const eval::Rates e = filter_and_evaluate(bag, "default_masked.yaml");
  std::remove(bag.c_str());
  EXPECT_EQ(e.moving_beams, 0);
  EXPECT_GE(e.preservation_rate(), 0.99);
}

}  // namespace
}  // namespace dispel::jobs
