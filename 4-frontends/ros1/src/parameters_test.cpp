#include "dispel/ros1/parameters.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "dispel/io/config_yaml.hpp"

namespace dispel::ros1 {
namespace {

using V = XmlRpc::XmlRpcValue;

V pair(double a, double b) {
  V v;
  v[0] = a;
  v[1] = b;
  return v;
}

// A private namespace as `rosparam load` leaves it: nested structs, ints, doubles, bools, strings.
V filter_tree() {
  V tree;
  tree["preset"] = std::string("thesis");
  tree["fixed_frame"] = std::string("/odom");  // The node's: not the filter's.
  tree["segmentation"]["cluster_gap_m"] = 0.1;
  tree["segmentation"]["min_points"] = 5;
  tree["segmentation"]["masked_sectors"][0] = pair(-2.0, -1.5);
  tree["segmentation"]["masked_sectors"][1] = pair(1.0 / 3.0, 1.5);
  tree["classification"]["presumption"] = std::string("guilt");
  tree["classification"]["speed_limit_mps"] = 1;  // An int where a number is expected.
  tree["free_space"]["enabled"] = true;
  tree["velocity"]["measurement_variance_m2"] = std::string("1e-4");  // PyYAML keeps it a string.
  tree["max_time_gap_s"] = 1e-300;
  return tree;
}

TEST(Ros1Parameters, TreeBecomesTheYamlTheConfigurationParserReads) {
  const V tree = filter_tree();
  const std::string yaml = to_yaml(tree, {"fixed_frame"});
  EXPECT_EQ(yaml.find("fixed_frame"), std::string::npos) << yaml;
  const DynamicFilterConfig c = io::parse_filter_config(yaml, "test");
  const DynamicFilterConfig thesis = thesis_config();
  EXPECT_EQ(c.segmentation.cluster_gap_m, 0.1);  // Bit for bit.
  EXPECT_EQ(c.segmentation.min_points, 5);
  ASSERT_EQ(c.segmentation.masked_sectors.size(), 2u);
  EXPECT_EQ(c.segmentation.masked_sectors[1].begin_rad, 1.0 / 3.0);
  EXPECT_EQ(c.segmentation.masked_sectors[0].end_rad, -1.5);
  EXPECT_EQ(c.classification.presumption, Presumption::kGuilt);
  EXPECT_EQ(c.classification.speed_limit_mps, 1.0);
  EXPECT_TRUE(c.free_space.enabled);
  EXPECT_EQ(c.velocity.measurement_variance_m2, 1e-4);
  EXPECT_EQ(c.max_time_gap_s, 1e-300);
  // The rest is the preset's.
  EXPECT_EQ(c.tracking.max_missed_scans, thesis.tracking.max_missed_scans);
  EXPECT_EQ(c.classification.dynamic_weight_limit, thesis.classification.dynamic_weight_limit);
}

TEST(Ros1Parameters, EmptyNamespaceIsTheDefaults) {
  const DynamicFilterConfig c = io::parse_filter_config(to_yaml(V()), "test");
  EXPECT_EQ(c.classification.dynamic_weight_limit,
            DynamicFilterConfig{}.classification.dynamic_weight_limit);
  NodeParameters p(V(), "~");
  EXPECT_EQ(p.text("fixed_frame", "odom"), "odom");
  EXPECT_TRUE(p.members().empty());
}

TEST(Ros1Parameters, SpecialValuesAndStringsSurviveTheRoundTrip) {
  V tree;
  tree["odometry"]["left_wheel_joint"] = std::string("we\"ird\\ joint: #1");
  tree["odometry"]["imu_yaw_axis"] = std::string("-y");
  const io::OdometrySettings s = io::parse_odometry_settings(to_yaml(tree), "test");
  EXPECT_EQ(s.left_wheel_joint, "we\"ird\\ joint: #1");
  EXPECT_EQ(s.imu_yaw_axis, 1);
  EXPECT_EQ(s.imu_yaw_sign, -1.0);
  // Infinity and NaN arrive as such, and are refused by name.
  tree["odometry"]["gate_override_after_s"] = std::numeric_limits<double>::infinity();
  tree["odometry"]["max_time_step_s"] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(to_yaml(tree).find(".inf"), std::string::npos);
  EXPECT_NE(to_yaml(tree).find(".nan"), std::string::npos);
  try {
    io::parse_odometry_settings(to_yaml(tree), "test");
    FAIL() << "accepted an infinite gate override";
  } catch (const io::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("got inf"), std::string::npos) << e.what();
  }
}

TEST(Ros1Parameters, FilterErrorsNameTheKeyAsDispelFilterDoes) {
  V tree = filter_tree();
  tree["segmentation"]["cluster_gap_m"] = -0.1;
  try {
    io::parse_filter_config(to_yaml(tree, {"fixed_frame"}), "parameters of /dispel_filter");
    FAIL() << "accepted a negative cluster gap";
  } catch (const io::ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "parameters of /dispel_filter: segmentation.cluster_gap_m must be a finite number "
                 "> 0, got -0.1");
  }
  // A misspelt node parameter is not skipped, so the parser names it.
  tree = filter_tree();
  tree["fixed_frme"] = std::string("odom");
  try {
    io::parse_filter_config(to_yaml(tree, {"fixed_frame"}), "parameters of /dispel_filter");
    FAIL() << "accepted an unknown key";
  } catch (const io::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown key 'fixed_frme'"), std::string::npos);
  }
}

TEST(Ros1Parameters, NodeParametersAreTypeCheckedAndRemembered) {
  V tree;
  tree["fixed_frame"] = 3;
  tree["transform_timeout_s"] = 2;  // An int is a number.
  tree["static_sensor"] = std::string("yes");
  tree["on_missing_transform"] = std::string("maybe");
  tree["queue_size"] = 2.5;
  NodeParameters p(tree, "/dispel_filter/");
  EXPECT_EQ(p.number("transform_timeout_s", 0.1), 2.0);
  const auto message = [](const auto& read) {
    try {
      read();
    } catch (const ParameterError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message([&] { p.text("fixed_frame", "odom"); }),
            "/dispel_filter/fixed_frame must be a string, got 3");
  EXPECT_EQ(message([&] { p.boolean("static_sensor", false); }),
            "/dispel_filter/static_sensor must be true or false, got \"yes\"");
  EXPECT_EQ(message([&] {
              p.choice("on_missing_transform", "drop", {"drop", "publish_unfiltered"});
            }),
            "/dispel_filter/on_missing_transform must be one of drop, publish_unfiltered, got "
            "'maybe'");
  EXPECT_EQ(message([&] { p.integer("queue_size", 10); }),
            "/dispel_filter/queue_size must be an integer, got 2.5");
  EXPECT_EQ(message([&] { p.require(false, "queue_size", "an integer >= 1", 0); }),
            "/dispel_filter/queue_size must be an integer >= 1, got 0");
  EXPECT_EQ(p.keys(), (std::set<std::string>{"fixed_frame", "transform_timeout_s", "static_sensor",
                                             "on_missing_transform", "queue_size"}));
  EXPECT_EQ(p.members(), p.keys());
}

}  // namespace
}  // namespace dispel::ros1
