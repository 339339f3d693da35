#include "dispel/eval/trajectory_error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

namespace dispel::eval {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A circle of radius 2 m driven at 0.5 m/s, sampled every dt.
std::vector<TrajectoryPoint> circle(double dt, double duration, double offset_x = 0.0,
                                    double yaw_offset = 0.0) {
  std::vector<TrajectoryPoint> p;
  for (double t = 0.0; t <= duration + 1e-9; t += dt) {
    const double a = 0.25 * t;
    p.push_back({t, 2.0 * std::sin(a) + offset_x, 2.0 - 2.0 * std::cos(a), a + yaw_offset});
  }
  return p;
}

TEST(TrajectoryError, IdenticalTrajectoriesHaveNoErrorAndTheTruePathLength) {
  const auto truth = circle(0.1, 20.0);
  const TrajectoryErrors e = compare_trajectories(truth, truth);
  EXPECT_NEAR(e.rmse_position_m, 0.0, 1e-12);
  EXPECT_NEAR(e.rmse_yaw_rad, 0.0, 1e-12);
  EXPECT_NEAR(e.path_length_m, 0.5 * 20.0, 1e-3);  // Chords of a circle: just under the arc.
  EXPECT_EQ(e.compared, static_cast<std::int64_t>(truth.size()));
  EXPECT_EQ(e.outside, 0);
}

TEST(TrajectoryError, AConstantOffsetIsTheRmseAndTheFinalError) {
  const auto truth = circle(0.1, 20.0);
  const TrajectoryErrors e = compare_trajectories(truth, circle(0.1, 20.0, 0.3, 0.05));
  EXPECT_NEAR(e.rmse_position_m, 0.3, 1e-9);
  EXPECT_NEAR(e.rmse_x_m, 0.3, 1e-9);
  EXPECT_NEAR(e.rmse_y_m, 0.0, 1e-9);
  EXPECT_NEAR(e.rmse_yaw_rad, 0.05, 1e-9);
  EXPECT_NEAR(e.final_position_error_m, 0.3, 1e-9);
  EXPECT_NEAR(e.final_yaw_error_rad, 0.05, 1e-9);
  EXPECT_NEAR(e.max_position_error_m, 0.3, 1e-9);
  EXPECT_NEAR(e.max_yaw_error_rad, 0.05, 1e-9);
}

TEST(TrajectoryError, TheLargestErrorIsKeptWhereverItOccurs) {
  // A detour of 0.8 m and 0.3 rad in the middle of an otherwise exact estimate.
  const auto truth = circle(0.1, 20.0);
  auto estimate = truth;
  estimate[100].y_m += 0.8;
  estimate[100].yaw_rad -= 0.3;
  const TrajectoryErrors e = compare_trajectories(truth, estimate);
  EXPECT_NEAR(e.max_position_error_m, 0.8, 1e-9);
  EXPECT_NEAR(e.max_yaw_error_rad, 0.3, 1e-9);
  EXPECT_NEAR(e.final_position_error_m, 0.0, 1e-9);
  EXPECT_LT(e.rmse_position_m, 0.1);
}

TEST(TrajectoryError, TheEstimateIsInterpolatedAtTheTruthsTimesAcrossTheYawSeam) {
  // A coarse estimate of the same motion: interpolation between its samples is what the truth
  // is compared with. The yaw passes +-pi between two estimate samples.
  std::vector<TrajectoryPoint> truth, estimate;
  for (int k = 0; k <= 100; ++k) {
    const double t = 0.01 * k;
    truth.push_back({t, t, 0.0, std::remainder(kPi - 0.5 + t, 2.0 * kPi)});
  }
  for (int k = 0; k <= 10; ++k) {
    const double t = 0.1 * k;
    estimate.push_back({t, t, 0.0, std::remainder(kPi - 0.5 + t, 2.0 * kPi)});
  }
  const TrajectoryErrors e = compare_trajectories(truth, estimate);
  EXPECT_NEAR(e.rmse_position_m, 0.0, 1e-12);
  EXPECT_NEAR(e.rmse_yaw_rad, 0.0, 1e-9);
}

TEST(TrajectoryError, TruthOutsideTheEstimatesSpanIsCountedNotCompared) {
  const auto truth = circle(0.1, 20.0);
  const auto estimate = circle(0.1, 10.0);
  const TrajectoryErrors e = compare_trajectories(truth, estimate);
  EXPECT_EQ(e.compared + e.outside, static_cast<std::int64_t>(truth.size()));
  EXPECT_NEAR(static_cast<double>(e.outside), 100.0, 1.0);
}

TEST(TrajectoryError, AlignmentRemovesAFrameRotationAndOffset) {
  // The same path seen in another frame (GPS east/north against odometry that starts at the
  // origin facing x): rotated by 0.7 rad and moved. Aligned on its first 2 m, nothing is left;
  // a truth without yaw gives NaN yaw errors and finite position errors.
  const auto truth = circle(0.1, 20.0);
  std::vector<TrajectoryPoint> other;
  const double c = std::cos(0.7), s = std::sin(0.7);
  for (const auto& p : truth) {
    other.push_back({p.t_s, c * p.x_m - s * p.y_m + 5.0, s * p.x_m + c * p.y_m - 3.0,
                     std::remainder(p.yaw_rad + 0.7, 2.0 * kPi)});
  }
  EXPECT_GT(compare_trajectories(truth, other).rmse_position_m, 1.0);
  const TrajectoryErrors e = compare_trajectories(truth, other, {2.0});
  EXPECT_NEAR(e.rmse_position_m, 0.0, 1e-9);
  EXPECT_NEAR(e.rmse_yaw_rad, 0.0, 1e-9);
  EXPECT_NEAR(e.alignment_rotation_rad, -0.7, 1e-9);
  auto no_yaw = truth;
  for (auto& p : no_yaw) p.yaw_rad = std::nan("");
  const TrajectoryErrors g = compare_trajectories(no_yaw, other, {2.0});
  EXPECT_NEAR(g.rmse_position_m, 0.0, 1e-9);
  EXPECT_TRUE(std::isnan(g.rmse_yaw_rad));
  EXPECT_THROW(compare_trajectories(no_yaw, other, {100.0}), std::invalid_argument);
  EXPECT_THROW(compare_trajectories(truth, no_yaw), std::invalid_argument);  // Estimate needs yaw.
}

TEST(TrajectoryError, BadInputIsAnErrorNamingTheProblem) {
  const auto good = circle(0.1, 5.0);
  const auto expect_error = [](const std::vector<TrajectoryPoint>& t,
                               const std::vector<TrajectoryPoint>& e, const std::string& what) {
    try {
      compare_trajectories(t, e);
      ADD_FAILURE() << what;
    } catch (const std::invalid_argument& err) {
      EXPECT_NE(std::string(err.what()).find(what), std::string::npos) << err.what();
    }
  };
  expect_error({good.front()}, good, "truth has 1 samples");
  auto nan = good;
  nan[3].y_m = std::nan("");
  expect_error(good, nan, "estimate sample 3 has a non-finite value");
  auto backwards = good;
  backwards[5].t_s = backwards[2].t_s;
  expect_error(backwards, good, "truth sample 5: time goes backwards");
  auto later = good;
  for (auto& p : later) p.t_s += 100.0;
  expect_error(good, later, "no truth sample lies inside");
}

}  // namespace
}  // namespace dispel::eval
