#include "dispel/core/ukf.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "dispel/core/invalid_field.hpp"

namespace dispel {
namespace {

// Regularised lower incomplete gamma function P(a, x) (Numerical Recipes: series below a + 1,
// Lentz's continued fraction above).
double regularized_gamma_p(double a, double x) {
  if (x <= 0.0) return 0.0;
  const double log_prefix = a * std::log(x) - x - std::lgamma(a);
  if (x < a + 1.0) {
    double term = 1.0 / a;
    double sum = term;
    for (int n = 1; n < 100000; ++n) {
      term *= x / (a + n);
      sum += term;
      if (std::abs(term) < std::abs(sum) * 1e-16) break;
    }
    return sum * std::exp(log_prefix);
  }
  constexpr double kTiny = 1e-300;
  double b = x + 1.0 - a;
  double c = 1.0 / kTiny;
  double d = 1.0 / b;
  double h = d;
  for (int n = 1; n < 100000; ++n) {
    const double an = -n * (n - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < 1e-16) break;
  }
  return 1.0 - std::exp(log_prefix) * h;
}

}  // namespace

void UkfParameters::validate(const char* prefix) const {
  const std::string p(prefix);
  if (!std::isfinite(alpha) || !(alpha > 0.0) || alpha > 1.0) {
    reject_field(p + "alpha", alpha, "in (0, 1]");
  }
  if (!std::isfinite(beta) || beta < 0.0) reject_field(p + "beta", beta, "a finite number >= 0");
  if (!std::isfinite(kappa)) reject_field(p + "kappa", kappa, "finite");
}

void reject_ukf_kappa(int state_dimension, double kappa) {
  reject_field("ukf.kappa", kappa,
               ("> -" + std::to_string(state_dimension) + " (n + kappa > 0)").c_str());
}

double chi_square_quantile(double probability, int dof) {
  if (!(probability >= 0.0 && probability < 1.0) || dof < 1) {
    throw std::invalid_argument("chi_square_quantile needs probability in [0, 1) and dof >= 1");
  }
  if (probability == 0.0) return 0.0;
  const double a = 0.5 * dof;
  double lo = 0.0;
  double hi = dof + 10.0 * std::sqrt(2.0 * dof) + 50.0;
  while (regularized_gamma_p(a, 0.5 * hi) < probability) hi *= 2.0;
  for (int i = 0; i < 200 && hi - lo > 1e-13 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (regularized_gamma_p(a, 0.5 * mid) < probability ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace dispel
