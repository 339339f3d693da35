// The filter node's per-scan work and `dispel filter` give the same output on the same recording
// (no ROS master needed: the node's middleware is only subscribing and publishing around
// FilterNodeCore, and both use the shared runner).
#include "dispel/ros1/filter_node_core.hpp"

#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/LaserScan.h>

#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "dispel/jobs/filter_job.hpp"
#include "test_files.hpp"

namespace dispel::ros1 {
namespace {

std::map<std::string, std::vector<sensor_msgs::LaserScan>> read_scans(const std::string& path) {
  std::map<std::string, std::vector<sensor_msgs::LaserScan>> out;
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    if (const auto s = m.instantiate<sensor_msgs::LaserScan>()) out[m.getTopic()].push_back(*s);
  }
  return out;
}

bool same_floats(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

// Runs `dispel filter --static-sensor --scale-to-scanner` (the job) and the node's core on the
// scans of @p bag; every scan's labels and filtered ranges must be equal. Returns the number of
// scans the node published unfiltered while it waited for the scanner's period.
std::int64_t expect_node_equals_dispel_filter(const std::string& bag, const std::string& name) {
  jobs::FilterJobOptions o;
  o.input = bag;
  o.output = test::temp_path(name + "_filtered.bag");
  o.static_sensor = true;
  o.scale_to_scanner = true;
  const jobs::FilterJobStats stats = jobs::run_filter_job(o);
  auto offline = read_scans(o.output);

  pipeline::ScanFilterRunnerOptions options;  // The node's defaults: dispel's, scaled.
  options.scale_to_scanner = true;
  options.static_sensor = true;
  FilterNodeCore node(options);
  const std::vector<sensor_msgs::LaserScan>& scans = offline.at("/scan");
  const std::vector<sensor_msgs::LaserScan>& labels = offline.at("/scan_labels");
  const std::vector<sensor_msgs::LaserScan>& filtered = offline.at("/scan_filtered");
  EXPECT_EQ(labels.size(), scans.size());
  EXPECT_EQ(filtered.size(), scans.size());
  std::int64_t differ = 0, removed = 0;
  for (std::size_t k = 0; k < scans.size() && k < labels.size() && k < filtered.size(); ++k) {
    const FilterNodeCore::Output out = node.process(scans[k], 0.0, Pose2{});
    EXPECT_EQ(out.labels.header.stamp, scans[k].header.stamp);
    EXPECT_EQ(out.labels.header.frame_id, scans[k].header.frame_id);
    if (out.labels.intensities != labels[k].intensities ||
        !same_floats(out.filtered.ranges, filtered[k].ranges)) {
      ++differ;
    }
    for (float l : out.labels.intensities) removed += l == 1.0F || l == 2.0F ? 1 : 0;
  }
  EXPECT_EQ(differ, 0) << name << ": scans whose labels or ranges differ";
  EXPECT_GT(removed, 1000) << name << ": the walkers were removed (the scene is not trivial)";
  // The same configuration, scaled to the same scanner by the same rule.
  EXPECT_EQ(node.runner().config().segmentation.min_points, stats.config.segmentation.min_points);
  EXPECT_EQ(node.runner().config().classification.dynamic_weight_limit,
            stats.config.classification.dynamic_weight_limit);
  EXPECT_EQ(node.runner().counts().waiting_period,
            stats.scans_skipped.count("waiting_for_scan_period")
                ? stats.scans_skipped.at("waiting_for_scan_period")
                : 0);
  return node.runner().counts().waiting_period;
}

TEST(FilterNodeCore, LabelsEqualDispelFilterOnTheRecordedBag) {
  // The leg_tracker recording states its period (scan_time 0.1 s): nothing waits.
  const std::int64_t waited = expect_node_equals_dispel_filter(
      test::source_path("data/leg_tracker/demo_stationary_simple_environment.bag"), "stated");
  EXPECT_EQ(waited, 0);
}

TEST(FilterNodeCore, LabelsEqualDispelFilterWhenTheScannerStatesNoPeriod) {
  // The same scans with scan_time 0: both learn the period from the stamps, by the same rule,
  // and publish the same first scans unfiltered while they do.
  const std::string bag = test::temp_path("no_scan_time.bag");
  {
    rosbag::Bag in(test::source_path("data/leg_tracker/demo_stationary_simple_environment.bag"),
                   rosbag::bagmode::Read);
    rosbag::Bag out(bag, rosbag::bagmode::Write);
    for (const rosbag::MessageInstance& m : rosbag::View(in)) {
      auto s = m.instantiate<sensor_msgs::LaserScan>();
      ASSERT_TRUE(s);
      s->scan_time = 0.0F;
      out.write(m.getTopic(), m.getTime(), *s);
    }
  }
  const std::int64_t waited = expect_node_equals_dispel_filter(bag, "unstated");
  EXPECT_EQ(waited, pipeline::ScanPeriod::kIntervals);
}

}  // namespace
}  // namespace dispel::ros1
