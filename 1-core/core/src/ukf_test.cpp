#include "dispel/core/ukf.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <random>
#include <stdexcept>
#include <string>

#include "dispel/core/motion_models.hpp"

// Suite names start with "odom_" so that `ctest -R odom` selects every odometry test.

namespace dispel {
namespace {

using Vec4 = Eigen::Vector4d;
using Mat4 = Eigen::Matrix4d;

UkfParameters with_alpha(double alpha) {
  UkfParameters p;
  p.alpha = alpha;
  return p;
}

double relative_difference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).norm() / b.norm();
}

// A planar constant-velocity model (x, y, vx, vy) with position measurements, filtered by the
// textbook Kalman filter and by the UKF: on a linear problem they must agree, whatever alpha.
class OdomUkfLinear : public ::testing::TestWithParam<double> {};

TEST_P(OdomUkfLinear, MatchesTheTextbookKalmanFilter) {
  UnscentedKalmanFilter<4> ukf(with_alpha(GetParam()));
  Vec4 x(1.0, -2.0, 0.5, 0.1);
  Mat4 p = Mat4::Identity();
  p(0, 2) = p(2, 0) = 0.3;
  ukf.reset(x, p);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> dt_dist(0.01, 0.3);
  std::normal_distribution<double> noise(0.0, 0.05);
  const Eigen::Matrix2d r = Eigen::Vector2d(0.01, 0.02).asDiagonal();
  Eigen::Matrix<double, 2, 4> h = Eigen::Matrix<double, 2, 4>::Zero();
  h(0, 0) = h(1, 1) = 1.0;
  // The mean is a second difference of the model over a step alpha * sigma: its rounding error is
  // about eps |h(x)| / alpha^2 per step (1e-10 for alpha = 0.001), the covariance's is not.
  const double mean_tolerance = 1e-14 / (GetParam() * GetParam()) + 1e-12;
  double t = 0.0;
  for (int k = 0; k < 300; ++k) {
    const double dt = dt_dist(rng);
    t += dt;
    Mat4 f = Mat4::Identity();
    f(0, 2) = f(1, 3) = dt;
    const Mat4 q = Vec4(0.0, 0.0, 0.2 * dt, 0.1 * dt).asDiagonal();
    ASSERT_EQ(ukf.predict([&f](const Vec4& s) -> Vec4 { return f * s; }, q), UkfStatus::kOk);
    x = f * x;
    p = f * p * f.transpose() + q;
    ASSERT_LT((ukf.state() - x).norm(), mean_tolerance * (1.0 + x.norm())) << "predict " << k;
    ASSERT_LT(relative_difference(ukf.covariance(), p), 1e-10) << "predict " << k;

    const Eigen::Vector2d z(1.0 + 0.7 * t + noise(rng), -2.0 + 0.2 * t + noise(rng));
    const UkfUpdateResult result =
        ukf.update([&h](const Vec4& s) -> Eigen::Vector2d { return h * s; }, z, r);
    ASSERT_EQ(result.status, UkfStatus::kOk);
    const Eigen::Matrix2d s = h * p * h.transpose() + r;
    const Eigen::Matrix<double, 4, 2> gain = p * h.transpose() * s.inverse();
    const Eigen::Vector2d nu = z - h * x;
    x += gain * nu;
    p = (Mat4::Identity() - gain * h) * p;
    p = (0.5 * (p + p.transpose())).eval();
    EXPECT_NEAR(result.nis, nu.dot(s.inverse() * nu),
                std::max(1e-10, 10.0 * mean_tolerance) * (1.0 + result.nis));
    ASSERT_LT((ukf.state() - x).norm(), mean_tolerance * (1.0 + x.norm())) << "update " << k;
    ASSERT_LT(relative_difference(ukf.covariance(), p), 1e-9) << "update " << k;
  }
  EXPECT_EQ(ukf.cholesky_repairs(), 0);
}

INSTANTIATE_TEST_SUITE_P(Alphas, OdomUkfLinear, ::testing::Values(0.001, 0.1, 0.5, 1.0));

// The covariance sums taken relative to the central sigma point equal the textbook weighted sum
// sum_i Wc_i (y_i - mean)(y_i - mean)^T on a nonlinear model (where the mean term matters).
TEST(OdomUkf, PredictionEqualsTheTextbookSigmaPointSums) {
  for (double alpha : {0.3, 1.0}) {
    UkfParameters params;
    params.alpha = alpha;
    params.kappa = 1.0;
    UnscentedKalmanFilter<5> ukf(params);
    CtState<double> x;
    x << 0.5, -0.2, 1.2, 0.3, 0.9;
    Eigen::Matrix<double, 5, 5> p = Eigen::Matrix<double, 5, 5>::Identity() * 0.2;
    p(2, 4) = p(4, 2) = 0.05;
    ukf.reset(x, p);
    const double dt = 0.7;
    auto f = [dt](const CtState<double>& s) -> CtState<double> { return ct_predict(s, dt); };
    ASSERT_EQ(ukf.predict(f, Eigen::Matrix<double, 5, 5>::Zero()), UkfStatus::kOk);

    const int n = 5;
    const double lambda = alpha * alpha * (n + params.kappa) - n;
    const Eigen::Matrix<double, 5, 5> l = (p * (n + lambda)).llt().matrixL();
    std::vector<CtState<double>> y{f(x)};
    std::vector<double> wm{lambda / (n + lambda)};
    for (int j = 0; j < n; ++j) {
      y.push_back(f(x + l.col(j)));
      y.push_back(f(x - l.col(j)));
      wm.push_back(0.5 / (n + lambda));
      wm.push_back(0.5 / (n + lambda));
    }
    CtState<double> mean = CtState<double>::Zero();
    for (std::size_t i = 0; i < y.size(); ++i) mean += wm[i] * y[i];
    Eigen::Matrix<double, 5, 5> cov = Eigen::Matrix<double, 5, 5>::Zero();
    for (std::size_t i = 0; i < y.size(); ++i) {
      const double wc = i == 0 ? wm[0] + 1.0 - alpha * alpha + params.beta : wm[i];
      cov += wc * (y[i] - mean) * (y[i] - mean).transpose();
    }
    EXPECT_LT((ukf.state() - mean).norm(), 1e-12) << "alpha " << alpha;
    EXPECT_LT(relative_difference(ukf.covariance(), cov), 1e-12) << "alpha " << alpha;
  }
}

// A CT state heading almost exactly at +pi (sigma points on both sides of the +-pi cut) and far
// from the origin, predicted and corrected with a yaw-rate and a compass measurement, gives the
// same result as the same problem rotated and translated so that it sits at the origin heading 0.
class OdomUkfAngles : public ::testing::TestWithParam<double> {};

TEST_P(OdomUkfAngles, StateNearPiFarFromTheOriginMatchesTheSameProblemAtTheOrigin) {
  using Ct = CtState<double>;
  using Cov = Eigen::Matrix<double, 5, 5>;
  UkfStateLayout<5> layout;
  layout.angle[CtIndex::kPsi] = true;
  layout.translation[CtIndex::kX] = layout.translation[CtIndex::kY] = true;

  const double theta = kPi - 1e-5;  // The far problem's heading.
  const Eigen::Vector2d origin(1e5, -3e4);
  Ct far;
  far << origin.x(), origin.y(), 0.8, theta, 0.3;
  Cov p = Cov::Identity();
  p.diagonal() << 0.04, 0.01, 0.02, 0.0025, 0.01;
  p(0, 1) = p(1, 0) = 0.005;
  p(3, 4) = p(4, 3) = 0.002;
  p(0, 3) = p(3, 0) = -0.003;

  // Mapping from the far problem into the near one: positions rotated by -theta about origin.
  const Eigen::Matrix2d rot = Eigen::Rotation2Dd(-theta).toRotationMatrix();
  Cov j = Cov::Identity();
  j.topLeftCorner<2, 2>() = rot;
  auto to_near = [&](const Ct& s) {
    Ct out = s;
    out.head<2>() = rot * (s.head<2>() - origin);
    out(CtIndex::kPsi) = wrap_to_pi(s(CtIndex::kPsi) - theta);
    return out;
  };

  UnscentedKalmanFilter<5> a(with_alpha(GetParam()), layout);
  UnscentedKalmanFilter<5> b(with_alpha(GetParam()), layout);
  a.reset(far, p);
  b.reset(to_near(far), j * p * j.transpose());
  const double dt = 0.1;
  const Cov q = ct_process_noise(dt, 0.01, 0.049);
  auto f = [dt](const Ct& s) -> Ct { return ct_predict(s, dt); };
  auto h_rate = [](const Ct& s) { return Eigen::Matrix<double, 1, 1>(s(CtIndex::kOmega)); };
  auto h_yaw = [](const Ct& s) { return Eigen::Matrix<double, 1, 1>(s(CtIndex::kPsi)); };
  const Eigen::Matrix<double, 1, 1> r_rate(1e-3);
  const Eigen::Matrix<double, 1, 1> r_yaw(1e-3);
  const std::array<bool, 1> angle{true};
  for (int k = 0; k < 5; ++k) {
    ASSERT_EQ(a.predict(f, q), UkfStatus::kOk);
    ASSERT_EQ(b.predict(f, q), UkfStatus::kOk);
    const Eigen::Matrix<double, 1, 1> rate(0.25);
    ASSERT_EQ(a.update(h_rate, rate, r_rate).status, UkfStatus::kOk);
    ASSERT_EQ(b.update(h_rate, rate, r_rate).status, UkfStatus::kOk);
    // A compass reading just across the cut from the estimate: -pi + 0.01 is near +pi.
    const double yaw_far = wrap_to_pi(theta + 0.02 + 0.01 * k);
    ASSERT_EQ(a.update(h_yaw, Eigen::Matrix<double, 1, 1>(yaw_far), r_yaw, angle).status,
              UkfStatus::kOk);
    const Eigen::Matrix<double, 1, 1> yaw_near(wrap_to_pi(yaw_far - theta));
    ASSERT_EQ(b.update(h_yaw, yaw_near, r_yaw, angle).status, UkfStatus::kOk);
  }
  const Ct mapped = to_near(a.state());
  EXPECT_LT((mapped.head<2>() - b.state().head<2>()).norm(), 1e-9);
  EXPECT_NEAR(wrap_to_pi(mapped(CtIndex::kPsi) - b.state()(CtIndex::kPsi)), 0.0, 1e-10);
  EXPECT_NEAR(mapped(CtIndex::kV), b.state()(CtIndex::kV), 1e-10);
  EXPECT_NEAR(mapped(CtIndex::kOmega), b.state()(CtIndex::kOmega), 1e-10);
  EXPECT_LT(relative_difference(j * a.covariance() * j.transpose(), b.covariance()), 1e-8);
  // The estimate crossed the cut and is reported in (-pi, pi].
  EXPECT_LT(a.state()(CtIndex::kPsi), 0.0);
  EXPECT_GT(a.state()(CtIndex::kPsi), -kPi);
}

INSTANTIATE_TEST_SUITE_P(Alphas, OdomUkfAngles, ::testing::Values(0.001, 0.5, 1.0));

TEST(OdomUkf, WrapToPiCoversTheHalfOpenIntervalMinusPiExcludedPiIncluded) {
  EXPECT_EQ(wrap_to_pi(kPi), kPi);
  EXPECT_EQ(wrap_to_pi(-kPi), kPi);
  EXPECT_NEAR(wrap_to_pi(3.0 * kPi), kPi, 1e-15);
  EXPECT_NEAR(wrap_to_pi(-kPi + 1e-3), -kPi + 1e-3, 1e-15);
  EXPECT_NEAR(wrap_to_pi(7.0), 7.0 - 2.0 * kPi, 1e-15);
  EXPECT_EQ(wrap_to_pi(0.25), 0.25);
}

TEST(OdomUkf, IndefiniteCovarianceIsReportedAndLeavesTheStateUntouched) {
  UnscentedKalmanFilter<2> ukf;
  ukf.reset(Eigen::Vector2d(1.0, 2.0), Eigen::Vector2d(1.0, -1.0).asDiagonal());
  const auto identity = [](const Eigen::Vector2d& s) -> Eigen::Vector2d { return s; };
  EXPECT_EQ(ukf.predict(identity, Eigen::Matrix2d::Zero()), UkfStatus::kNotPositiveDefinite);
  const UkfUpdateResult u =
      ukf.update(identity, Eigen::Vector2d(0.0, 0.0), Eigen::Matrix2d::Identity());
  EXPECT_EQ(u.status, UkfStatus::kNotPositiveDefinite);
  EXPECT_EQ(ukf.state(), Eigen::Vector2d(1.0, 2.0));
  EXPECT_EQ(ukf.covariance()(1, 1), -1.0);
}

TEST(OdomUkf, SingularCovarianceIsRepairedWithJitterAndCounted) {
  UnscentedKalmanFilter<2> ukf;
  Eigen::Matrix2d p;
  p << 1.0, 1.0, 1.0, 1.0;  // Rank one: the plain factorisation fails.
  ukf.reset(Eigen::Vector2d(0.0, 0.0), p);
  const auto identity = [](const Eigen::Vector2d& s) -> Eigen::Vector2d { return s; };
  EXPECT_EQ(ukf.predict(identity, Eigen::Matrix2d::Identity() * 1e-3), UkfStatus::kOk);
  EXPECT_EQ(ukf.cholesky_repairs(), 1);
  EXPECT_EQ(Eigen::LLT<Eigen::Matrix2d>(ukf.covariance()).info(), Eigen::Success);
}

TEST(OdomUkf, GatedMeasurementIsRefusedWithItsNisAndChangesNothing) {
  UnscentedKalmanFilter<1> ukf;
  ukf.reset(Eigen::Matrix<double, 1, 1>(0.0), Eigen::Matrix<double, 1, 1>(1.0));
  const auto h = [](const Eigen::Matrix<double, 1, 1>& s) { return s; };
  const Eigen::Matrix<double, 1, 1> r(1.0);
  const double gate = chi_square_quantile(0.99, 1);
  const UkfUpdateResult far = ukf.update(h, Eigen::Matrix<double, 1, 1>(10.0), r, {}, gate);
  EXPECT_EQ(far.status, UkfStatus::kGated);
  EXPECT_NEAR(far.nis, 50.0, 1e-9);  // 10^2 / (1 + 1).
  EXPECT_EQ(ukf.state()(0), 0.0);
  EXPECT_EQ(ukf.covariance()(0, 0), 1.0);
  const UkfUpdateResult near = ukf.update(h, Eigen::Matrix<double, 1, 1>(2.0), r, {}, gate);
  EXPECT_EQ(near.status, UkfStatus::kOk);
  EXPECT_NEAR(ukf.state()(0), 1.0, 1e-12);
  EXPECT_NEAR(ukf.covariance()(0, 0), 0.5, 1e-12);
}

TEST(OdomUkf, NonFiniteModelOutputIsRefused) {
  UnscentedKalmanFilter<1> ukf;
  const auto bad = [](const Eigen::Matrix<double, 1, 1>& s) -> Eigen::Matrix<double, 1, 1> {
    return s * std::numeric_limits<double>::quiet_NaN();
  };
  EXPECT_EQ(ukf.predict(bad, Eigen::Matrix<double, 1, 1>(0.0)), UkfStatus::kNonFinite);
  EXPECT_EQ(
      ukf.update(bad, Eigen::Matrix<double, 1, 1>(0.0), Eigen::Matrix<double, 1, 1>(1.0)).status,
      UkfStatus::kNonFinite);
  EXPECT_EQ(ukf.state()(0), 0.0);
  EXPECT_EQ(ukf.covariance()(0, 0), 1.0);
}

TEST(OdomUkf, ChiSquareQuantilesMatchTables) {
  EXPECT_NEAR(chi_square_quantile(0.95, 1), 3.841458820694124, 1e-9);
  EXPECT_NEAR(chi_square_quantile(0.95, 2), 5.991464547107979, 1e-9);
  EXPECT_NEAR(chi_square_quantile(0.999, 2), 13.815510557964274, 1e-8);
  EXPECT_NEAR(chi_square_quantile(0.999, 3), 16.266236196238129, 1e-8);
  EXPECT_NEAR(chi_square_quantile(0.025, 300), 253.9123, 1e-3);
  EXPECT_NEAR(chi_square_quantile(0.975, 300), 349.8744, 1e-3);
  EXPECT_EQ(chi_square_quantile(0.0, 4), 0.0);
  EXPECT_THROW(chi_square_quantile(1.0, 2), std::invalid_argument);
  EXPECT_THROW(chi_square_quantile(0.5, 0), std::invalid_argument);
}

TEST(OdomUkf, InvalidParametersAreRejectedByName) {
  auto message = [](UkfParameters p) -> std::string {
    try {
      UnscentedKalmanFilter<3> ukf(p);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  UkfParameters p;
  p.alpha = 0.0;
  EXPECT_EQ(message(p).rfind("ukf.alpha must be in (0, 1]", 0), 0u) << message(p);
  p.alpha = 1.5;
  EXPECT_EQ(message(p).rfind("ukf.alpha", 0), 0u);
  p = UkfParameters{};
  p.beta = -1.0;
  EXPECT_EQ(message(p).rfind("ukf.beta", 0), 0u);
  p = UkfParameters{};
  p.kappa = -3.0;  // n + kappa = 0.
  EXPECT_EQ(message(p).rfind("ukf.kappa must be > -3", 0), 0u) << message(p);
  p.kappa = -2.0;
  EXPECT_EQ(message(p), "");
}

TEST(OdomUkf, WeightsOfTheThesisParameters) {
  UnscentedKalmanFilter<6> ukf;                             // alpha 0.001, beta 2, kappa 0.
  EXPECT_NEAR(ukf.mean_weight0(), 1.0 - 6.0 / 6e-6, 1e-3);  // -999 999.
  EXPECT_NEAR(ukf.weight(), 1.0 / (2.0 * 6e-6), 1e-3);
  EXPECT_NEAR(ukf.mean_weight0() + 12.0 * ukf.weight(), 1.0, 1e-9);
}

}  // namespace
}  // namespace dispel
