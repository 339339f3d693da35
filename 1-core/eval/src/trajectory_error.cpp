#include "dispel/eval/trajectory_error.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace dispel::eval {
namespace {

constexpr double kPi = 3.14159265358979323846;

double wrap(double a) {
  a = std::fmod(a + kPi, 2.0 * kPi);
  if (a < 0.0) a += 2.0 * kPi;
  return a - kPi;
}

void check(const std::vector<TrajectoryPoint>& p, const char* name, bool yaw_may_be_nan) {
  if (p.size() < 2) {
    throw std::invalid_argument(std::string(name) + " has " + std::to_string(p.size()) +
                                " samples; at least 2 are needed");
  }
  for (std::size_t i = 0; i < p.size(); ++i) {
    const TrajectoryPoint& s = p[i];
    if (!std::isfinite(s.t_s) || !std::isfinite(s.x_m) || !std::isfinite(s.y_m) ||
        !(std::isfinite(s.yaw_rad) || (yaw_may_be_nan && std::isnan(s.yaw_rad)))) {
      throw std::invalid_argument(std::string(name) + " sample " + std::to_string(i) +
                                  " has a non-finite value");
    }
    if (i > 0 && s.t_s < p[i - 1].t_s) {
      throw std::invalid_argument(std::string(name) + " sample " + std::to_string(i) +
                                  ": time goes backwards");
    }
  }
}

// The estimate's pose at time t (inside its span), interpolated.
TrajectoryPoint interpolate(const std::vector<TrajectoryPoint>& estimate, double t) {
  const auto after =
      std::upper_bound(estimate.begin(), estimate.end(), t,
                       [](double time, const TrajectoryPoint& p) { return time < p.t_s; });
  const TrajectoryPoint& a = *(after - 1);
  TrajectoryPoint at = a;
  at.t_s = t;
  if (after != estimate.end() && after->t_s > a.t_s) {
    const double u = (t - a.t_s) / (after->t_s - a.t_s);
    at.x_m = a.x_m + u * (after->x_m - a.x_m);
    at.y_m = a.y_m + u * (after->y_m - a.y_m);
    at.yaw_rad = a.yaw_rad + u * wrap(after->yaw_rad - a.yaw_rad);
  }
  return at;
}

bool inside(const std::vector<TrajectoryPoint>& estimate, double t) {
  return t >= estimate.front().t_s && t <= estimate.back().t_s;
}

// The rigid motion (rotation theta about the origin, then translation) that best moves the
// estimate onto the truth over the truth's first `metres` of path.
void align(const std::vector<TrajectoryPoint>& truth, std::vector<TrajectoryPoint>& estimate,
           double metres, double& theta) {
  std::vector<std::pair<TrajectoryPoint, TrajectoryPoint>> pairs;  // (truth, estimate)
  double path = 0.0;
  const TrajectoryPoint* previous = nullptr;
  for (const TrajectoryPoint& t : truth) {
    if (!inside(estimate, t.t_s)) continue;
    if (previous != nullptr) path += std::hypot(t.x_m - previous->x_m, t.y_m - previous->y_m);
    previous = &t;
    if (path > metres) break;
    pairs.emplace_back(t, interpolate(estimate, t.t_s));
  }
  if (path < metres) {
    throw std::invalid_argument("the truth covers only " + std::to_string(path) +
                                " m of path; cannot align on its first " + std::to_string(metres) +
                                " m");
  }
  double tx = 0.0, ty = 0.0, ex = 0.0, ey = 0.0;
  for (const auto& [t, e] : pairs) {
    tx += t.x_m, ty += t.y_m, ex += e.x_m, ey += e.y_m;
  }
  const auto n = static_cast<double>(pairs.size());
  tx /= n, ty /= n, ex /= n, ey /= n;
  double dot = 0.0, cross = 0.0;
  for (const auto& [t, e] : pairs) {
    const double ax = e.x_m - ex, ay = e.y_m - ey, bx = t.x_m - tx, by = t.y_m - ty;
    dot += ax * bx + ay * by;
    cross += ax * by - ay * bx;
  }
  theta = std::atan2(cross, dot);
  const double c = std::cos(theta), s = std::sin(theta);
  for (TrajectoryPoint& p : estimate) {
    const double x = p.x_m - ex, y = p.y_m - ey;
    p.x_m = c * x - s * y + tx;
    p.y_m = s * x + c * y + ty;
    p.yaw_rad = wrap(p.yaw_rad + theta);
  }
}

}  // namespace

TrajectoryErrors compare_trajectories(const std::vector<TrajectoryPoint>& truth,
                                      const std::vector<TrajectoryPoint>& original,
                                      const TrajectoryComparison& how) {
  check(truth, "truth", true);
  check(original, "estimate", false);
  if (!(how.align_first_m >= 0.0 && std::isfinite(how.align_first_m))) {
    throw std::invalid_argument("align_first_m must be a finite number >= 0");
  }
  std::vector<TrajectoryPoint> estimate = original;
  double theta = 0.0;
  if (how.align_first_m > 0.0) align(truth, estimate, how.align_first_m, theta);
  TrajectoryErrors e;
  double sum_x2 = 0.0, sum_y2 = 0.0, sum_yaw2 = 0.0;
  const TrajectoryPoint* previous = nullptr;
  for (const TrajectoryPoint& t : truth) {
    if (!inside(estimate, t.t_s)) {
      ++e.outside;
      continue;
    }
    const TrajectoryPoint at = interpolate(estimate, t.t_s);
    const double dx = at.x_m - t.x_m, dy = at.y_m - t.y_m, dyaw = wrap(at.yaw_rad - t.yaw_rad);
    sum_x2 += dx * dx;
    sum_y2 += dy * dy;
    sum_yaw2 += dyaw * dyaw;
    e.final_position_error_m = std::hypot(dx, dy);
    e.final_yaw_error_rad = std::abs(dyaw);
    e.max_position_error_m = std::max(e.max_position_error_m, e.final_position_error_m);
    if (!std::isnan(dyaw)) e.max_yaw_error_rad = std::max(e.max_yaw_error_rad, std::abs(dyaw));
    if (previous != nullptr) {
      e.path_length_m += std::hypot(t.x_m - previous->x_m, t.y_m - previous->y_m);
    }
    previous = &t;
    ++e.compared;
  }
  if (e.compared == 0) {
    throw std::invalid_argument("no truth sample lies inside the estimate's time span");
  }
  const auto n = static_cast<double>(e.compared);
  e.rmse_x_m = std::sqrt(sum_x2 / n);
  e.rmse_y_m = std::sqrt(sum_y2 / n);
  e.rmse_position_m = std::sqrt((sum_x2 + sum_y2) / n);
  e.rmse_yaw_rad = std::sqrt(sum_yaw2 / n);  // NaN when the truth has no yaw.
  e.alignment_rotation_rad = theta;
  if (std::isnan(e.rmse_yaw_rad)) e.max_yaw_error_rad = e.rmse_yaw_rad;
  return e;
}

}  // namespace dispel::eval
