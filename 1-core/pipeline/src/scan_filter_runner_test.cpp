#include "dispel/pipeline/scan_filter_runner.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "dispel/pipeline/node_diagnostics.hpp"

namespace dispel::pipeline {
namespace {

// A scanner at the origin inside a round room of radius 5 m (361 beams over 180 degrees), with a
// person (a 0.3 m wide blob at 2 m) walking across the view at 1 m/s.
LaserScan scene(int k, double period_s) {
  LaserScan scan;
  scan.stamp_s = 100.0 + k * period_s;
  scan.angle_min_rad = -kPi / 2.0;
  scan.angle_increment_rad = kPi / 360.0;
  scan.range_min_m = 0.05F;
  scan.range_max_m = 10.0F;
  scan.ranges_m.assign(361, 5.0F);
  const double person_x = -1.5 + 1.0 * k * period_s;  // Across the view, 2 m ahead.
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const double a = scan.bearing_rad(i);
    // Bearing from the scanner to the person's centre at (2, person_x) in the scanner frame.
    const double centre = std::atan2(person_x, 2.0);
    const double half_width = std::atan2(0.15, std::hypot(2.0, person_x));
    if (std::abs(a - centre) < half_width)
      scan.ranges_m[i] = static_cast<float>(std::hypot(2.0, person_x));
  }
  scan.ranges_m[10] = std::numeric_limits<float>::quiet_NaN();  // One invalid beam.
  return scan;
}

TEST(ScanFilterRunner, LabelsEqualTheFilterFedDirectly) {
  ScanFilterRunner runner({});
  DynamicFilter direct(DynamicFilterConfig{});
  int dynamic = 0;
  for (int k = 0; k < 60; ++k) {
    const LaserScan scan = scene(k, 0.05);
    const FilterResult expected = direct.process(scan, Pose2{});
    const FilterResult& got = runner.process(scan, 0.0, Pose2{});
    ASSERT_EQ(got.labels, expected.labels) << "scan " << k;
    for (BeamLabel l : got.labels) dynamic += l == BeamLabel::kDynamic ? 1 : 0;
  }
  EXPECT_GT(dynamic, 0);  // The walker was removed at some point: the scene is not trivial.
  EXPECT_EQ(runner.counts().scans, 60);
  EXPECT_EQ(runner.counts().filtered, 60);
  EXPECT_EQ(runner.filter_counters().scans, 60);
}

TEST(ScanFilterRunner, ScanWithoutPoseIsPassedThroughAndCounted) {
  // Without the registration (with it, a scan without a pose is registered: laser-only).
  ScanFilterRunnerOptions options;
  options.config.registration.enabled = false;
  ScanFilterRunner runner(options);
  const LaserScan scan = scene(0, 0.05);
  const FilterResult& r = runner.process(scan, 0.0, std::nullopt);
  EXPECT_EQ(r.event, FilterEvent::kNoPose);
  EXPECT_EQ(runner.last_outcome(), ScanOutcome::kNoPose);
  ASSERT_EQ(r.labels.size(), scan.size());
  EXPECT_EQ(r.labels[10], BeamLabel::kInvalid);
  EXPECT_EQ(r.labels[0], BeamLabel::kNoObject);
  EXPECT_EQ(r.filtered.ranges_m[0], scan.ranges_m[0]);
  EXPECT_EQ(runner.counts().no_pose, 1);
  EXPECT_EQ(runner.counts().filtered, 0);
}

TEST(ScanFilterRunner, ScalesToTheStatedPeriodOrWaitsForTheStamps) {
  ScanFilterRunnerOptions o;
  o.scale_to_scanner = true;
  const DynamicFilterConfig expected = scale_to_scanner(DynamicFilterConfig{}, kPi / 360.0, 0.1);
  {
    ScanFilterRunner stated(o);
    EXPECT_FALSE(stated.configured());
    stated.process(scene(0, 0.1), 0.1, Pose2{});
    ASSERT_TRUE(stated.configured());
    EXPECT_EQ(stated.config().segmentation.min_points, expected.segmentation.min_points);
    EXPECT_EQ(stated.config().classification.dynamic_weight_limit,
              expected.classification.dynamic_weight_limit);
    EXPECT_EQ(stated.counts().filtered, 1);
    EXPECT_EQ(stated.scan_period_s(), 0.1);
  }
  {
    // The messages state no period: the first ScanPeriod::kIntervals scans go by unfiltered.
    ScanFilterRunner from_stamps(o);
    for (int k = 0; k < ScanPeriod::kIntervals; ++k) {
      const FilterResult& r = from_stamps.process(scene(k, 0.1), 0.0, Pose2{});
      EXPECT_EQ(r.event, FilterEvent::kNoPose);
      EXPECT_EQ(from_stamps.last_outcome(), ScanOutcome::kWaitingForPeriod);
      EXPECT_EQ(r.filtered.ranges_m[0], scene(k, 0.1).ranges_m[0]);
      EXPECT_FALSE(from_stamps.configured());
    }
    EXPECT_EQ(from_stamps.counts().waiting_period, ScanPeriod::kIntervals);
    from_stamps.process(scene(ScanPeriod::kIntervals, 0.1), 0.0, Pose2{});
    ASSERT_TRUE(from_stamps.configured());
    EXPECT_EQ(from_stamps.last_outcome(), ScanOutcome::kFiltered);
    EXPECT_EQ(from_stamps.config().classification.dynamic_weight_limit,
              expected.classification.dynamic_weight_limit);
  }
  o.scan_period_s = 0.025;  // Given: wins over the message's.
  ScanFilterRunner given(o);
  given.process(scene(0, 0.1), 0.1, Pose2{});
  EXPECT_EQ(given.config().classification.dynamic_weight_limit,
            scale_to_scanner(DynamicFilterConfig{}, kPi / 360.0, 0.025)
                .classification.dynamic_weight_limit);
}

TEST(ScanFilterRunner, OutcomesCountEachWayAScanIsPassedThrough) {
  // Without the registration (with it, a scan without a pose is registered: laser-only).
  ScanFilterRunnerOptions options;
  options.config.registration.enabled = false;
  ScanFilterRunner runner(options);
  LaserScan bad = scene(0, 0.05);
  bad.angle_increment_rad = 0.0;
  runner.process(bad, 0.0, Pose2{});
  EXPECT_EQ(runner.last_outcome(), ScanOutcome::kBadScan);
  runner.process(scene(1, 0.05), 0.0, Pose2{std::nan(""), 0.0, 0.0});
  EXPECT_EQ(runner.last_outcome(), ScanOutcome::kBadPose);
  runner.process(scene(2, 0.05), 0.0, std::nullopt);
  EXPECT_EQ(runner.last_outcome(), ScanOutcome::kNoPose);
  runner.process(scene(3, 0.05), 0.0, Pose2{});
  EXPECT_EQ(runner.last_outcome(), ScanOutcome::kFiltered);
  const ScanFilterCounts& c = runner.counts();
  EXPECT_EQ(c.scans, 4);
  EXPECT_EQ(c.rejected_scan, 1);
  EXPECT_EQ(c.bad_pose, 1);
  EXPECT_EQ(c.no_pose, 1);
  EXPECT_EQ(c.filtered, 1);
  EXPECT_EQ(c.waiting_period, 0);
}

TEST(ScanFilterRunner, BadOptionsAreRefusedNamingTheField) {
  ScanFilterRunnerOptions o;
  o.scan_period_s = -1.0;
  try {
    ScanFilterRunner runner(o);
    FAIL() << "accepted a negative period";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("scan_period_s"), std::string::npos) << e.what();
  }
  o.scan_period_s = 0.0;
  o.config.segmentation.cluster_gap_m = -0.1;
  EXPECT_THROW(ScanFilterRunner{o}, std::invalid_argument);
}

TEST(ScanFilterRunner, TimesAreTakenPerWindow) {
  ScanFilterRunner runner({});
  for (int k = 0; k < 5; ++k) runner.process(scene(k, 0.05), 0.0, Pose2{});
  const ScanTimes t = runner.take_times();
  EXPECT_EQ(t.count, 5);
  EXPECT_GT(t.max_s, 0.0);
  EXPECT_GE(t.max_s, t.mean_s);
  EXPECT_EQ(runner.take_times().count, 0);
}

TEST(ScanFilterRunner, EachScanSaysWhatItCostAndWhatItDid) {
  ScanFilterRunner runner({});
  double cpu_total = 0.0;
  std::int64_t first_tiles = 0, later_tiles = 0;
  for (int k = 0; k < 40; ++k) {
    const LaserScan scan = scene(k, 0.05);
    const FilterResult& r = runner.process(scan, 0.0, Pose2{});
    EXPECT_EQ(r.work.beams, 361);
    EXPECT_EQ(r.work.objects, static_cast<std::int32_t>(r.segmentation.objects.size()));
    EXPECT_EQ(r.work.tracks, static_cast<std::int32_t>(r.tracks.size()));
    EXPECT_EQ(r.work.registration_points, r.registration.points);
    EXPECT_EQ(r.work.registration_iterations, r.registration.iterations);
    EXPECT_EQ(r.work.registration_alignments, r.registration.alignments);
    EXPECT_EQ(r.work.registration_total_iterations, r.registration.total_iterations);
    EXPECT_GE(r.work.registration_total_iterations, r.work.registration_iterations);
    EXPECT_GT(r.work.registration_us, 0.0);  // The registration ran for every scan.
    EXPECT_GT(r.work.free_space_us, 0.0);
    if (k > 0) {
      EXPECT_GE(r.registration.alignments, 1);  // Every scan after the first is aligned.
    }
    // The first scan empties the free-space tiles the room's beams reach; a scanner that stays
    // put needs few more (a registered pose that moves by millimetres reaches a tile at the
    // room's edge now and then).
    if (k == 0) {
      first_tiles = r.work.free_space_tiles_started;
    } else {
      later_tiles += r.work.free_space_tiles_started;
    }
    if (k > 0) {
      EXPECT_GT(r.work.map_voxels, 0);  // The room, learnt by the registration.
    }
    EXPECT_GE(runner.last_cpu_time_s(), 0.0);
    cpu_total += runner.last_cpu_time_s();
  }
  EXPECT_GT(cpu_total, 0.0);
  EXPECT_GT(first_tiles, 20);  // A half disc of 5 m: about 60 tiles of 0.8 m.
  EXPECT_LT(later_tiles, first_tiles / 4);
  // A scan passed through says only its beams.
  LaserScan bad = scene(40, 0.05);
  bad.angle_increment_rad = 0.0;
  const FilterResult& r = runner.process(bad, 0.0, Pose2{});
  EXPECT_EQ(r.event, FilterEvent::kRejectedScan);
  EXPECT_EQ(r.work.beams, 361);
  EXPECT_EQ(r.work.objects, 0);
  EXPECT_EQ(r.work.free_space_tiles_started, 0);
}

}  // namespace
}  // namespace dispel::pipeline

namespace dispel::pipeline {
namespace {

std::string value_of(const DiagnosticStatus& s, const std::string& key) {
  for (const auto& [k, v] : s.values) {
    if (k == key) return v;
  }
  return "(missing)";
}

TEST(FilterNodeStatus, SaysThePeriodsScansAndWarnsOfScansWithoutAPose) {
  ScanFilterRunnerOptions options;
  options.config.registration.enabled = false;
  ScanFilterRunner runner(options);
  DiagnosticStatus s = filter_node_status("dispel_filter", runner, {});
  EXPECT_EQ(s.name, "dispel_filter: dynamic filter");
  EXPECT_EQ(s.level, DiagnosticStatus::Level::kOk);
  EXPECT_EQ(s.message, "no scans");

  for (int k = 0; k < 40; ++k) runner.process(scene(k, 0.05), 0.0, Pose2{});
  runner.process(scene(40, 0.05), 0.0, std::nullopt);
  s = filter_node_status("dispel_filter", runner, {3, 1, 2});
  EXPECT_EQ(s.level, DiagnosticStatus::Level::kWarn);
  EXPECT_EQ(s.message.rfind("41 scans, ", 0), 0u) << s.message;
  EXPECT_NE(s.message.find(" ms per scan (mean); 1 without a sensor pose"), std::string::npos)
      << s.message;
  EXPECT_EQ(value_of(s, "scans in period"), "41");
  EXPECT_EQ(value_of(s, "scans"), "43");  // The runner's 41 and the 2 dropped before it.
  EXPECT_EQ(value_of(s, "scans filtered"), "40");
  EXPECT_EQ(value_of(s, "scans without a sensor pose"), "3");
  EXPECT_EQ(value_of(s, "scans dropped (no sensor pose)"), "2");
  EXPECT_EQ(value_of(s, "scans published unfiltered (no sensor pose)"), "1");
  EXPECT_NE(value_of(s, "beams removed (dynamic)"), "0");  // The walker.
  EXPECT_EQ(value_of(s, "min_points"), std::to_string(runner.config().segmentation.min_points));
  // Times are in milliseconds with three decimals.
  const std::string mean = value_of(s, "processing time mean (ms)");
  ASSERT_GT(mean.size(), 4u);
  EXPECT_EQ(mean[mean.size() - 4], '.') << mean;

  // The next period: its own times (none), no warning.
  s = filter_node_status("dispel_filter", runner, {3, 0, 2});
  EXPECT_EQ(s.level, DiagnosticStatus::Level::kOk);
  EXPECT_EQ(s.message, "no scans");
  EXPECT_EQ(value_of(s, "scans in period"), "0");
  EXPECT_EQ(value_of(s, "scans filtered"), "40");
}

}  // namespace
}  // namespace dispel::pipeline
