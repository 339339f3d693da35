#include "dispel/core/odometry_fusion.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "dispel/core/motion_models.hpp"
#include "dispel/core/ukf.hpp"

// Suite names start with "odom_" so that `ctest -R odom` selects every odometry test.

namespace dispel {
namespace {

constexpr double kTrack = 0.5;

std::int64_t wheels(const OdometryFusion& f, OdometryEvent e) {
  return f.counters().wheels[static_cast<std::size_t>(e)];
}
std::int64_t imu(const OdometryFusion& f, OdometryEvent e) {
  return f.counters().imu[static_cast<std::size_t>(e)];
}

// ---------------------------------------------------------------------------------------------
// Consistency on simulated data. The truth follows the filter's own CT model: speed, yaw rate
// and gyro bias are random walks with the configured variances; the wheels (50 Hz) and the gyro
// (100 Hz) have white Gaussian noise of known variance. The NEES e^T P^-1 e of the full state
// (x, y, v, psi, omega, b), averaged over the runs and over check times once per second, must lie
// inside the 95% chi-square band of one time step, [chi2_0.025(M n), chi2_0.975(M n)] / M;
// averaging over time can only narrow the spread, so the band is conservative.
struct MonteCarloResult {
  double anees = 0.0;
  double band_low = 0.0;
  double band_high = 0.0;
};

MonteCarloResult monte_carlo_nees(const OdometryConfig& config, int runs, double duration_s,
                                  double wheel_noise_mps, double gyro_noise_radps) {
  const int n = 6;
  double nees_sum = 0.0;
  int samples = 0;
  for (int run = 0; run < runs; ++run) {
    std::mt19937_64 rng(1000 + static_cast<std::uint64_t>(run));
    std::normal_distribution<double> n01(0.0, 1.0);
    OdometryFusion filter(config);
    // The truth starts as a draw from the filter's prior.
    CtState<double> truth;
    truth << std::sqrt(config.initial_position_variance_m2) * n01(rng),
        std::sqrt(config.initial_position_variance_m2) * n01(rng),
        std::sqrt(config.initial_velocity_variance_m2ps2) * n01(rng),
        std::sqrt(config.initial_yaw_variance_rad2) * n01(rng),
        std::sqrt(config.initial_yaw_rate_variance_rad2ps2) * n01(rng);
    double bias = std::sqrt(config.gyro_bias_initial_variance_rad2ps2) * n01(rng);
    const double dt = 0.01;
    const int steps = static_cast<int>(std::lround(duration_s / dt));
    for (int k = 0; k <= steps; ++k) {
      const double t = k * dt;
      if (k > 0) {
        truth = ct_predict(truth, dt);
        truth(CtIndex::kV) += std::sqrt(dt * config.linear_velocity_variance_m2ps3) * n01(rng);
        truth(CtIndex::kOmega) += std::sqrt(dt * config.yaw_rate_variance_rad2ps3) * n01(rng);
        bias += std::sqrt(dt * config.gyro_bias_random_walk_variance_rad2ps3) * n01(rng);
      }
      const double v = truth(CtIndex::kV);
      const double w = truth(CtIndex::kOmega);
      EXPECT_EQ(filter.add_imu(t, w + bias + gyro_noise_radps * n01(rng)),
                OdometryEvent::kAccepted);
      if (k % 2 == 0) {
        const double left = v - 0.5 * kTrack * w + wheel_noise_mps * n01(rng);
        const double right = v + 0.5 * kTrack * w + wheel_noise_mps * n01(rng);
        EXPECT_EQ(filter.add_wheels(t, left, right), OdometryEvent::kAccepted);
      }
      if (k > 0 && k % 100 == 0) {
        Eigen::Matrix<double, 6, 1> e =
            filter.state() - (Eigen::Matrix<double, 6, 1>() << truth, bias).finished();
        e(CtIndex::kPsi) = wrap_to_pi(e(CtIndex::kPsi));
        const Eigen::MatrixXd p = filter.covariance();
        nees_sum += e.dot(p.llt().solve(e));
        ++samples;
      }
    }
  }
  MonteCarloResult r;
  r.anees = nees_sum / samples;
  const double m = runs;
  r.band_low = chi_square_quantile(0.025, runs * n) / m;
  r.band_high = chi_square_quantile(0.975, runs * n) / m;
  return r;
}

OdometryConfig simulation_config(double alpha, double wheel_noise_mps, double gyro_noise_radps) {
  OdometryConfig c;
  c.ukf_alpha = alpha;
  c.track_width_m = kTrack;
  c.wheel_velocity_variance_m2ps2 = wheel_noise_mps * wheel_noise_mps / 2.0;
  c.wheel_yaw_rate_variance_rad2ps2 = 2.0 * wheel_noise_mps * wheel_noise_mps / (kTrack * kTrack);
  c.imu_yaw_rate_variance_rad2ps2 = gyro_noise_radps * gyro_noise_radps;
  c.gyro_bias_initial_variance_rad2ps2 = 1e-4;
  c.gyro_bias_random_walk_variance_rad2ps3 = 1e-6;
  c.initial_position_variance_m2 = 1e-4;
  c.initial_yaw_variance_rad2 = 1e-4;
  c.gate_probability = 0.0;  // Consistency of the filter itself; no measurement is an outlier.
  return c;
}

class OdomFusionConsistency : public ::testing::TestWithParam<double> {};

TEST_P(OdomFusionConsistency, AverageNeesOfMonteCarloRunsIsInsideTheChiSquareBand) {
  const double wheel_noise = 0.01;
  const double gyro_noise = 0.005;
  const MonteCarloResult r = monte_carlo_nees(
      simulation_config(GetParam(), wheel_noise, gyro_noise), 50, 30.0, wheel_noise, gyro_noise);
  RecordProperty("anees", std::to_string(r.anees));
  EXPECT_GT(r.anees, r.band_low) << "band [" << r.band_low << ", " << r.band_high << "]";
  EXPECT_LT(r.anees, r.band_high) << "band [" << r.band_low << ", " << r.band_high << "]";
}

INSTANTIATE_TEST_SUITE_P(Alphas, OdomFusionConsistency, ::testing::Values(0.001, 0.1, 0.5, 1.0));

// ---------------------------------------------------------------------------------------------
// Long runs. kLongRunSteps measurements (half wheels, half IMU, 100 Hz): a lawnmower pattern of
// straight lines and U-turns with smooth 2 s transitions, 10 000 s for the full count. The
// covariance must stay exactly symmetric and positive definite without ever needing a repair or
// refusing a step. The full 1e6 steps take 3.7 s in Release; under AddressSanitizer (GCC defines
// __SANITIZE_ADDRESS__) they take about a minute, so the sanitizer build runs 1e5: it looks for
// memory errors, the Release build for numerical drift.
#if defined(__SANITIZE_ADDRESS__)
constexpr int kLongRunSteps = 100'000;
#else
constexpr int kLongRunSteps = 1'000'000;
#endif

// Speed and yaw rate of the lawnmower pattern: per 60 s, 48 s straight at 0.5 m/s, a 2 s
// transition into a U-turn at 0.2 m/s and pi/10 rad/s (alternating left and right), 8 s of
// turning, a 2 s transition back.
std::pair<double, double> lawnmower(double t) {
  const double phase = std::fmod(t, 60.0);
  double turning = 0.0;  // 0 straight, 1 turning.
  if (phase >= 48.0 && phase < 50.0) turning = 0.5 - 0.5 * std::cos(kPi * (phase - 48.0) / 2.0);
  if (phase >= 50.0 && phase < 58.0) turning = 1.0;
  if (phase >= 58.0) turning = 0.5 + 0.5 * std::cos(kPi * (phase - 58.0) / 2.0);
  const double side = static_cast<int>(t / 60.0) % 2 == 0 ? 1.0 : -1.0;
  return {0.5 - 0.3 * turning, side * turning * kPi / 10.0};
}

TEST(OdomFusionLongRun, CovarianceStaysSymmetricPositiveDefiniteOverAMillionSteps) {
  for (OdometryModel model : {OdometryModel::kCt, OdometryModel::kOmni}) {
    OdometryConfig config;
    config.model = model;
    OdometryFusion filter(config);
    std::mt19937 rng(11);
    std::normal_distribution<double> noise(0.0, 0.005);
    for (int k = 0; k < kLongRunSteps; ++k) {
      const double t = 0.01 * k;
      const auto [v, w] = lawnmower(t);
      const OdometryEvent e = k % 2 == 0 ? filter.add_wheels(t, v - 0.5 * kTrack * w + noise(rng),
                                                             v + 0.5 * kTrack * w + noise(rng))
                                         : filter.add_imu(t, w + 0.01 + noise(rng));
      ASSERT_TRUE(e == OdometryEvent::kAccepted || e == OdometryEvent::kGated)
          << "step " << k << ": " << odometry_event_name(e);
      if (k % 10000 == 0 || k == kLongRunSteps - 1) {
        const Eigen::MatrixXd p = filter.covariance();
        ASSERT_EQ((p - p.transpose()).cwiseAbs().maxCoeff(), 0.0) << "step " << k;
        ASSERT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(p).eigenvalues().minCoeff(), 0.0)
            << "step " << k;
      }
    }
    EXPECT_EQ(filter.counters().cholesky_repairs, 0);
    // Noise beyond the 99.9% gate happens; more than 1% gated would mean a broken filter.
    EXPECT_LT(filter.counters().count(OdometryEvent::kGated), kLongRunSteps / 100);
    EXPECT_NEAR(filter.estimate().gyro_bias_radps, 0.01, 2e-3);
  }
}

// ---------------------------------------------------------------------------------------------
// Gyro bias: standing still, the wheels say omega = 0 and the gyro reports a constant 0.02 rad/s.
// With the bias state the bias is learnt and the yaw does not drift; without it the filter
// believes part of the gyro and turns.
// Returns the estimates after duration_s / 2 and after duration_s.
std::pair<OdometryEstimate, OdometryEstimate> stand_still(bool bias_enabled, double duration_s) {
  OdometryConfig config;
  config.gyro_bias_enabled = bias_enabled;
  OdometryFusion filter(config);
  std::mt19937 rng(5);
  std::normal_distribution<double> wheel_noise(0.0, 0.003);
  std::normal_distribution<double> gyro_noise(0.0, 0.003);
  OdometryEstimate half;
  const int steps = static_cast<int>(std::lround(duration_s / 0.01));
  for (int k = 0; k <= steps; ++k) {
    const double t = 0.01 * k;
    filter.add_imu(t, 0.02 + gyro_noise(rng));
    if (k % 2 == 0) filter.add_wheels(t, wheel_noise(rng), wheel_noise(rng));
    if (k == steps / 2) half = filter.estimate();
  }
  return {half, filter.estimate()};
}

TEST(OdomFusionGyroBias, StandingStillTheBiasConvergesAndTheYawDoesNotDrift) {
  const auto [half, end] = stand_still(true, 120.0);
  EXPECT_NEAR(end.gyro_bias_radps, 0.02, 1e-3);
  EXPECT_LT(std::sqrt(end.gyro_bias_variance_rad2ps2), 2e-3);
  // While the bias is being learnt (the first seconds) the yaw moves a little; then it stays.
  EXPECT_LT(std::abs(end.yaw_rad), 0.05);
  EXPECT_LT(std::abs(end.yaw_rad - half.yaw_rad), 0.005);
  EXPECT_LT(std::abs(end.omega_radps), 0.01);  // Noise level of one gyro sample.
  const auto [half_without, without] = stand_still(false, 120.0);
  EXPECT_EQ(without.gyro_bias_radps, 0.0);
  EXPECT_GT(std::abs(without.yaw_rad - half_without.yaw_rad), 0.5);  // Turning all along.
  EXPECT_GT(std::abs(without.yaw_rad), 20.0 * std::abs(end.yaw_rad));
}

// ---------------------------------------------------------------------------------------------
// Wheel slip: the robot drives straight at 0.5 m/s for 20 s; from 8.0 s to 8.6 s the left wheel
// spins at 1.0 m/s. The gate refuses the slipping measurements (and counts them); the final
// position error stays at the noise level, while the ungated filter turns and ends far off.
OdometryFusion drive_with_slip(double gate_probability) {
  OdometryConfig config;
  config.gate_probability = gate_probability;
  OdometryFusion filter(config);
  std::mt19937 rng(21);
  std::normal_distribution<double> wheel_noise(0.0, 0.003);
  std::normal_distribution<double> gyro_noise(0.0, 0.003);
  for (int k = 0; k <= 2000; ++k) {
    const double t = 0.01 * k;
    filter.add_imu(t, gyro_noise(rng));
    if (k % 2 == 0) {
      const bool slipping = t >= 8.0 - 1e-9 && t < 8.6 - 1e-9;
      filter.add_wheels(t, (slipping ? 1.0 : 0.5) + wheel_noise(rng), 0.5 + wheel_noise(rng));
    }
  }
  return filter;
}

TEST(OdomFusionGate, WheelSlipIsGatedAndCountedAndThePoseStaysAccurate) {
  const OdometryFusion gated = drive_with_slip(0.999);
  const OdometryFusion ungated = drive_with_slip(0.0);
  auto error = [](const OdometryFusion& f) {
    const OdometryEstimate e = f.estimate();
    return std::hypot(e.x_m - 0.5 * 20.0, e.y_m);
  };
  EXPECT_EQ(wheels(gated, OdometryEvent::kGated), 30);  // Every slipping sample, no other.
  EXPECT_EQ(wheels(gated, OdometryEvent::kGateOverridden), 0);
  EXPECT_EQ(wheels(ungated, OdometryEvent::kGated), 0);
  EXPECT_LT(error(gated), 0.05);
  EXPECT_GT(error(ungated), 10.0 * error(gated));
  EXPECT_LT(std::abs(gated.estimate().yaw_rad), 0.01);
}

// A robot that drives straight at 0.5 m/s for 2 s, then turns on the spot at 0.6 rad/s for 3 s,
// starting and stopping the turn at once (no ramp); stopped at `end_s`. Wheels at 50 Hz, the gyro
// at 100 Hz unless `with_imu` is false.
OdometryFusion turn_on_the_spot(const OdometryConfig& config, bool with_imu, double end_s = 6.0) {
  OdometryFusion filter(config);
  const double b = config.track_width_m;
  for (int k = 0; k <= static_cast<int>(std::lround(end_s / 0.01)); ++k) {
    const double t = 0.01 * k;
    const bool turning = t >= 2.0 - 1e-9 && t < 5.0 - 1e-9;
    const double w = turning ? 0.6 : 0.0, v = turning ? 0.0 : 0.5;
    if (with_imu) filter.add_imu(t, w);
    if (k % 2 == 0) filter.add_wheels(t, v - 0.5 * w * b, v + 0.5 * w * b);
  }
  return filter;
}

TEST(OdomFusionGate, ATurnBothSensorsSeeIsFusedAtOnce) {
  // The turn starts faster than the yaw-rate random walk expects, so the gate refuses it; the
  // wheels and the gyro agree, so it is a manoeuvre, not a slip.
  // Stopped in the middle of the turn (1.5 s into it).
  OdometryConfig config;
  const OdometryFusion agreeing = turn_on_the_spot(config, true, 3.5);
  config.gate_agreement_radps = 0.0;
  const OdometryFusion gate_only = turn_on_the_spot(config, true, 3.5);
  const double true_yaw = 0.6 * 1.5;
  EXPECT_NEAR(agreeing.estimate().yaw_rad, true_yaw, 0.02);
  // The first samples at the turn's start are refused: the gyro's until the wheels agree, and the
  // wheels' for 0.1 s, since their speed drops to 0 at once as well (which the gyro cannot
  // confirm). Without the agreement the gyro and the wheels are refused for 2 s.
  EXPECT_LE(agreeing.counters().count(OdometryEvent::kGated), 8);
  EXPECT_GT(gate_only.counters().count(OdometryEvent::kGated), 100);
  EXPECT_GT(std::abs(gate_only.estimate().yaw_rad - true_yaw), 0.15);
}

TEST(OdomFusionGate, WithoutAGyroTheWheelsAreNotGated) {
  // Nothing but the motion model could call the turn a slip: the wheels are taken as they are
  // (and the filter follows dead reckoning), unless gate_wheels_without_imu asks otherwise.
  OdometryConfig config;
  const OdometryFusion wheels_only = turn_on_the_spot(config, false);
  EXPECT_EQ(wheels(wheels_only, OdometryEvent::kGated), 0);
  EXPECT_NEAR(wheels_only.estimate().yaw_rad, 0.6 * 3.0, 0.02);
  config.gate_wheels_without_imu = true;
  const OdometryFusion gated = turn_on_the_spot(config, false);
  EXPECT_GT(wheels(gated, OdometryEvent::kGated), 20);
}

TEST(OdomFusionGate, APersistentChangeIsAcceptedAfterTheOverrideTime) {
  // The robot is pushed: the wheels jump from 0.5 to 1.5 m/s and stay there. The gate refuses
  // the jump at first, but cannot lock the filter out.
  OdometryConfig config;
  config.gate_override_after_s = 0.5;
  OdometryFusion filter(config);
  for (int k = 0; k <= 300; ++k) {
    const double t = 0.02 * k;
    const double v = t < 2.0 ? 0.5 : 1.5;
    filter.add_wheels(t, v, v);
    filter.add_imu(t, 0.0);
  }
  EXPECT_GT(wheels(filter, OdometryEvent::kGated), 0);
  EXPECT_EQ(wheels(filter, OdometryEvent::kGateOverridden), 1);
  EXPECT_NEAR(filter.estimate().v_mps, 1.5, 1e-3);
}

// ---------------------------------------------------------------------------------------------
// Bad data never aborts: it is counted and leaves the state as it was.
TEST(OdomFusionRejection, NonFiniteAndOutOfOrderInputsAreCountedAndChangeNothing) {
  OdometryFusion filter{OdometryConfig{}};
  ASSERT_EQ(filter.add_wheels(1.0, 0.5, 0.5), OdometryEvent::kAccepted);
  ASSERT_EQ(filter.add_imu(1.01, 0.0), OdometryEvent::kAccepted);
  ASSERT_EQ(filter.add_wheels(1.02, 0.5, 0.5), OdometryEvent::kAccepted);
  const Eigen::VectorXd x = filter.state();
  const Eigen::MatrixXd p = filter.covariance();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(filter.add_wheels(1.03, nan, 0.5), OdometryEvent::kRejectedNonFinite);
  EXPECT_EQ(filter.add_wheels(1.03, 0.5, inf), OdometryEvent::kRejectedNonFinite);
  EXPECT_EQ(filter.add_imu(nan, 0.0), OdometryEvent::kRejectedNonFinite);
  EXPECT_EQ(filter.add_imu(1.03, -inf), OdometryEvent::kRejectedNonFinite);
  EXPECT_EQ(filter.add_imu(1.005, 0.0), OdometryEvent::kRejectedOutOfOrder);
  EXPECT_EQ(filter.add_wheels(0.5, 0.5, 0.5), OdometryEvent::kRejectedOutOfOrder);
  EXPECT_EQ(filter.state(), x);
  EXPECT_EQ(filter.covariance(), p);
  EXPECT_EQ(filter.estimate().t_s, 1.02);
  EXPECT_EQ(wheels(filter, OdometryEvent::kRejectedNonFinite), 2);
  EXPECT_EQ(imu(filter, OdometryEvent::kRejectedNonFinite), 2);
  EXPECT_EQ(wheels(filter, OdometryEvent::kRejectedOutOfOrder), 1);
  EXPECT_EQ(imu(filter, OdometryEvent::kRejectedOutOfOrder), 1);
  EXPECT_EQ(filter.counters().count(OdometryEvent::kAccepted), 3);
  // The same time stamp again is in order (a second sensor at the same instant).
  EXPECT_EQ(filter.add_imu(1.02, 0.0), OdometryEvent::kAccepted);
  EXPECT_STREQ(odometry_event_name(OdometryEvent::kRejectedOutOfOrder), "rejected_out_of_order");
}

TEST(OdomFusionRejection, InvalidConfigurationThrowsNamingTheField) {
  auto message = [](OdometryConfig c) -> std::string {
    try {
      OdometryFusion filter(c);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  OdometryConfig c;
  EXPECT_EQ(message(c), "");
  c.track_width_m = 0.0;
  EXPECT_EQ(message(c), "odometry.track_width_m must be a finite number > 0, got 0");
  c = OdometryConfig{};
  c.ukf_alpha = 0.0;
  EXPECT_EQ(message(c).rfind("odometry.ukf_alpha must be in (0, 1]", 0), 0u) << message(c);
  c = OdometryConfig{};
  c.ukf_kappa = -6.0;
  EXPECT_EQ(message(c).rfind("odometry.ukf_kappa", 0), 0u) << message(c);
  c = OdometryConfig{};
  c.linear_velocity_variance_m2ps3 = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(message(c).rfind("odometry.linear_velocity_variance_m2ps3", 0), 0u);
  c = OdometryConfig{};
  c.imu_smoothing = 0.0;
  EXPECT_EQ(message(c).rfind("odometry.imu_smoothing must be in (0, 1]", 0), 0u);
  c = OdometryConfig{};
  c.gate_probability = 1.0;
  EXPECT_EQ(message(c).rfind("odometry.gate_probability", 0), 0u);
  c = OdometryConfig{};
  c.max_time_step_s = -0.1;
  EXPECT_EQ(message(c).rfind("odometry.max_time_step_s", 0), 0u);
  c = OdometryConfig{};
  c.gyro_bias_random_walk_variance_rad2ps3 = -1.0;
  EXPECT_EQ(message(c).rfind("odometry.gyro_bias_random_walk_variance_rad2ps3", 0), 0u);
  c = OdometryConfig{};
  c.model = static_cast<OdometryModel>(7);
  EXPECT_EQ(message(c).rfind("odometry.model", 0), 0u);
  EXPECT_THROW(WheelOdometry(-1.0), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// Models and helpers.
TEST(OdomFusion, NoiseFreeArcIsFollowedByEveryModelAndByDeadReckoning) {
  // 0.4 m/s on a circle of radius 2 m (omega 0.2 rad/s) for 10 s, starting at (1, 2, 0.3).
  const Pose2 start{1.0, 2.0, 0.3};
  const double v = 0.4;
  const double w = 0.2;
  CtState<double> s;
  s << start.x_m, start.y_m, v, start.yaw_rad, w;
  const CtState<double> truth = ct_predict(s, 10.0);
  WheelOdometry dead_reckoning(kTrack, start);
  for (int k = 0; k <= 500; ++k) {
    dead_reckoning.add_wheels(0.02 * k, v - 0.5 * kTrack * w, v + 0.5 * kTrack * w);
  }
  const OdometryEstimate dr = dead_reckoning.estimate();
  EXPECT_NEAR(dr.x_m, truth(CtIndex::kX), 1e-12);
  EXPECT_NEAR(dr.y_m, truth(CtIndex::kY), 1e-12);
  EXPECT_NEAR(dr.yaw_rad, truth(CtIndex::kPsi), 1e-12);
  EXPECT_TRUE(std::isnan(dr.x_variance_m2));

  for (OdometryModel model : {OdometryModel::kCt, OdometryModel::kCtEuler, OdometryModel::kOmni}) {
    OdometryConfig config;
    config.model = model;
    OdometryFusion filter(config, start);
    for (int k = 0; k <= 1000; ++k) {
      const double t = 0.01 * k;
      filter.add_imu(t, w);
      if (k % 2 == 0) filter.add_wheels(t, v - 0.5 * kTrack * w, v + 0.5 * kTrack * w);
    }
    const OdometryEstimate e = filter.estimate();
    // The filter starts at v = 0; the first few updates cost a little distance.
    const double tolerance = model == OdometryModel::kCt ? 2e-3 : 5e-3;
    EXPECT_NEAR(e.x_m, truth(CtIndex::kX), tolerance) << odometry_model_name(model);
    EXPECT_NEAR(e.y_m, truth(CtIndex::kY), tolerance) << odometry_model_name(model);
    EXPECT_NEAR(e.yaw_rad, truth(CtIndex::kPsi), 1e-3) << odometry_model_name(model);
    EXPECT_NEAR(e.v_mps, v, 1e-4);
    EXPECT_NEAR(e.omega_radps, w, 1e-4);
    EXPECT_NEAR(e.lateral_velocity_mps, 0.0, 1e-3);
    EXPECT_EQ(e.t_s, 10.0);
    EXPECT_GT(e.x_variance_m2, 0.0);
  }
}

TEST(OdomFusion, LongGapsAreSplitAndPredictLooksAheadWithoutChangingTheFilter) {
  OdometryFusion filter{OdometryConfig{}};
  filter.add_wheels(0.0, 0.5, 0.5);
  const OdometryEstimate ahead = filter.predict(1.0);
  EXPECT_EQ(ahead.t_s, 1.0);
  EXPECT_EQ(filter.estimate().t_s, 0.0);
  EXPECT_EQ(filter.counters().split_predictions, 0);
  EXPECT_EQ(filter.estimate().x_m, 0.0);
  // Slightly short of v T: the yaw rate is uncertain and a mean over arcs is shorter.
  EXPECT_NEAR(ahead.x_m, 0.5, 3e-3);
  EXPECT_LT(ahead.x_m, 0.5);
  filter.add_wheels(1.0, 0.5, 0.5);
  EXPECT_EQ(filter.counters().split_predictions, 1);  // 1 s in steps of at most 0.1 s.
  EXPECT_NEAR(filter.estimate().x_m, ahead.x_m, 1e-3);
  EXPECT_EQ(filter.estimate().t_s, 1.0);
}

TEST(OdomFusion, ImuSmoothingIsTheExponentialMovingAverage) {
  OdometryConfig config;
  config.imu_smoothing = 0.5;
  config.gyro_bias_enabled = false;
  config.imu_yaw_rate_variance_rad2ps2 = 1e-10;  // Trust the (smoothed) gyro completely.
  config.gate_probability = 0.0;
  OdometryFusion filter(config);
  filter.add_imu(0.0, 0.0);
  filter.add_imu(0.01, 1.0);
  EXPECT_NEAR(filter.estimate().omega_radps, 0.5, 1e-6);
  filter.add_imu(0.02, 1.0);
  EXPECT_NEAR(filter.estimate().omega_radps, 0.75, 1e-6);
  filter.add_imu(0.03, 1.0);
  EXPECT_NEAR(filter.estimate().omega_radps, 0.875, 1e-6);
}

}  // namespace
}  // namespace dispel
