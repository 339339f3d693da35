#include "dispel/io/config_yaml.hpp"

#include <gtest/gtest.h>

#include <set>
#include <string>

namespace dispel::io {
namespace {

std::string default_yaml() { return std::string(DISPEL_SOURCE_DIR) + "/config/default.yaml"; }

void expect_error(const std::string& yaml, const std::string& expected) {
  try {
    parse_filter_config(yaml, "test.yaml");
    ADD_FAILURE() << "accepted: " << yaml;
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("test.yaml: "), std::string::npos) << what;
    EXPECT_NE(what.find(expected), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << "not one line: " << what;
  }
}

// Every field of two configurations is equal.
void expect_same(const DynamicFilterConfig& loaded, const DynamicFilterConfig& d) {
  EXPECT_EQ(loaded.segmentation.cluster_gap_m, d.segmentation.cluster_gap_m);
  EXPECT_EQ(loaded.segmentation.cluster_gap_spacings, d.segmentation.cluster_gap_spacings);
  EXPECT_EQ(loaded.segmentation.min_points, d.segmentation.min_points);
  EXPECT_EQ(loaded.segmentation.min_width_m, d.segmentation.min_width_m);
  EXPECT_EQ(loaded.segmentation.gap_metric, d.segmentation.gap_metric);
  EXPECT_EQ(loaded.segmentation.masked_sectors.size(), d.segmentation.masked_sectors.size());
  EXPECT_EQ(loaded.tracking.match_distance_m, d.tracking.match_distance_m);
  EXPECT_EQ(loaded.tracking.matching, d.tracking.matching);
  EXPECT_EQ(loaded.tracking.max_missed_scans, d.tracking.max_missed_scans);
  EXPECT_EQ(loaded.tracking.max_gate_m, d.tracking.max_gate_m);
  EXPECT_EQ(loaded.tracking.max_extent_change_m, d.tracking.max_extent_change_m);
  EXPECT_EQ(loaded.tracking.companion_distance_m, d.tracking.companion_distance_m);
  EXPECT_EQ(loaded.tracking.fragment_distance_m, d.tracking.fragment_distance_m);
  EXPECT_EQ(loaded.tracking.inherit_on_split, d.tracking.inherit_on_split);
  EXPECT_EQ(loaded.tracking.follow_fragments, d.tracking.follow_fragments);
  EXPECT_EQ(loaded.tracking.remove_edge_pixels, d.tracking.remove_edge_pixels);
  EXPECT_EQ(loaded.tracking.companion_speed_difference_mps,
            d.tracking.companion_speed_difference_mps);
  EXPECT_EQ(loaded.velocity.position_variance_m2, d.velocity.position_variance_m2);
  EXPECT_EQ(loaded.velocity.velocity_variance_m2ps2, d.velocity.velocity_variance_m2ps2);
  EXPECT_EQ(loaded.velocity.measurement_variance_m2, d.velocity.measurement_variance_m2);
  EXPECT_EQ(loaded.velocity.velocity_decay, d.velocity.velocity_decay);
  EXPECT_EQ(loaded.velocity.nominal_scan_period_s, d.velocity.nominal_scan_period_s);
  EXPECT_EQ(loaded.classification.presumption, d.classification.presumption);
  EXPECT_EQ(loaded.classification.speed_limit_mps, d.classification.speed_limit_mps);
  EXPECT_EQ(loaded.classification.dynamic_weight_limit, d.classification.dynamic_weight_limit);
  EXPECT_EQ(loaded.classification.static_weight_limit, d.classification.static_weight_limit);
  EXPECT_DOUBLE_EQ(loaded.classification.max_direction_difference_rad,
                   d.classification.max_direction_difference_rad);
  EXPECT_EQ(loaded.classification.max_dynamic_extent_m, d.classification.max_dynamic_extent_m);
  EXPECT_EQ(loaded.classification.max_point_count_ratio, d.classification.max_point_count_ratio);
  EXPECT_EQ(loaded.classification.still_scans_to_static, d.classification.still_scans_to_static);
  EXPECT_EQ(loaded.classification.still_alone_to_static_s,
            d.classification.still_alone_to_static_s);
  EXPECT_EQ(loaded.classification.slow_scans_reduce_dynamic_weight,
            d.classification.slow_scans_reduce_dynamic_weight);
  EXPECT_EQ(loaded.free_space.enabled, d.free_space.enabled);
  EXPECT_EQ(loaded.free_space.cell_size_m, d.free_space.cell_size_m);
  EXPECT_EQ(loaded.free_space.extent_m, d.free_space.extent_m);
  EXPECT_EQ(loaded.free_space.margin_m, d.free_space.margin_m);
  EXPECT_EQ(loaded.free_space.min_free_observations, d.free_space.min_free_observations);
  EXPECT_EQ(loaded.free_space.free_range_m, d.free_space.free_range_m);
  EXPECT_EQ(loaded.free_space.no_return_is_free, d.free_space.no_return_is_free);
  EXPECT_EQ(loaded.free_space.max_recent_hits, d.free_space.max_recent_hits);
  EXPECT_EQ(loaded.free_space.memory_s, d.free_space.memory_s);
  EXPECT_EQ(loaded.free_space.keep_long_occupied, d.free_space.keep_long_occupied);
  EXPECT_EQ(loaded.free_space.long_occupied_scans, d.free_space.long_occupied_scans);
  EXPECT_EQ(loaded.free_space.neighbourhood_cells, d.free_space.neighbourhood_cells);
  EXPECT_EQ(loaded.free_space.min_object_share, d.free_space.min_object_share);
  EXPECT_EQ(loaded.free_space.mark_beside_dynamic, d.free_space.mark_beside_dynamic);
  EXPECT_EQ(loaded.free_space.require_unseen, d.free_space.require_unseen);
  EXPECT_EQ(loaded.registration.deskew, d.registration.deskew);
  EXPECT_EQ(loaded.registration.deskew_laser_only_turn, d.registration.deskew_laser_only_turn);
  EXPECT_EQ(loaded.registration.align, d.registration.align);
  EXPECT_EQ(loaded.registration.slide_tolerance_mps, d.registration.slide_tolerance_mps);
  EXPECT_EQ(loaded.registration.lateral_noise_mps, d.registration.lateral_noise_mps);
  EXPECT_EQ(loaded.registration.fallback_turn_decay_s, d.registration.fallback_turn_decay_s);
  EXPECT_EQ(loaded.registration.leave_out_moving, d.registration.leave_out_moving);
  EXPECT_EQ(loaded.max_time_gap_s, d.max_time_gap_s);
  EXPECT_EQ(loaded.max_pose_jump_m, d.max_pose_jump_m);
  EXPECT_EQ(loaded.max_pose_jump_rad, d.max_pose_jump_rad);
  EXPECT_EQ(loaded.max_speed_mps, d.max_speed_mps);
  EXPECT_EQ(loaded.max_turn_rate_radps, d.max_turn_rate_radps);
}

TEST(ConfigYaml, ShippedDefaultFileHoldsExactlyTheDefaults) {
  expect_same(load_filter_config(default_yaml()), DynamicFilterConfig{});
  expect_same(parse_filter_config("", "empty.yaml"), DynamicFilterConfig{});
}

TEST(ConfigYaml, ShippedThesisFileHoldsExactlyTheThesisParameters) {
  expect_same(load_filter_config(std::string(DISPEL_SOURCE_DIR) + "/config/thesis.yaml"),
              thesis_config());
  const DynamicFilterConfig t = thesis_config();
  EXPECT_EQ(t.classification.dynamic_weight_limit, 18);
  EXPECT_EQ(t.velocity.measurement_variance_m2, 15.0);
  EXPECT_FALSE(t.free_space.enabled);
  EXPECT_EQ(t.tracking.companion_distance_m, 0.0);
  EXPECT_EQ(t.tracking.fragment_distance_m, 0.0);
  // The thesis's rules, not dispel's.
  EXPECT_EQ(t.tracking.matching, Matching::kNearestNeighbour);
  EXPECT_FALSE(t.tracking.inherit_on_split);
  EXPECT_FALSE(t.tracking.follow_fragments);
  EXPECT_FALSE(t.tracking.remove_edge_pixels);
  EXPECT_EQ(t.segmentation.gap_metric, GapMetric::kRangeDifference);
  EXPECT_FALSE(t.classification.slow_scans_reduce_dynamic_weight);
  EXPECT_EQ(t.classification.still_scans_to_static, 0);
  EXPECT_EQ(t.classification.still_alone_to_static_s, 0.0);
}

TEST(ConfigYaml, ShippedMaskedFilesAreTheirPresetsWithTheThesisScannersSectors) {
  const std::string dir = std::string(DISPEL_SOURCE_DIR) + "/config/";
  for (const auto& [file, preset] :
       {std::pair<std::string, DynamicFilterConfig>{"default_masked.yaml", DynamicFilterConfig{}},
        {"thesis_masked.yaml", thesis_config()}}) {
    DynamicFilterConfig loaded = load_filter_config(dir + file);
    ASSERT_EQ(loaded.segmentation.masked_sectors.size(), 2u) << file;
    loaded.segmentation.masked_sectors.clear();
    expect_same(loaded, preset);
  }
}

// For commands without --scale-to-scanner (dispel experiment on office_corridors_slam.yaml): the
// default carried over to a 768-beam 270-degree 7.5 Hz scanner, as scale_to_scanner() does it.
TEST(ConfigYaml, ShippedScannerFileIsTheDefaultCarriedOverToItsScanner) {
  const DynamicFilterConfig loaded =
      load_filter_config(std::string(DISPEL_SOURCE_DIR) + "/config/scanner_768_7hz.yaml");
  expect_same(loaded, scale_to_scanner(DynamicFilterConfig{}, 0.352 * kPi / 180.0, 1.0 / 7.5));
}

TEST(ConfigYaml, PresetIsTheStartingPointWhereverItStands) {
  // The preset applies first even when written after other keys.
  const DynamicFilterConfig c = parse_filter_config(
      "classification: {dynamic_weight_limit: 5}\npreset: thesis\n", "test.yaml");
  EXPECT_EQ(c.classification.dynamic_weight_limit, 5);
  EXPECT_EQ(c.velocity.measurement_variance_m2, thesis_config().velocity.measurement_variance_m2);
  EXPECT_FALSE(c.free_space.enabled);
  const DynamicFilterConfig d = parse_filter_config("preset: default\n", "test.yaml");
  expect_same(d, DynamicFilterConfig{});
  expect_error("preset: thesys", "preset must be one of default, thesis, got 'thesys'");
  expect_error("preset: [thesis]", "preset must be a word");
}

TEST(ConfigYaml, ValuesAreReadIntoTheirFields) {
  const DynamicFilterConfig c = parse_filter_config(
      "segmentation: {cluster_gap_m: 0.2, cluster_gap_spacings: 2.5, gap_metric: range_difference,"
      " min_width_m: 0.15, masked_sectors: [[-0.5, -0.1], [0.1, 0.5]]}\n"
      "tracking: {matching: nearest_neighbour}\n"
      "classification: {presumption: guilt, static_weight_limit: 20}\n"
      "free_space: {require_unseen: always}\n"
      "max_pose_jump_m: 2.0\n",
      "test.yaml");
  EXPECT_EQ(c.segmentation.cluster_gap_m, 0.2);
  EXPECT_EQ(c.segmentation.cluster_gap_spacings, 2.5);
  EXPECT_EQ(c.segmentation.gap_metric, GapMetric::kRangeDifference);
  EXPECT_EQ(c.segmentation.min_width_m, 0.15);
  ASSERT_EQ(c.segmentation.masked_sectors.size(), 2u);
  EXPECT_EQ(c.segmentation.masked_sectors[1].end_rad, 0.5);
  EXPECT_EQ(c.tracking.matching, Matching::kNearestNeighbour);
  EXPECT_EQ(c.classification.presumption, Presumption::kGuilt);
  EXPECT_EQ(c.classification.static_weight_limit, 20);
  EXPECT_EQ(c.free_space.require_unseen, RequireUnseen::kAlways);
  EXPECT_EQ(c.max_pose_jump_m, 2.0);
  EXPECT_EQ(c.segmentation.min_points, 8);  // Untouched keys keep their defaults.
  EXPECT_EQ(c.tracking.max_missed_scans, DynamicFilterConfig{}.tracking.max_missed_scans);
  EXPECT_NO_THROW(parse_filter_config("", "empty.yaml"));
}

TEST(ConfigYaml, UnknownKeysWrongTypesAndBadValuesAreErrorsNamingTheKey) {
  expect_error("segmentation: {cluster_gapm: 0.1}", "unknown key 'segmentation.cluster_gapm'");
  expect_error("tracker: {}", "unknown key 'tracker'");
  expect_error("tracking:\n  matching: global\n  matching: nearest_neighbour\n",
               "key 'tracking.matching' is given twice");
  expect_error("max_time_gap_s: 1\nmax_time_gap_s: 2\n", "key 'max_time_gap_s' is given twice");
  expect_error("segmentation: {cluster_gap_m: -0.1}", "segmentation.cluster_gap_m must be");
  expect_error("segmentation: {min_points: many}", "segmentation.min_points must be an integer");
  expect_error("segmentation: {min_width_m: -0.1}", "segmentation.min_width_m must be");
  expect_error("segmentation: {cluster_gap_spacings: 50}",
               "segmentation.cluster_gap_spacings must be");
  expect_error("tracking: {matching: psychic}", "tracking.matching must be one of");
  expect_error("classification: {presumption: [1]}", "classification.presumption must be");
  expect_error("free_space: {require_unseen: sometimes}",
               "free_space.require_unseen must be one of");
  expect_error("velocity: {velocity_decay: 2}", "velocity.velocity_decay must be in [0, 1]");
  expect_error("segmentation: {masked_sectors: [[1]]}", "segmentation.masked_sectors[0]");
  expect_error("segmentation: {masked_sectors: [[0.5, 0.1]]}", "masked_sectors[0] must satisfy");
  expect_error("segmentation: [1, 2]", "segmentation must be a mapping");
  expect_error("a: [unclosed", "not valid YAML");
  expect_error("max_time_gap_s:", "max_time_gap_s has no value");
  EXPECT_THROW(load_filter_config("/nonexistent/dispel.yaml"), ConfigError);
}

TEST(ConfigYaml, TopLevelKeysAreThoseTheParserAccepts) {
  const std::set<std::string> keys = filter_config_top_level_keys();
  EXPECT_EQ(keys, (std::set<std::string>{"preset", "odometry", "segmentation", "tracking",
                                         "velocity", "classification", "free_space", "registration",
                                         "max_time_gap_s", "max_pose_jump_m", "max_pose_jump_rad",
                                         "max_speed_mps", "max_turn_rate_radps"}));
  // Each of them is accepted...
  for (const char* text : {"segmentation: {}", "tracking: {}", "velocity: {}", "classification: {}",
                           "free_space: {}", "registration: {}", "max_time_gap_s: 1.0",
                           "max_pose_jump_m: 1.0", "max_pose_jump_rad: 1.0", "max_speed_mps: 2.0",
                           "max_turn_rate_radps: 2.0", "preset: thesis", "odometry: {model: ct}"}) {
    EXPECT_NO_THROW(parse_filter_config(text, "t.yaml")) << text;
  }
  // ...and anything else is not.
  EXPECT_THROW(parse_filter_config("fixed_frame: odom\n", "t.yaml"), ConfigError);
}

// Issue 16, fuzzing: yaml-cpp's message quoted a control byte of the file (two lines on a
// terminal, or worse); a key that is a list escaped as yaml-cpp's own exception.
TEST(ConfigYaml, FuzzingFindingsAreOneLineConfigErrors) {
  expect_error("a: \"\\\x01\"\n",
               "not valid YAML: yaml-cpp: error at line 1, column 7: unknown "
               "escape character: \\x01");
  expect_error("[max_time_gap_s]: 1\n", "the file has a key that is not a word");
  expect_error("tracking:\n  {a: 1}: 2\n", "tracking has a key that is not a word");
  try {
    parse_odometry_settings("odometry:\n  [model]: ct\n", "test.yaml");
    ADD_FAILURE() << "accepted a list as a key";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("odometry has a key that is not a word"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace dispel::io
