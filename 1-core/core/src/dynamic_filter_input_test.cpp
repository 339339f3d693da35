// The dynamic filter on bad input: time going backwards, repeated stamps, pose jumps, no pose or a
// pose that is not finite, scans that fail their checks, NaN ranges. Never a throw, always valid
// labels, every case counted.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "dispel/core/dynamic_filter.hpp"
#include "filter_scenes.hpp"

namespace dispel {
namespace {

using namespace scenes;  // NOLINT: the scenes' vocabulary.

// --- Bad input ----------------------------------------------------------------------------------

void expect_sane(const FilterResult& r, const LaserScan& in) {
  ASSERT_EQ(r.labels.size(), in.size());
  for (BeamLabel l : r.labels) EXPECT_LE(static_cast<int>(l), 4);
  ASSERT_EQ(r.filtered.size(), in.size());
  for (const TrackedObject& t : r.tracks) {
    EXPECT_TRUE(t.position_m.allFinite());
    EXPECT_TRUE(t.velocity_mps.allFinite());
  }
}

TEST(DynamicFilterInput, TimeGoingBackwardsResetsAndIsCounted) {
  Scenario s;
  s.walls = room(6.0, 5.0);
  s.movers = {walker({3.0, -2.0}, {0.0, 1.0})};
  DynamicFilter filter{DynamicFilterConfig{}};
  run(s, filter, 40);
  ASSERT_GT(filter.track_count(), 0u);
  Frame f = render(s, 1.0);  // Earlier than the last scan (1.95 s).
  const FilterResult r = filter.process(f.scan, f.pose);
  EXPECT_EQ(r.event, FilterEvent::kResetTimeBackwards);
  expect_sane(r, f.scan);
  EXPECT_EQ(filter.counters().events[static_cast<int>(FilterEvent::kResetTimeBackwards)], 1);
  // Tracks start again from this scan.
  for (const TrackedObject& t : r.tracks) EXPECT_EQ(t.age_scans, 1);
  f = render(s, 1.05);
  EXPECT_EQ(filter.process(f.scan, f.pose).event, FilterEvent::kFiltered);
}

TEST(DynamicFilterInput, RepeatedStampLabelsFromTheTracksWithoutChangingThem) {
  Scenario s;
  s.walls = room(6.0, 5.0);
  s.movers = {walker({3.0, -2.0}, {0.0, 1.2})};
  DynamicFilter filter{DynamicFilterConfig{}};
  run(s, filter, 60);
  const Frame f = render(s, 59 * kPeriod);  // The same stamp as the last scan.
  const std::size_t tracks = filter.track_count();
  const FilterResult r = filter.process(f.scan, f.pose);
  EXPECT_EQ(r.event, FilterEvent::kRepeatedStamp);
  expect_sane(r, f.scan);
  EXPECT_EQ(filter.track_count(), tracks);
  const ScanStats st = stats_of(f, r);
  EXPECT_GT(st.removed.at(1), st.beams.at(1) * 9 / 10);  // The walker is still removed.
  EXPECT_EQ(st.removed.count(0), 0u);
  EXPECT_EQ(filter.counters().events[static_cast<int>(FilterEvent::kRepeatedStamp)], 1);
}

TEST(DynamicFilterInput, PoseJumpResetsInsteadOfMakingTheWorldMove) {
  Scenario s;
  s.walls = room(6.0, 5.0);
  s.pillars = {{{2.0, 1.0}, 0.3}};
  DynamicFilter filter{DynamicFilterConfig{}};
  run(s, filter, 20);
  // Odometry jumps by 2 m (a reset of the fixed frame): the same scan, a different pose.
  Frame f = render(s, 20 * kPeriod);
  const FilterResult r = filter.process(f.scan, Pose2{2.0, 0.0, 0.0});
  EXPECT_EQ(r.event, FilterEvent::kResetPoseJump);
  expect_sane(r, f.scan);
  // Continuing in the new frame, nothing is ever dynamic.
  for (int k = 21; k < 80; ++k) {
    f = render(s, k * kPeriod);
    const FilterResult rk = filter.process(f.scan, Pose2{2.0, 0.0, 0.0});
    EXPECT_EQ(rk.removed_dynamic, 0);
  }
}

// A slow scanner on a robot driving fast moves farther than max_pose_jump_m between two scans:
// that is motion (up to max_speed_mps), not a jump; a jump beyond it still resets.
TEST(DynamicFilterInput, ASlowScannerOnAFastRobotIsMotionNotAJump) {
  Scenario s;
  s.walls = room(30.0, 6.0);
  s.pillars = {{{2.0, 2.0}, 0.3}, {{12.0, -2.0}, 0.3}};
  s.sensor = [](double t) { return Pose2{-12.0 + 1.3 * t, 0.0, 0.0}; };  // 1.3 m/s.
  DynamicFilter filter{DynamicFilterConfig{}};
  constexpr double kSlowPeriod = 0.5;  // A 2 Hz scanner: 0.65 m between scans.
  for (int k = 0; k < 20; ++k) {
    const Frame f = render(s, k * kSlowPeriod);
    const FilterResult r = filter.process(f.scan, f.pose);
    EXPECT_EQ(r.event, k == 0 ? FilterEvent::kFirstScan : FilterEvent::kFiltered) << "scan " << k;
  }
  EXPECT_EQ(filter.counters().events[static_cast<int>(FilterEvent::kResetPoseJump)], 0);
  // 3 m in 0.5 s is beyond 0.5 m + 3 m/s * 0.5 s: a jump.
  const Frame f = render(s, 20 * kSlowPeriod);
  const FilterResult r = filter.process(f.scan, Pose2{f.pose.x_m + 3.0, 0.0, 0.0});
  EXPECT_EQ(r.event, FilterEvent::kResetPoseJump);
}

TEST(DynamicFilterInput, NonFinitePoseAndBadScansPassThroughUnchanged) {
  Scenario s;
  s.walls = room(6.0, 5.0);
  DynamicFilter filter{DynamicFilterConfig{}};
  run(s, filter, 10);
  Frame f = render(s, 10 * kPeriod);
  for (const Pose2& bad : {Pose2{std::nan(""), 0.0, 0.0}, Pose2{0.0, 0.0, INFINITY}}) {
    const FilterResult r = filter.process(f.scan, bad);
    EXPECT_EQ(r.event, FilterEvent::kRejectedPose);
    expect_sane(r, f.scan);
    for (std::size_t i = 0; i < f.scan.size(); ++i) {
      const float a = r.filtered.ranges_m[i];
      const float b = f.scan.ranges_m[i];
      EXPECT_TRUE(a == b || (std::isnan(a) && std::isnan(b)));
    }
  }
  LaserScan bad_scan = f.scan;
  bad_scan.angle_increment_rad = 0.0;
  bad_scan.stamp_s = 11 * kPeriod;
  const FilterResult r = filter.process(bad_scan, Pose2{});
  EXPECT_EQ(r.event, FilterEvent::kRejectedScan);
  expect_sane(r, bad_scan);
  for (BeamLabel l : r.labels) EXPECT_EQ(l, BeamLabel::kInvalid);
  LaserScan empty;
  empty.angle_increment_rad = 0.01;
  empty.range_max_m = 10.0F;
  EXPECT_EQ(filter.process(empty, Pose2{}).event, FilterEvent::kRejectedScan);
  const FilterCounters& c = filter.counters();
  EXPECT_EQ(c.events[static_cast<int>(FilterEvent::kRejectedPose)], 2);
  EXPECT_EQ(c.rejected_by_issue[static_cast<int>(ScanIssue::kNonPositiveIncrement)], 1);
  EXPECT_EQ(c.rejected_by_issue[static_cast<int>(ScanIssue::kEmpty)], 1);
  // After rejections the filter carries on as before.
  f = render(s, 12 * kPeriod);
  EXPECT_EQ(filter.process(f.scan, f.pose).event, FilterEvent::kFiltered);
}

TEST(DynamicFilterInput, WithoutRegistrationAScanWithoutAPoseIsPassedThroughAndTracksWait) {
  Scenario s;
  s.walls = room(6.0, 5.0);
  s.movers = {walker({3.0, -3.0}, {0.0, 1.0})};
  DynamicFilterConfig config;
  config.registration.enabled = false;
  DynamicFilter filter{config};
  run(s, filter, 20);
  const std::size_t tracks = filter.track_count();
  const Frame f = render(s, 20 * kPeriod);
  const FilterResult r = filter.process(f.scan, std::nullopt);
  EXPECT_EQ(r.event, FilterEvent::kNoPose);
  expect_sane(r, f.scan);
  EXPECT_EQ(r.removed_dynamic, 0);
  for (std::size_t i = 0; i < f.scan.size(); ++i) {
    EXPECT_EQ(r.labels[i], f.scan.is_valid(i) ? BeamLabel::kNoObject : BeamLabel::kInvalid);
  }
  EXPECT_EQ(filter.track_count(), tracks);  // Kept, not reset.
  EXPECT_EQ(filter.counters().events[static_cast<int>(FilterEvent::kNoPose)], 1);
  EXPECT_STREQ(filter_event_name(FilterEvent::kNoPose), "no_pose");
  const Frame next = render(s, 21 * kPeriod);
  EXPECT_EQ(filter.process(next.scan, next.pose).event, FilterEvent::kFiltered);
}

// With the registration (dispel's default) a scan without a pose is registered with a
// constant-velocity guess: laser-only. A robot driving through a room with a walker: every scan is
// filtered, the registered poses follow the true ones, the walker is removed and the walls kept.
TEST(DynamicFilterInput, WithRegistrationScansWithoutPosesAreRegisteredAndFiltered) {
  Scenario s;
  s.walls = room(8.0, 6.0);
  s.pillars = {{{1.5, 1.5}, 0.15}, {{-2.0, -1.0}, 0.2}, {{2.5, -2.0}, 0.1}};
  s.movers = {walker({2.0, -2.5}, {0.0, 1.0})};
  s.sensor = [](double t) { return Pose2{-2.0 + 0.5 * t, 0.3 * std::sin(0.5 * t), 0.1 * t}; };
  DynamicFilter filter{DynamicFilterConfig{}};
  std::vector<ScanStats> st;
  double worst_m = 0.0;
  const Pose2 start = s.sensor(0.0);
  for (int k = 0; k < 100; ++k) {
    const Frame f = render(s, k * kPeriod);
    const FilterResult r = filter.process(f.scan, std::nullopt);
    ASSERT_NE(r.event, FilterEvent::kNoPose) << "scan " << k;
    ASSERT_TRUE(r.sensor_pose.has_value());
    // The registration's frame is the first scan's sensor frame.
    const Pose2 truth = start.inverse() * f.pose;
    worst_m = std::max(worst_m, (r.sensor_pose->translation() - truth.translation()).norm());
    st.push_back(stats_of(f, r));
  }
  EXPECT_LT(worst_m, 0.05) << "registered pose off the truth";
  EXPECT_EQ(filter.counters().scans_without_odometry, 100);
  EXPECT_GE(filter.counters().scans_registered, 90);
  std::int64_t static_beams = 0;
  for (const ScanStats& one : st) {
    const auto b = one.beams.find(0);
    static_beams += b == one.beams.end() ? 0 : b->second;
  }
  EXPECT_LE(static_cast<double>(static_removed(st)), 0.002 * static_cast<double>(static_beams));
  EXPECT_GE(scans_until_removed(st, 1), 0);
}

TEST(DynamicFilterInput, NanRangesGiveValidLabels) {
  Scenario s;
  s.walls = room(6.0, 5.0);
  DynamicFilter filter{DynamicFilterConfig{}};
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < 30; ++k) {
    Frame f = render(s, k * kPeriod);
    for (float& r : f.scan.ranges_m) {
      const double p = u(rng);
      if (p < 0.2) r = std::numeric_limits<float>::quiet_NaN();
      if (p > 0.95) r = -std::numeric_limits<float>::infinity();
    }
    const FilterResult r = filter.process(f.scan, f.pose);
    expect_sane(r, f.scan);
    for (std::size_t i = 0; i < f.scan.size(); ++i) {
      if (!f.scan.is_valid(i)) {
        EXPECT_EQ(r.labels[i], BeamLabel::kInvalid);
      }
    }
  }
}
}  // namespace
}  // namespace dispel
