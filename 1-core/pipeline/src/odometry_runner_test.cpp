#include "dispel/pipeline/odometry_runner.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

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

TEST(OdometryRunner, WithoutAWindowLateMeasurementsAreRejectedAsOutOfOrder) {
  OdometryRunner runner(OdometryConfig{}, 0.0);
  for (const Sample& s : arrivals()) {
    s.imu ? runner.add_imu(s.t_s, s.a) : runner.add_wheels(s.t_s, s.a, s.b);
    runner.release();
  }
  EXPECT_GT(runner.counters().imu[static_cast<int>(OdometryEvent::kRejectedOutOfOrder)], 0);
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
