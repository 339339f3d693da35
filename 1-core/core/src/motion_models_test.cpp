#include "dispel/core/motion_models.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "dispel/core/pose2.hpp"

// Suite names start with "odom_" so that `ctest -R odom` selects every odometry test
// (gtest_discover_tests names tests "Suite.Name" without the executable's name).

namespace dispel {
namespace {

using I = CtIndex;

CtState<double> ct(double x, double y, double v, double psi, double omega) {
  CtState<double> s;
  s << x, y, v, psi, omega;
  return s;
}

// The continuous model x' = v cos psi, y' = v sin psi, psi' = omega (v, omega constant),
// integrated by classic Runge-Kutta with @p steps steps.
CtState<double> rk4(const CtState<double>& s0, double dt, int steps) {
  auto deriv = [](const Eigen::Vector3d& p, double v, double omega) {
    return Eigen::Vector3d(v * std::cos(p(2)), v * std::sin(p(2)), omega);
  };
  const double v = s0(I::kV);
  const double omega = s0(I::kOmega);
  Eigen::Vector3d p(s0(I::kX), s0(I::kY), s0(I::kPsi));
  const double h = dt / steps;
  for (int k = 0; k < steps; ++k) {
    const Eigen::Vector3d k1 = deriv(p, v, omega);
    const Eigen::Vector3d k2 = deriv(p + 0.5 * h * k1, v, omega);
    const Eigen::Vector3d k3 = deriv(p + 0.5 * h * k2, v, omega);
    const Eigen::Vector3d k4 = deriv(p + h * k3, v, omega);
    p += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
  }
  return ct(p(0), p(1), v, p(2), omega);
}

// Eq. 3.12 evaluated in long double with the quotient form (no sinc), straight line at 0.
Eigen::Vector3d ct_reference(double v, double psi, double omega, double dt) {
  using L = long double;
  const L lv = v, lpsi = psi, lw = omega, lt = dt;
  L chord = lv * lt;
  if (omega != 0.0) chord = L(2) * lv / lw * std::sin(lw * lt / L(2));
  const L heading = lpsi + lw * lt / L(2);
  return {static_cast<double>(chord * std::cos(heading)),
          static_cast<double>(chord * std::sin(heading)), static_cast<double>(lpsi + lw * lt)};
}

TEST(OdomMotionModels, CtExactMatchesRungeKuttaIntegrationOfTheContinuousModel) {
  const std::vector<double> speeds{0.0, 0.3, 2.0, -1.0};
  const std::vector<double> rates{0.0, 1e-12, -1e-12, 1e-6, 0.5, -0.5, 3.0, -2.7};
  const std::vector<double> steps{0.01, 0.1, 1.0, 2.5};
  const std::vector<double> headings{0.0, 2.5, -3.1};
  for (double v : speeds) {
    for (double omega : rates) {
      for (double dt : steps) {
        for (double psi : headings) {
          const CtState<double> s = ct(12.0, -7.0, v, psi, omega);
          const CtState<double> exact = ct_predict(s, dt);
          const CtState<double> numeric = rk4(s, dt, 4000);
          // RK4 with 4000 steps is accurate to far below 1e-10 here.
          EXPECT_NEAR(exact(I::kX), numeric(I::kX), 1e-10)
              << "v " << v << " omega " << omega << " T " << dt << " psi " << psi;
          EXPECT_NEAR(exact(I::kY), numeric(I::kY), 1e-10);
          EXPECT_NEAR(exact(I::kPsi), numeric(I::kPsi), 1e-12);
          EXPECT_EQ(exact(I::kV), v);
          EXPECT_EQ(exact(I::kOmega), omega);
        }
      }
    }
  }
}

TEST(OdomMotionModels, CtExactIsContinuousAcrossZeroYawRateToMachinePrecision) {
  const double v = 1.3;
  const double psi = 0.7;
  const double dt = 0.1;
  for (double omega : {-1e-6, -1e-9, 0.0, 1e-9, 1e-6}) {
    const CtState<double> out = ct_predict(ct(0.0, 0.0, v, psi, omega), dt);
    const Eigen::Vector3d ref = ct_reference(v, psi, omega, dt);
    // A few ulps of a displacement of 0.13 m: the Taylor branch and the limit agree exactly.
    EXPECT_NEAR(out(I::kX), ref(0), 4e-17) << "omega " << omega;
    EXPECT_NEAR(out(I::kY), ref(1), 4e-17) << "omega " << omega;
    EXPECT_NEAR(out(I::kPsi), ref(2), 1e-16) << "omega " << omega;
  }
  // Neighbours differ only by the physics (y changes by v T^2 omega / 2), never by a jump.
  const double y_plus = ct_predict(ct(0.0, 0.0, v, 0.0, 1e-9), dt)(I::kY);
  const double y_zero = ct_predict(ct(0.0, 0.0, v, 0.0, 0.0), dt)(I::kY);
  EXPECT_NEAR(y_plus - y_zero, v * dt * dt * 1e-9 / 2.0, 1e-24);
}

TEST(OdomMotionModels, SincIsSmoothAcrossItsTaylorThreshold) {
  for (double a : {0.01, -0.01}) {
    const double below = sinc(std::nextafter(a, 0.0));
    const double above = sinc(a);
    EXPECT_NEAR(below, above, 4.5e-16);  // Two ulps of 1.
    EXPECT_NEAR(above, std::sin(a) / a, 2.3e-16);
  }
  EXPECT_EQ(sinc(0.0), 1.0);
  EXPECT_NEAR(sinc(1e-3), std::sin(1e-3) / 1e-3, 2e-16);
}

TEST(OdomMotionModels, CtEulerErrorShrinksWithTheSquareOfTheStep) {
  const CtState<double> s = ct(1.0, 2.0, 1.5, 0.4, 0.8);
  auto error = [&](double dt) {
    return (ct_predict_euler(s, dt) - ct_predict(s, dt)).head<2>().norm();
  };
  const double e1 = error(0.02);
  const double e2 = error(0.01);
  const double e3 = error(0.005);
  EXPECT_NEAR(e1 / e2, 4.0, 0.05);
  EXPECT_NEAR(e2 / e3, 4.0, 0.05);
  // The leading term: |v T (omega T / 2)|.
  EXPECT_NEAR(e2, 1.5 * 0.01 * 0.8 * 0.01 / 2.0, 1e-8);
  // Heading and the straight line are exact in the Euler form too.
  EXPECT_EQ(ct_predict_euler(s, 0.01)(I::kPsi), ct_predict(s, 0.01)(I::kPsi));
  const CtState<double> straight = ct(1.0, 2.0, 1.5, 0.4, 0.0);
  EXPECT_LT((ct_predict_euler(straight, 0.3) - ct_predict(straight, 0.3)).norm(), 1e-15);
}

TEST(OdomMotionModels, OmniMovesInTheBodyFrameRotatedByYaw) {
  using O = OmniIndex;
  OmniState<double> s;
  s << 3.0, 4.0, kPi / 2.0, 1.0, 0.5, 0.2;  // Facing +y, driving forward and to the left.
  const OmniState<double> out = omni_predict(s, 0.1);
  EXPECT_NEAR(out(O::kX), 3.0 - 0.05, 1e-15);  // Left of a robot facing +y is -x.
  EXPECT_NEAR(out(O::kY), 4.0 + 0.1, 1e-15);
  EXPECT_NEAR(out(O::kPsi), kPi / 2.0 + 0.02, 1e-15);
  EXPECT_EQ(out.tail<3>(), s.tail<3>());
  // Without sideways speed it is the CT model's Euler form.
  s(O::kVy) = 0.0;
  const CtState<double> c = ct(3.0, 4.0, 1.0, kPi / 2.0, 0.2);
  const OmniState<double> o = omni_predict(s, 0.1);
  const CtState<double> e = ct_predict_euler(c, 0.1);
  EXPECT_NEAR(o(O::kX), e(I::kX), 1e-15);
  EXPECT_NEAR(o(O::kY), e(I::kY), 1e-15);
}

TEST(OdomMotionModels, ProcessNoiseIsTheThesisDiagonalScaledByTheStep) {
  const Eigen::Matrix<double, 5, 5> q = ct_process_noise(0.05, 0.01, 0.049);
  Eigen::Matrix<double, 5, 1> diag;
  diag << 0.0, 0.0, 0.05 * 0.01, 0.0, 0.05 * 0.049;
  EXPECT_EQ(q.diagonal(), diag);
  EXPECT_EQ((q - Eigen::Matrix<double, 5, 5>(diag.asDiagonal())).norm(), 0.0);
  const Eigen::Matrix<double, 6, 6> qo = omni_process_noise(0.05, 0.01, 0.049);
  Eigen::Matrix<double, 6, 1> diag_o;
  diag_o << 0.0, 0.0, 0.0, 0.05 * 0.01, 0.05 * 0.01, 0.05 * 0.049;
  EXPECT_EQ(qo.diagonal(), diag_o);
}

TEST(OdomMotionModels, WheelMeasurementsOfADifferentialDrive) {
  EXPECT_DOUBLE_EQ(wheel_linear_velocity(0.4, 0.6), 0.5);
  EXPECT_DOUBLE_EQ(wheel_yaw_rate(0.4, 0.6, 0.5), 0.4);  // Right wheel faster: turning left.
  EXPECT_DOUBLE_EQ(wheel_yaw_rate(-0.25, 0.25, 0.5), 1.0);
}

}  // namespace
}  // namespace dispel
