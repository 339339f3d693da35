#pragma once
/// @file
/// A generic unscented Kalman filter over a fixed-size state (thesis section 2.3), written so that
/// the thesis's alpha = 0.001 (central weight near -1e6) stays numerically sound: every weighted
/// sum is taken over differences from the central sigma point, never over absolute values.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstddef>
#include <limits>

#include "dispel/core/pose2.hpp"

namespace dispel {

/// Wraps an angle to (-pi, pi] (exactly: std::remainder is exact, so wrap_to_pi(a + 2 pi k) == a
/// for a in (-pi, pi] up to the rounding of the argument itself).
inline double wrap_to_pi(double angle_rad) {
  const double r = std::remainder(angle_rad, 2.0 * kPi);
  return r <= -kPi ? r + 2.0 * kPi : r;
}

/// Scaling of the sigma points (Julier and Uhlmann's scaled unscented transform). Defaults are
/// the thesis's (Appendix A).
struct UkfParameters {
  /// Spread of the sigma points around the mean, in (0, 1]. Small values keep the points close
  /// to the mean; 0.001 gives a central weight of about -1e6 (harmless in this implementation).
  double alpha = 0.001;
  /// Prior knowledge of the distribution (2 is optimal for a Gaussian), >= 0.
  double beta = 2.0;
  /// Secondary scaling; n + kappa must be > 0 for the state dimension n.
  double kappa = 0.0;

  /// Throws std::invalid_argument naming the first bad field ("<prefix>alpha ...").
  void validate(const char* prefix = "ukf.") const;
};

/// The outcome of one filter step.
enum class UkfStatus {
  kOk,                   ///< The step was applied.
  kGated,                ///< The innovation failed the gate; state and covariance are unchanged.
  kNotPositiveDefinite,  ///< A covariance could not be factored even after repair; unchanged.
  kNonFinite,            ///< The model produced NaN or infinity; state and covariance unchanged.
};

/// The outcome of a measurement update.
struct UkfUpdateResult {
  UkfStatus status = UkfStatus::kOk;
  /// Normalised innovation squared nu^T S^-1 nu (NaN if S could not be formed).
  double nis = std::numeric_limits<double>::quiet_NaN();
};

/// The probability-p quantile of the chi-square distribution with @p dof degrees of freedom
/// (the x with P(chi2_dof <= x) = p), for p in [0, 1) and dof >= 1. Accurate to about 1e-10
/// relative. Used for innovation gates and consistency bands.
double chi_square_quantile(double probability, int dof);

/// Which state components need special treatment.
template <int N>
struct UkfStateLayout {
  /// Angles: differences are wrapped to (-pi, pi], the mean is wrapped to (-pi, pi].
  std::array<bool, N> angle{};
  /// Components the process model only carries forward additively, f(x + t e_k) = f(x) + t e_k
  /// (positions in a planar motion model). The prediction evaluates f with these components
  /// relative to the current mean and adds the mean back afterwards, so that a state far from the
  /// origin (x = 1e5 m) is predicted as exactly as one at the origin, whatever alpha is.
  /// Measurement functions see the absolute value.
  std::array<bool, N> translation{};
};

/// Unscented Kalman filter over an N-dimensional state (Wan and van der Merwe's formulation):
///
///   sigma points  chi_0 = x,  chi_{+-j} = x +- sqrt(n + lambda) L_j,  P = L L^T (checked LLT),
///   lambda = alpha^2 (n + kappa) - n,  Wm_0 = lambda / (n + lambda),
///   Wc_0 = Wm_0 + 1 - alpha^2 + beta,  W_i = 1 / (2 (n + lambda)) for i >= 1.
///
/// Predict: y_i = f(chi_i), d_i = y_i - y_0 (angles wrapped), m = sum_{i>=1} W_i d_i,
/// x = y_0 + m, P = sum_{i>=1} W_i d_i d_i^T + (beta - alpha^2) m m^T + Q; the last form is
/// algebraically equal to sum_i Wc_i (y_i - x)(y_i - x)^T but never multiplies by Wc_0.
/// Update: sigma points are redrawn from the predicted covariance (which includes Q),
/// S = sum W dz dz^T + (beta - alpha^2) m_z m_z^T + R, P_xz = sum W dx dz^T, K = P_xz S^-1, and the
/// covariance is formed as (I - K H) P (I - K H)^T + K (S - H P H^T) K^T with the statistically
/// linearised H = P_xz^T P^-1 (equal to P - K S K^T, but a sum of positive terms), then
/// symmetrised.
///
/// A covariance whose Cholesky factorisation fails is repaired once by symmetrising and adding a
/// growing diagonal jitter (counted in cholesky_repairs()); if that fails too the step is refused
/// with UkfStatus::kNotPositiveDefinite and nothing changes.
template <int N>
class UnscentedKalmanFilter {
 public:
  static_assert(N > 0, "the state needs at least one component");
  static constexpr int kSigmaPoints = 2 * N + 1;
  using State = Eigen::Matrix<double, N, 1>;
  using Covariance = Eigen::Matrix<double, N, N>;
  using Layout = UkfStateLayout<N>;

  /// Throws std::invalid_argument if @p params is invalid or n + kappa <= 0.
  explicit UnscentedKalmanFilter(const UkfParameters& params = {}, const Layout& layout = {})
      : params_(params), layout_(layout) {
    params.validate();
    if (!(N + params.kappa > 0.0)) reject_kappa(params.kappa);
    const double a2 = params.alpha * params.alpha;
    scale_ = a2 * (N + params.kappa);  // n + lambda
    weight_ = 1.0 / (2.0 * scale_);
    mean_weight0_ = (scale_ - N) / scale_;
    extra_weight0_ = params.beta - a2;
    spread_ = std::sqrt(scale_);
  }

  /// Sets the state and its covariance (symmetric positive definite, asserted symmetric).
  void reset(const State& x, const Covariance& p) {
    assert((p - p.transpose()).cwiseAbs().maxCoeff() <= 1e-9 * (1.0 + p.cwiseAbs().maxCoeff()));
    x_ = x;
    wrap_angles(x_);
    p_ = symmetrised(p);
  }

  const State& state() const { return x_; }
  const Covariance& covariance() const { return p_; }
  const UkfParameters& parameters() const { return params_; }
  /// Weight of the central sigma point in the mean (about -1e6 for alpha = 0.001, n = 6).
  double mean_weight0() const { return mean_weight0_; }
  /// Weight of every other sigma point.
  double weight() const { return weight_; }
  /// How often a covariance had to be repaired before it could be factored.
  long long cholesky_repairs() const { return repairs_; }

  /// Propagates through x_k = f(x_{k-1}) and adds the process noise @p q of this step.
  /// @p f maps a State to a State (it need not wrap angles).
  template <class F>
  UkfStatus predict(F&& f, const Covariance& q) {
    Covariance l;
    if (!factor(p_, l)) return UkfStatus::kNotPositiveDefinite;
    State centre = x_;
    for (int k = 0; k < N; ++k) {
      if (layout_.translation[k]) centre(k) = 0.0;
    }
    const State y0 = f(centre);
    Eigen::Matrix<double, N, 2 * N> d;
    for (int j = 0; j < N; ++j) {
      const State offset = spread_ * l.col(j);
      d.col(j) = difference(f(State(centre + offset)), y0);
      d.col(N + j) = difference(f(State(centre - offset)), y0);
    }
    const State m = weight_ * d.rowwise().sum();
    State x = y0 + m;
    for (int k = 0; k < N; ++k) {
      if (layout_.translation[k]) x(k) += x_(k);
    }
    wrap_angles(x);
    Covariance p = weight_ * d * d.transpose() + extra_weight0_ * m * m.transpose() + q;
    p = symmetrised(p);
    if (!x.allFinite() || !p.allFinite()) return UkfStatus::kNonFinite;
    x_ = x;
    p_ = p;
    return UkfStatus::kOk;
  }

  /// Corrects with measurement @p z = h(x) + v, v ~ N(0, r). Components flagged in
  /// @p z_is_angle are angles (innovations wrapped). If the normalised innovation squared
  /// exceeds @p gate_nis (e.g. chi_square_quantile(0.999, M); infinity = no gate) the update is
  /// refused with UkfStatus::kGated and nothing changes.
  template <int M, class H>
  UkfUpdateResult update(H&& h, const Eigen::Matrix<double, M, 1>& z,
                         const typename Eigen::Matrix<double, M, M>::PlainObject& r,
                         const std::array<bool, static_cast<std::size_t>(M)>& z_is_angle = {},
                         double gate_nis = std::numeric_limits<double>::infinity()) {
    using Measurement = Eigen::Matrix<double, M, 1>;
    UkfUpdateResult result;
    Covariance l;
    if (!factor(p_, l)) {
      result.status = UkfStatus::kNotPositiveDefinite;
      return result;
    }
    const Eigen::Matrix<double, N, N> dx = spread_ * l;  // Sigma points are x +- dx.col(j).
    const Measurement z0 = h(x_);
    Eigen::Matrix<double, M, 2 * N> dz;
    for (int j = 0; j < N; ++j) {
      dz.col(j) = difference<M>(h(State(x_ + dx.col(j))), z0, z_is_angle);
      dz.col(N + j) = difference<M>(h(State(x_ - dx.col(j))), z0, z_is_angle);
    }
    if (!z0.allFinite() || !dz.allFinite()) {
      result.status = UkfStatus::kNonFinite;
      return result;
    }
    const Measurement mz = weight_ * dz.rowwise().sum();
    Measurement z_mean = z0 + mz;
    Measurement nu = z - z_mean;
    for (int k = 0; k < M; ++k) {
      if (z_is_angle[k]) nu(k) = wrap_to_pi(nu(k));
    }
    Eigen::Matrix<double, M, M> s =
        weight_ * dz * dz.transpose() + extra_weight0_ * mz * mz.transpose() + r;
    s = symmetrised(s);
    // sum_{i>=1} W dx_i = 0 by symmetry, so no mean term enters the cross covariance.
    const Eigen::Matrix<double, N, M> pxz =
        weight_ * (dx * (dz.leftCols(N) - dz.rightCols(N)).transpose());
    Eigen::Matrix<double, M, M> ls;
    if (!factor(s, ls)) {
      result.status = UkfStatus::kNotPositiveDefinite;
      return result;
    }
    const Measurement whitened = ls.template triangularView<Eigen::Lower>().solve(nu);
    result.nis = whitened.squaredNorm();
    if (!std::isfinite(result.nis)) {
      result.status = UkfStatus::kNonFinite;
      return result;
    }
    if (result.nis > gate_nis) {
      result.status = UkfStatus::kGated;
      return result;
    }
    // K = P_xz S^-1 and H^T = P^-1 P_xz through the Cholesky factors.
    const Eigen::Matrix<double, N, M> k =
        solve_with_factor<M, N>(ls, Eigen::Matrix<double, M, N>(pxz.transpose())).transpose();
    const Eigen::Matrix<double, N, M> ht = solve_with_factor<N, M>(l, pxz);
    State x = x_ + k * nu;
    wrap_angles(x);
    const Covariance a = Covariance::Identity() - k * ht.transpose();
    Eigen::Matrix<double, M, M> rest = s - pxz.transpose() * ht;  // S - H P H^T >= R.
    rest = symmetrised(rest);
    Covariance p = a * p_ * a.transpose() + k * rest * k.transpose();
    p = symmetrised(p);
    if (!x.allFinite() || !p.allFinite()) {
      result.status = UkfStatus::kNonFinite;
      return result;
    }
    x_ = x;
    p_ = p;
    return result;
  }

 private:
  [[noreturn]] static void reject_kappa(double kappa);

  // (A + A^T) / 2 into a new matrix (assigning it to A in place would read overwritten entries).
  template <int K>
  static Eigen::Matrix<double, K, K> symmetrised(const Eigen::Matrix<double, K, K>& a) {
    Eigen::Matrix<double, K, K> out = a;
    for (int i = 0; i < K; ++i) {
      for (int j = 0; j < i; ++j) out(i, j) = out(j, i) = 0.5 * (a(i, j) + a(j, i));
    }
    return out;
  }

  State difference(const State& a, const State& b) const {
    State d = a - b;
    for (int k = 0; k < N; ++k) {
      if (layout_.angle[k]) d(k) = wrap_to_pi(d(k));
    }
    return d;
  }

  template <int M>
  static Eigen::Matrix<double, M, 1> difference(
      const Eigen::Matrix<double, M, 1>& a, const Eigen::Matrix<double, M, 1>& b,
      const std::array<bool, static_cast<std::size_t>(M)>& is_angle) {
    Eigen::Matrix<double, M, 1> d = a - b;
    for (int k = 0; k < M; ++k) {
      if (is_angle[k]) d(k) = wrap_to_pi(d(k));
    }
    return d;
  }

  void wrap_angles(State& x) const {
    for (int k = 0; k < N; ++k) {
      if (layout_.angle[k]) x(k) = wrap_to_pi(x(k));
    }
  }

  // Solves (L L^T) X = B for the lower Cholesky factor L.
  template <int K, int C>
  static Eigen::Matrix<double, K, C> solve_with_factor(const Eigen::Matrix<double, K, K>& l,
                                                       const Eigen::Matrix<double, K, C>& b) {
    const Eigen::Matrix<double, K, C> y = l.template triangularView<Eigen::Lower>().solve(b);
    return l.transpose().template triangularView<Eigen::Upper>().solve(y);
  }

  // The lower Cholesky factor of @p a, repairing it (symmetrise, diagonal jitter growing tenfold)
  // if the plain factorisation fails. False if even that fails or @p a is not finite.
  template <int K>
  bool factor(const Eigen::Matrix<double, K, K>& a, Eigen::Matrix<double, K, K>& l) {
    if (!a.allFinite()) return false;
    Eigen::LLT<Eigen::Matrix<double, K, K>> llt(a);
    if (llt.info() == Eigen::Success) {
      l = llt.matrixL();
      return true;
    }
    Eigen::Matrix<double, K, K> repaired = symmetrised(a);
    const double base = std::max(repaired.diagonal().cwiseAbs().maxCoeff(), 1e-300);
    for (double jitter = 1e-12 * base; jitter <= 1e-3 * base; jitter *= 10.0) {
      repaired.diagonal().array() += jitter;
      llt.compute(repaired);
      if (llt.info() == Eigen::Success) {
        ++repairs_;
        l = llt.matrixL();
        return true;
      }
    }
    return false;
  }

  UkfParameters params_;
  Layout layout_;
  double scale_ = 1.0;          // n + lambda = alpha^2 (n + kappa)
  double spread_ = 1.0;         // sqrt(n + lambda)
  double weight_ = 0.5;         // W_i, i >= 1
  double mean_weight0_ = 0.0;   // Wm_0
  double extra_weight0_ = 2.0;  // Wc_0 - Wm_0 - 1 = beta - alpha^2
  State x_ = State::Zero();
  Covariance p_ = Covariance::Identity();
  long long repairs_ = 0;
};

/// Throws std::invalid_argument for a kappa with n + kappa <= 0 (out of line, cold).
[[noreturn]] void reject_ukf_kappa(int state_dimension, double kappa);

template <int N>
void UnscentedKalmanFilter<N>::reject_kappa(double kappa) {
  reject_ukf_kappa(N, kappa);
}

}  // namespace dispel
