#include "dispel/core/velocity_filter.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>
#include <stdexcept>
#include <string>

namespace dispel {
namespace {

// The textbook filter, written with full matrices, to check the written-out predict and update.
struct ReferenceKf {
  Eigen::Vector4d x;
  Eigen::Matrix4d p;
  void step(const Eigen::Vector2d& z, double dt, const VelocityFilterConfig& c) {
    Eigen::Matrix4d f = Eigen::Matrix4d::Identity();
    f(0, 2) = f(1, 3) = dt;
    Eigen::Matrix4d q = Eigen::Matrix4d::Zero();
    const double s = dt / c.nominal_scan_period_s;
    q.diagonal() << c.position_variance_m2 * s, c.position_variance_m2 * s,
        c.velocity_variance_m2ps2 * s, c.velocity_variance_m2ps2 * s;
    Eigen::Matrix<double, 2, 4> h = Eigen::Matrix<double, 2, 4>::Zero();
    h(0, 0) = h(1, 1) = 1.0;
    const Eigen::Matrix2d r = Eigen::Matrix2d::Identity() * c.measurement_variance_m2;
    x = f * x;
    p = f * p * f.transpose() + q;
    const Eigen::Matrix<double, 4, 2> k = p * h.transpose() * (h * p * h.transpose() + r).inverse();
    x += k * (z - h * x);
    p = (Eigen::Matrix4d::Identity() - k * h) * p;
  }
};

TEST(PointVelocityFilter, MatchesTheTextbookFilterWithVariableTimeSteps) {
  const VelocityFilterConfig config;
  PointVelocityFilter kf({1.0, 2.0}, config);
  ReferenceKf ref{kf.state(), kf.covariance()};
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> dt_dist(0.01, 0.3);
  std::normal_distribution<double> noise(0.0, 0.02);
  double t = 0.0;
  for (int k = 0; k < 200; ++k) {
    const double dt = dt_dist(rng);
    t += dt;
    const Eigen::Vector2d z(1.0 + 0.7 * t + noise(rng), 2.0 - 0.3 * t + noise(rng));
    kf.predict_and_update(z, dt, config);
    ref.step(z, dt, config);
    ASSERT_LT((kf.state() - ref.x).norm(), 1e-9) << "step " << k;
    ASSERT_LT((kf.covariance() - ref.p).norm(), 1e-6 * ref.p.norm()) << "step " << k;
  }
}

TEST(PointVelocityFilter, ConvergesToTheTrueVelocityAndCovarianceStaysPositive) {
  const VelocityFilterConfig config;
  PointVelocityFilter kf({0.0, 0.0}, config);
  std::mt19937 rng(9);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (int k = 1; k <= 200; ++k) {
    const double t = 0.05 * k;
    kf.predict_and_update({1.2 * t + noise(rng), -0.4 * t + noise(rng)}, 0.05, config);
    const Eigen::Matrix4d& p = kf.covariance();
    ASSERT_LT((p - p.transpose()).norm(), 1e-9);
    ASSERT_GT(Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d>(p).eigenvalues().minCoeff(), 0.0);
  }
  EXPECT_NEAR(kf.velocity().x(), 1.2, 0.05);
  EXPECT_NEAR(kf.velocity().y(), -0.4, 0.05);
  EXPECT_NEAR(kf.predicted_position(1.0).x(), kf.position().x() + kf.velocity().x(), 1e-12);
}

TEST(PointVelocityFilter, DecayShrinksVelocityAndHoldKeepsIt) {
  const VelocityFilterConfig config;
  PointVelocityFilter kf({0.0, 0.0}, config);
  for (int k = 1; k <= 100; ++k) kf.predict_and_update({0.05 * k, 0.0}, 0.05, config);
  const Eigen::Vector2d v = kf.velocity();
  ASSERT_GT(v.x(), 0.9);
  PointVelocityFilter held = kf;
  held.predict_and_hold({7.0, 1.0}, 0.05, config);
  EXPECT_EQ(held.position(), Eigen::Vector2d(7.0, 1.0));
  EXPECT_EQ(held.velocity(), v);
  kf.predict_and_decay({7.0, 1.0}, 0.05, config);
  EXPECT_EQ(kf.position(), Eigen::Vector2d(7.0, 1.0));
  EXPECT_LT((kf.velocity() - config.velocity_decay * v).norm(), 1e-12);
}

TEST(VelocityFilterConfig, BadValuesAreRejectedByName) {
  const auto expect_bad = [](VelocityFilterConfig c, const std::string& field) {
    try {
      c.validate();
      ADD_FAILURE() << "accepted bad " << field;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  VelocityFilterConfig c;
  EXPECT_NO_THROW(c.validate());
  c.measurement_variance_m2 = 0.0;
  expect_bad(c, "measurement_variance_m2");
  c = VelocityFilterConfig{};
  c.velocity_decay = 1.5;
  expect_bad(c, "velocity_decay");
  c = VelocityFilterConfig{};
  c.nominal_scan_period_s = -1.0;
  expect_bad(c, "nominal_scan_period_s");
}

}  // namespace
}  // namespace dispel
