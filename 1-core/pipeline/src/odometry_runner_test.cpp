#include "dispel/pipeline/odometry_runner.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "dispel/pipeline/node_diagnostics.hpp"

namespace dispel::pipeline {
namespace {

struct Sample {
  double t_s;
  bool imu;
  double a, b;
};

// A robot driving an arc: wheels at 10 Hz, IMU at 30 Hz whose messages arrive 40 ms late (the
// Husky's in robot_localization's test1.bag arrive 21 to 36 ms late).
std::vector<Sample> arrivals() {
  std::vector<std::pair<double, Sample>> by_arrival;
  for (int k = 0; k < 100; ++k) {
    const double t = 0.1 * k;
    by_arrival.push_back({t, {t, false, 0.9, 1.1}});
  }
  for (int k = 0; k < 300; ++k) {
    const double t = 0.005 + k / 30.0;
    by_arrival.push_back({t + 0.04, {t, true, 0.4 + 0.01 * std::sin(k), 0.0}});
  }
  std::stable_sort(by_arrival.begin(), by_arrival.end(),
                   [](const auto& x, const auto& y) { return x.first < y.first; });
  std::vector<Sample> out;
  for (const auto& a : by_arrival) out.push_back(a.second);
  return out;
}

void add(OdometryRunner& runner, const Sample& s) {
  s.imu ? runner.add_imu(s.t_s, s.a) : runner.add_wheels(s.t_s, s.a, s.b);
}

// What `dispel odom` gives for these measurements: all of them, fused in stamp order.
std::vector<OdometryEstimate> offline(const std::vector<Sample>& in) {
  OdometryRunner whole(OdometryConfig{}, std::numeric_limits<double>::infinity());
  for (const Sample& s : in) add(whole, s);
  return whole.release(true);
}

// Fed live, one measurement at a time; flushed at the end.
std::vector<OdometryEstimate> live(OdometryRunner& runner, const std::vector<Sample>& in) {
  std::vector<OdometryEstimate> out;
  for (const Sample& s : in) {
    add(runner, s);
    for (const auto& e : runner.release()) out.push_back(e);
  }
  for (const auto& e : runner.release(true)) out.push_back(e);
  return out;
}

void expect_same(const std::vector<OdometryEstimate>& a, const std::vector<OdometryEstimate>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].t_s, b[i].t_s) << i;
    EXPECT_EQ(a[i].x_m, b[i].x_m) << i;
    EXPECT_EQ(a[i].y_m, b[i].y_m) << i;
    EXPECT_EQ(a[i].yaw_rad, b[i].yaw_rad) << i;
  }
}

constexpr auto kWheels = OdometrySource::kWheels;
constexpr auto kImu = OdometrySource::kImu;

TEST(OdometryRunner, LateImuWithinTheWindowGivesTheSortedRecordingsEstimates) {
  const std::vector<Sample> in = arrivals();
  OdometryRunner runner(OdometryConfig{}, 0.05);
  std::vector<OdometryEstimate> live;
  for (const Sample& s : in) {
    s.imu ? runner.add_imu(s.t_s, s.a) : runner.add_wheels(s.t_s, s.a, s.b);
    for (const auto& e : runner.release()) live.push_back(e);
  }
  EXPECT_GT(runner.pending(), 0u);  // The last 50 ms wait for newer stamps...
  for (const auto& e : runner.release(true)) live.push_back(e);
  EXPECT_EQ(runner.pending(), 0u);  // ...or a flush.

  // The whole recording sorted by stamp, fed to the fusion: what `dispel odom` does.
  std::vector<Sample> sorted = in;
  std::stable_sort(sorted.begin(), sorted.end(), [](const Sample& x, const Sample& y) {
    return x.t_s < y.t_s || (x.t_s == y.t_s && !x.imu && y.imu);
  });
  OdometryFusion offline(OdometryConfig{});
  std::vector<OdometryEstimate> expected;
  for (const Sample& s : sorted) {
    s.imu ? offline.add_imu(s.t_s, s.a) : offline.add_wheels(s.t_s, s.a, s.b);
    expected.push_back(offline.estimate());
  }
  ASSERT_EQ(live.size(), expected.size());
  for (std::size_t i = 0; i < live.size(); ++i) {
    EXPECT_EQ(live[i].t_s, expected[i].t_s);
    EXPECT_EQ(live[i].x_m, expected[i].x_m);
    EXPECT_EQ(live[i].yaw_rad, expected[i].yaw_rad);
  }
  EXPECT_EQ(runner.counters().count(OdometryEvent::kRejectedOutOfOrder), 0);
  EXPECT_GT(std::hypot(live.back().x_m, live.back().y_m), 1.0);  // It went somewhere.
}

TEST(OdometryRunner, EachSourceInOrderIsPutBackInOrderHoweverFarApartTheyArrive) {
  // A busy machine: the player stalls, then the node reads one connection's backlog before the
  // other's. Here the wheels arrive in 2 s bursts ahead of the IMU (each source in order).
  const std::vector<Sample> sorted = arrivals();
  std::vector<Sample> wheels, imu, in;
  for (const Sample& s : sorted) (s.imu ? imu : wheels).push_back(s);
  std::size_t w = 0, i = 0;
  for (double until = 2.0; w < wheels.size() || i < imu.size(); until += 2.0) {
    while (w < wheels.size() && wheels[w].t_s < until) in.push_back(wheels[w++]);
    while (i < imu.size() && imu[i].t_s < until) in.push_back(imu[i++]);
  }
  OdometryRunner runner(OdometryConfig{}, 0.0);  // No window at all.
  const std::vector<OdometryEstimate> out = live(runner, in);
  expect_same(out, offline(in));
  EXPECT_EQ(runner.late(kWheels) + runner.late(kImu), 0);
  EXPECT_EQ(runner.arrived_out_of_order(), 0);
  // A window measured from the newest stamp alone would have had to be 2 s long.
  EXPECT_NEAR(runner.arrivals(kImu).largest_lag_s, 1.895, 1e-9);
  EXPECT_EQ(runner.arrivals(kImu).largest_lag_in_source_s, 0.0);
  EXPECT_EQ(runner.arrivals(kWheels).count, 100);
  EXPECT_EQ(runner.arrivals(kImu).count, 300);
}

TEST(OdometryRunner, InOrderMeasurementsAreReleasedOnceBothSourcesHavePassedThem) {
  OdometryRunner runner(OdometryConfig{}, 0.1);
  runner.add_wheels(0.0, 1.0, 1.0);
  runner.add_wheels(0.5, 1.0, 1.0);
  EXPECT_TRUE(runner.release().empty());  // No IMU yet: it may still send older stamps.
  runner.add_imu(0.05, 0.0);
  EXPECT_TRUE(runner.release().empty());  // 0.05 - 0.1: not even t = 0 has passed.
  runner.add_imu(0.2, 0.0);
  const auto out = runner.release();  // Everything up to 0.2 - 0.1.
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].t_s, 0.0);
  EXPECT_EQ(out[1].t_s, 0.05);
  EXPECT_EQ(runner.pending(), 2u);  // 0.2 (IMU) and 0.5 (wheels).
}

TEST(OdometryRunner, DisorderWithinASourceIsPutRightWithinTheWindowAndLateBeyondIt) {
  // Wheels at 10 Hz, the IMU 20 ms after each; the wheel measurement of t = 1.0 arrives after
  // that of 1.3 (and the IMU's of 1.32): 0.3 s behind its own source.
  std::vector<Sample> in, without;
  for (int k = 0; k < 30; ++k) {
    if (k != 10) in.push_back({0.1 * k, false, 1.0, 1.0 + 0.01 * k});
    in.push_back({0.1 * k + 0.02, true, 0.02 * k, 0.0});
    if (k == 13) {
      without = in;
      in.push_back({1.0, false, 1.0, 1.1});
    }
  }
  without.insert(without.end(), in.begin() + static_cast<long>(without.size()) + 1, in.end());
  {
    OdometryRunner runner(OdometryConfig{}, 0.35);
    const std::vector<OdometryEstimate> out = live(runner, in);
    expect_same(out, offline(in));
    EXPECT_EQ(runner.late(kWheels), 0);
    EXPECT_EQ(runner.arrivals(kWheels).out_of_order, 1);
    EXPECT_NEAR(runner.arrivals(kWheels).largest_lag_in_source_s, 0.3, 1e-9);
  }
  {
    OdometryRunner runner(OdometryConfig{}, 0.1);  // Shorter than the disorder: 1.0 is late.
    const std::vector<OdometryEstimate> out = live(runner, in);
    EXPECT_EQ(runner.late(kWheels), 1);
    EXPECT_EQ(runner.late(kImu), 0);
    expect_same(out, offline(without));  // As if the late one had never come.
  }
}

TEST(OdometryRunner, EqualStampsGiveOneEstimateAfterAllOfThem) {
  for (bool imu_first : {false, true}) {
    OdometryRunner runner(OdometryConfig{}, 0.0);
    std::vector<OdometryEstimate> out;
    for (int k = 0; k < 5; ++k) {
      const double t = 0.1 * k;
      if (imu_first) runner.add_imu(t, 0.1);
      runner.add_wheels(t, 1.0, 1.1);
      runner.add_wheels(t, 1.0, 1.1);  // Twice at the same stamp: fused both, not late.
      if (!imu_first) runner.add_imu(t, 0.1);
      for (const auto& e : runner.release()) out.push_back(e);
    }
    for (const auto& e : runner.release(true)) out.push_back(e);
    ASSERT_EQ(out.size(), 5u) << imu_first;
    for (int k = 0; k < 5; ++k) EXPECT_EQ(out[k].t_s, 0.1 * k);
    EXPECT_EQ(runner.late(kWheels) + runner.late(kImu), 0);
    EXPECT_EQ(runner.arrived_out_of_order(), 0);
    const auto fused = runner.counters().wheels[static_cast<int>(OdometryEvent::kAccepted)] +
                       runner.counters().wheels[static_cast<int>(OdometryEvent::kGated)];
    EXPECT_EQ(fused, 10);
  }
}

TEST(OdometryRunner, StampsJumpingFarBackAreRefusedAsLateAndCounted) {
  // A clock reset (a recording played again): everything after it is older than what was fused.
  OdometryRunner runner(OdometryConfig{}, 0.1);
  std::vector<OdometryEstimate> out;
  for (int k = 0; k < 100; ++k) {
    runner.add_wheels(0.1 * k, 1.0, 1.0);
    runner.add_imu(0.1 * k + 0.05, 0.0);
    for (const auto& e : runner.release()) out.push_back(e);
  }
  const std::size_t before = out.size();
  const OdometryEstimate last = runner.estimate();
  for (int k = 0; k < 50; ++k) {
    runner.add_wheels(0.1 * k, 1.0, 1.0);
    runner.add_imu(0.1 * k + 0.05, 0.0);
    EXPECT_TRUE(runner.release().empty());
    EXPECT_EQ(runner.pending(), 3u);  // Refused at once, not held (3 from before still wait).
  }
  EXPECT_EQ(out.size(), before);
  EXPECT_EQ(runner.late(kWheels), 50);
  EXPECT_EQ(runner.late(kImu), 50);
  EXPECT_EQ(runner.estimate().t_s, last.t_s);  // The state untouched.
  EXPECT_EQ(runner.estimate().x_m, last.x_m);
  EXPECT_EQ(runner.arrivals(kWheels).out_of_order, 50);  // Behind 9.9 s, the latest...
  EXPECT_NEAR(runner.arrivals(kWheels).largest_lag_in_source_s, 9.9, 1e-9);  // ...by up to 9.9 s.
  // Then time passes the old stamps again and the measurements are fused.
  runner.add_wheels(10.0, 1.0, 1.0);
  runner.add_imu(10.05, 0.0);
  runner.add_wheels(10.2, 1.0, 1.0);
  runner.add_imu(10.25, 0.0);
  const auto again = runner.release();
  ASSERT_FALSE(again.empty());
  EXPECT_EQ(again.back().t_s, 10.05);
}

TEST(OdometryRunner, AQuietSourceIsNoLongerWaitedForAfterTheTimeout) {
  OdometryRunner runner(OdometryConfig{}, 0.1);
  std::vector<OdometryEstimate> out;
  double now = 100.0;  // The arrival clock, in steps of 10 ms.
  const auto feed = [&](double t, bool imu) {
    imu ? runner.add_imu(t, 0.0) : runner.add_wheels(t, 1.0, 1.0);
    for (const auto& e : runner.release_at(now, 0.5)) out.push_back(e);
  };
  for (int k = 0; k < 20; ++k, now += 0.01) feed(0.1 * k, false);  // No IMU yet.
  EXPECT_TRUE(out.empty());  // The IMU is waited for from the start...
  for (; now < 100.49; now += 0.01) EXPECT_TRUE(runner.release_at(now, 0.5).empty());
  now = 100.5;
  for (const auto& e : runner.release_at(now, 0.5)) out.push_back(e);
  // ...for 0.5 s after the first measurement came to wait: then the wheels go on alone.
  EXPECT_FALSE(runner.waiting_for(kImu));
  EXPECT_TRUE(runner.waiting_for(kWheels));
  EXPECT_EQ(runner.quiet_count(kImu), 1);
  EXPECT_NEAR(runner.arrivals(kWheels).longest_gap_s, 0.01, 1e-9);  // One per release_at().
  ASSERT_FALSE(out.empty());
  EXPECT_NEAR(out.back().t_s, 1.8, 1e-9);  // Up to the newest wheels minus the window.
  // The IMU comes back: waited for again; its measurements are fused in order.
  const std::size_t n = out.size();
  feed(2.02, true);
  EXPECT_TRUE(runner.waiting_for(kImu));
  feed(2.0, false);
  EXPECT_NEAR(runner.arrivals(kWheels).longest_gap_s, 0.31, 1e-9);  // 100.19 to 100.5.
  EXPECT_EQ(runner.arrivals(kImu).longest_gap_s, 0.0);              // It had never come before.
  feed(2.1, false);
  feed(2.15, true);
  feed(2.2, false);
  EXPECT_EQ(runner.late(kImu) + runner.late(kWheels), 0);
  ASSERT_GT(out.size(), n);
  EXPECT_NEAR(out.back().t_s, 2.02, 1e-9);
  // Nothing arrives any more (the end of a recording): after the timeout both are quiet and
  // everything is released.
  now = 100.99;
  EXPECT_TRUE(runner.release_at(now, 0.5).empty());
  now = 101.0;
  for (const auto& e : runner.release_at(now, 0.5)) out.push_back(e);
  EXPECT_EQ(runner.pending(), 0u);
  EXPECT_NEAR(out.back().t_s, 2.2, 1e-9);
  EXPECT_EQ(runner.quiet_count(kImu), 2);
  EXPECT_EQ(runner.quiet_count(kWheels), 1);
}

TEST(OdometryRunner, AStreamStartingAfterALongSilenceWaitsForBothSourcesAgain) {
  // Nodes are often started long before data comes: the silence before it is no timeout.
  OdometryRunner runner(OdometryConfig{}, 0.0);
  EXPECT_TRUE(runner.release_at(0.0, 0.5).empty());
  EXPECT_TRUE(runner.release_at(10.0, 0.5).empty());
  EXPECT_TRUE(runner.waiting_for(kImu));
  runner.add_wheels(1.0, 1.0, 1.0);
  runner.add_wheels(1.1, 1.0, 1.0);
  EXPECT_TRUE(runner.release_at(10.0, 0.5).empty());
  EXPECT_TRUE(runner.release_at(10.4, 0.5).empty());  // The IMU has 0.5 s from 10.0.
  runner.add_imu(0.98, 0.0);                          // 20 ms older than the wheels: in its place.
  runner.add_imu(1.2, 0.0);
  const auto out = runner.release_at(10.45, 0.5);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0].t_s, 0.98);
  EXPECT_EQ(runner.late(kImu) + runner.late(kWheels), 0);
  EXPECT_EQ(runner.quiet_count(kImu), 0);
  EXPECT_THROW(runner.release_at(11.0, -1.0), std::invalid_argument);
  EXPECT_THROW(runner.release_at(11.0, std::nan("")), std::invalid_argument);
}

TEST(OdometryRunner, OneEstimatePerStampAndNonFiniteStampsCounted) {
  OdometryRunner runner(OdometryConfig{}, 0.0);
  runner.add_imu(1.0, 0.1);
  runner.add_wheels(1.0, 1.0, 1.0);
  const auto out = runner.release();
  ASSERT_EQ(out.size(), 1u);  // After both measurements at t = 1.
  EXPECT_EQ(out[0].t_s, 1.0);
  const auto fused = [](const auto& counts) {
    return counts[static_cast<int>(OdometryEvent::kAccepted)] +
           counts[static_cast<int>(OdometryEvent::kGated)] +
           counts[static_cast<int>(OdometryEvent::kGateOverridden)];
  };
  EXPECT_EQ(fused(runner.counters().wheels), 1);
  EXPECT_EQ(fused(runner.counters().imu), 1);
  runner.add_wheels(std::nan(""), 1.0, 1.0);
  EXPECT_EQ(runner.pending(), 0u);
  EXPECT_EQ(runner.counters().wheels[static_cast<int>(OdometryEvent::kRejectedNonFinite)], 1);
  EXPECT_TRUE(runner.release().empty());
}

TEST(OdometryRunner, AWholeRecordingFlushedOnceIsFusedInStampOrder) {
  // What `dispel odom` does: an infinite window, everything added, one flush.
  const std::vector<Sample> in = arrivals();
  OdometryRunner whole(OdometryConfig{}, std::numeric_limits<double>::infinity());
  OdometryRunner live(OdometryConfig{}, 0.05);
  std::vector<OdometryEstimate> live_out;
  for (const Sample& s : in) {
    s.imu ? whole.add_imu(s.t_s, s.a) : whole.add_wheels(s.t_s, s.a, s.b);
    s.imu ? live.add_imu(s.t_s, s.a) : live.add_wheels(s.t_s, s.a, s.b);
    EXPECT_TRUE(whole.release().empty());
    for (const auto& e : live.release()) live_out.push_back(e);
  }
  for (const auto& e : live.release(true)) live_out.push_back(e);
  const std::vector<OdometryEstimate> whole_out = whole.release(true);
  ASSERT_EQ(whole_out.size(), live_out.size());
  for (std::size_t i = 0; i < whole_out.size(); ++i) {
    EXPECT_EQ(whole_out[i].t_s, live_out[i].t_s);
    EXPECT_EQ(whole_out[i].x_m, live_out[i].x_m);
  }
  // Every IMU message arrives after a wheel message with a later stamp, but each source on its
  // own arrives in order.
  EXPECT_EQ(whole.arrived_out_of_order(), 0);
}

TEST(OdometryRunner, DeadReckoningIgnoresTheImuAndCountsStampsOutOfOrder) {
  OdometryRunner runner(OdometryConfig{}, std::numeric_limits<double>::infinity(),
                        OdometryEngine::kDeadReckoning);
  WheelOdometry expected(OdometryConfig{}.track_width_m);
  for (int k = 0; k < 20; ++k) {
    runner.add_wheels(0.1 * k, 0.9, 1.0 + 0.01 * k);
    runner.add_imu(0.1 * k + 0.05, 5.0);  // Would turn the robot fast if it were used.
    expected.add_wheels(0.1 * k, 0.9, 1.0 + 0.01 * k);
    if (k == 5) expected.add_wheels(0.55, 0.2, 0.4);
  }
  runner.add_wheels(0.55, 0.2, 0.4);  // Arrives late; the buffer puts it back in its place.
  const std::vector<OdometryEstimate> out = runner.release(true);
  EXPECT_EQ(runner.arrived_out_of_order(), 1);
  ASSERT_EQ(out.size(), 21u);
  EXPECT_EQ(runner.pending(), 0u);
  EXPECT_EQ(runner.estimate().yaw_rad, expected.estimate().yaw_rad);
  EXPECT_EQ(runner.estimate().x_m, expected.estimate().x_m);
  EXPECT_EQ(runner.counters().imu[static_cast<int>(OdometryEvent::kAccepted)], 0);
}

TEST(OdometryRunner, BadWindowOrConfigurationIsRefused) {
  EXPECT_THROW(OdometryRunner(OdometryConfig{}, -0.1), std::invalid_argument);
  EXPECT_THROW(OdometryRunner(OdometryConfig{}, std::nan("")), std::invalid_argument);
  OdometryConfig bad;
  bad.track_width_m = 0.0;
  EXPECT_THROW(OdometryRunner(bad, 0.1), std::invalid_argument);
}

}  // namespace
}  // namespace dispel::pipeline

namespace dispel::pipeline {
namespace {

TEST(OdometryNodeStatus, CountsEachSourceAndCountsRefusedMeasurements) {
  OdometryRunner runner(OdometryConfig{}, 0.05);
  for (const Sample& s : arrivals()) {
    s.imu ? runner.add_imu(s.t_s, s.a) : runner.add_wheels(s.t_s, s.a, s.b);
    runner.release();
  }
  runner.release(true);
  EXPECT_EQ(odometry_refused(runner), 0);
  runner.add_wheels(1.0, 0.5, 0.5);  // Older than what was fused: refused as late.
  runner.release(true);
  EXPECT_EQ(odometry_refused(runner), 1);

  const DiagnosticStatus s = odometry_node_status("dispel_odometry", "ct", runner, {12, 3, true});
  EXPECT_EQ(s.name, "dispel_odometry: odometry fusion");
  EXPECT_EQ(s.level, DiagnosticStatus::Level::kWarn);
  EXPECT_EQ(s.message, "12 estimates published");
  const auto value = [&s](const std::string& key) {
    for (const auto& [k, v] : s.values) {
      if (k == key) return v;
    }
    return std::string("(missing)");
  };
  EXPECT_EQ(value("model"), "ct");
  EXPECT_EQ(value("wheels received"), "101");
  EXPECT_EQ(value("imu received"), "300");
  EXPECT_EQ(value("wheels late"), "1");
  EXPECT_EQ(value("wheel messages without both wheels"), "3");
  EXPECT_EQ(value("imu arrived out of order"), "0");
  EXPECT_EQ(value("wheels arrived out of order"), "1");
  // Seconds with four decimals: the IMU, 40 ms late, lags the newest stamp by less than that.
  const std::string lag = value("imu largest lag behind newest (s)");
  ASSERT_EQ(lag.size(), 6u) << lag;
  EXPECT_GT(std::stod(lag), 0.0);
  EXPECT_LE(std::stod(lag), 0.04);
  EXPECT_EQ(odometry_node_status("n", "ct", runner, {12, 3, false}).level,
            DiagnosticStatus::Level::kOk);
}

}  // namespace
}  // namespace dispel::pipeline
