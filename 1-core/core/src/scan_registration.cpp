// Scan-to-map registration (scan_registration.hpp): thin and de-skew the scan, seed, point-to-line
// Gauss-Newton with a Geman-McClure kernel against the local voxel map, check, learn the threshold.
#include "dispel/core/scan_registration.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "dispel/core/floor_index.hpp"
#include "dispel/core/invalid_field.hpp"

namespace dispel {
namespace {

constexpr auto reject = reject_field;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInfinity = std::numeric_limits<double>::infinity();
// A margin for the rounding of distances of a few metres in bounds that must hold exactly.
constexpr double kDistanceMargin_m = 1e-9;
// map_normal(): the map's points within this radius of a map point, at least this many.
constexpr double kMapNormalRadius_m = 0.3;
constexpr int kMapNormalMinPoints = 4;
// A pose change that scales with time: motion per second times dt (first order).
Pose2 scaled(const Pose2& per_s, double dt) {
  return {per_s.x_m * dt, per_s.y_m * dt, per_s.yaw_rad * dt};
}
Eigen::Vector2d perp(const Eigen::Vector2d& v) { return {-v.y(), v.x()}; }

// Range at which an angular error is turned into metres for the adaptive threshold.
constexpr double kThresholdRange_m = 10.0;
// Sensor motion below which a scan says nothing about the seed's error.
constexpr double kMinMotionForThreshold_m = 0.02;
// The odometry's motion and the constant-velocity guess part by more than a robot's motors can
// change within a scan (1.5 rad/s^2 over a scan of 0.13 s moves the heading by 0.03 rad more than
// the guess): the guess is tried as a seed too. It replaces the odometry's alignment when it
// matches this much more of the scan (or the odometry's did not register); with 0.1 Debian's
// wheelchair log had 4 scans overruled and 16 beams removed, with 0.2 two and none.
constexpr double kSeedsApart_rad = 0.05;
constexpr double kSeedsApart_m = 0.15;
constexpr double kBetterShare = 0.2;
// A scan de-skewed by a turn that bends its sweep this much (at kThresholdRange_m) against the
// registered turn is de-skewed and aligned again, at most kMaxRealignments times
// (register_scan()).
constexpr double kRebend_m = 0.04;
constexpr int kMaxRealignments = 4;
// Laser-only, a scan is de-skewed by the constant-velocity guess's turn, then by its registered
// turn when that bends the sweep by more than this against the turn it was de-skewed by, at most
// kLaserOnlyRealignments times. On the simulated office loop at 1 m/s (768 beams, 7.5 Hz; seeds
// 1-20) the error over 1 s fell from 0.60 to 0.10 degrees (the seeded registration's 0.11): a
// scan bent by a turn was aligned with a turn of its own. With 4 cm and one realignment it stayed
// at 0.21 degrees.
constexpr double kLaserOnlyRebend_m = 0.01;
constexpr int kLaserOnlyRealignments = 3;
// Voxels hit by fewer scans than structure needs are forgotten when unseen this long (the trail
// of someone walking by).
constexpr double kTransientMemory_s = 2.0;
// Laser-only heading (RegistrationConfig::lateral_noise_mps): the sensor's x axis counts as this
// many scans at 1 m/s; a scan teaches the direction when it turned slower than kStraight_radps
// and moved faster than kMoving_mps; the direction is clear when the scatter across it is at most
// kClearShare of the scatter along it; the sideways motion per turn starts from none with the
// weight of kPriorTurn2 (rad/s)^2 of turning.
constexpr double kHeadingPriorScans = 10.0;
constexpr double kStraight_radps = 0.2;
constexpr double kMoving_mps = 0.2;
constexpr double kClearShare = 0.1;
constexpr double kPriorTurn2 = 1.0;

}  // namespace

void RegistrationConfig::validate() const {
  if (!(voxel_size_m >= 0.05 && voxel_size_m <= 5.0))
    reject("registration.voxel_size_m", voxel_size_m, "in [0.05, 5]");
  if (max_points_per_voxel < 1 || max_points_per_voxel > 4)
    reject("registration.max_points_per_voxel", max_points_per_voxel, "in [1, 4]");
  if (!(scan_spacing_m >= 0.0 && scan_spacing_m <= 1.0))
    reject("registration.scan_spacing_m", scan_spacing_m, "in [0, 1]");
  if (!(max_range_m > 0.0 && max_range_m <= 1000.0))
    reject("registration.max_range_m", max_range_m, "in (0, 1000]");
  if (!(local_map_radius_m > 0.0 && local_map_radius_m <= 1000.0))
    reject("registration.local_map_radius_m", local_map_radius_m, "in (0, 1000]");
  if (max_iterations < 1 || max_iterations > 1000)
    reject("registration.max_iterations", max_iterations, "in [1, 1000]");
  if (!(min_threshold_m > 0.0)) reject("registration.min_threshold_m", min_threshold_m, "> 0");
  if (!(max_threshold_m >= min_threshold_m && max_threshold_m <= 10.0))
    reject("registration.max_threshold_m", max_threshold_m, "in [min_threshold_m, 10]");
  if (!(initial_threshold_m >= min_threshold_m && initial_threshold_m <= max_threshold_m))
    reject("registration.initial_threshold_m", initial_threshold_m,
           "in [min_threshold_m, max_threshold_m]");
  if (!(min_inlier_share >= 0.0 && min_inlier_share <= 1.0))
    reject("registration.min_inlier_share", min_inlier_share, "in [0, 1]");
  if (min_points < 3) reject("registration.min_points", min_points, ">= 3");
  if (min_points_with_odometry < min_points)
    reject("registration.min_points_with_odometry", min_points_with_odometry, ">= min_points");
  if (!(max_correction_m > 0.0)) reject("registration.max_correction_m", max_correction_m, "> 0");
  if (!(max_correction_rad > 0.0 && max_correction_rad <= 3.2))
    reject("registration.max_correction_rad", max_correction_rad, "in (0, 3.2]");
  if (!(degeneracy_ratio >= 0.0 && degeneracy_ratio < 1.0))
    reject("registration.degeneracy_ratio", degeneracy_ratio, "in [0, 1)");
  if (explained_min_scans < 1)
    reject("registration.explained_min_scans", explained_min_scans, ">= 1");
  if (!(explained_min_span_s >= 0.0 && explained_min_span_s <= 3600.0))
    reject("registration.explained_min_span_s", explained_min_span_s, "in [0, 3600]");
  if (!(explained_min_span_in_free_s >= explained_min_span_s &&
        explained_min_span_in_free_s <= 3600.0))
    reject("registration.explained_min_span_in_free_s", explained_min_span_in_free_s,
           "in [explained_min_span_s, 3600]");
  if (!(explained_max_age_s > 0.0 && explained_max_age_s <= 3600.0))
    reject("registration.explained_max_age_s", explained_max_age_s, "in (0, 3600]");
  if (!(slide_tolerance_mps >= 0.0 && slide_tolerance_mps <= 100.0))
    reject("registration.slide_tolerance_mps", slide_tolerance_mps, "0 (off) or in (0, 100]");
  if (!(range_noise_m > 0.0 && range_noise_m <= 1.0))
    reject("registration.range_noise_m", range_noise_m, "in (0, 1]");
  if (!(odometry_noise_m > 0.0)) reject("registration.odometry_noise_m", odometry_noise_m, "> 0");
  if (!(odometry_noise_rad > 0.0))
    reject("registration.odometry_noise_rad", odometry_noise_rad, "> 0");
  if (!(constant_velocity_noise_m > 0.0))
    reject("registration.constant_velocity_noise_m", constant_velocity_noise_m, "> 0");
  if (!(velocity_smoothing > 0.0 && velocity_smoothing <= 1.0))
    reject("registration.velocity_smoothing", velocity_smoothing, "in (0, 1]");
  if (!(constant_velocity_noise_rad > 0.0))
    reject("registration.constant_velocity_noise_rad", constant_velocity_noise_rad, "> 0");
  if (!(lateral_noise_mps == 0.0 || (lateral_noise_mps >= 0.001 && lateral_noise_mps <= 10.0)))
    reject("registration.lateral_noise_mps", lateral_noise_mps, "0 (off) or in [0.001, 10]");
  if (!(fallback_turn_decay_s >= 0.0 && fallback_turn_decay_s <= 3600.0))
    reject("registration.fallback_turn_decay_s", fallback_turn_decay_s, "in [0, 3600]");
  if (!(explained_distance_m > 0.0 && explained_distance_m <= voxel_size_m))
    reject("registration.explained_distance_m", explained_distance_m, "in (0, voxel_size_m]");
}

ScanRegistration::ScanRegistration(RegistrationConfig config, SpeedLimits limits)
    : config_((config.validate(), config)), limits_(limits) {}

void ScanRegistration::reset() {
  map_.clear();
  explaining_valid_ = false;
  have_previous_ = false;
  previous_odometry_.reset();
  velocity_per_s_ = Pose2{};
  velocity_per_s_initialised_ = false;
  sparse_ = true;
}

ScanRegistration::Heading::Heading() : sxx(kHeadingPriorScans) {}

// The direction: the principal axis of the straight, moving scans' velocities (either way along
// it). The sideways motion per turn: the sideways part of velocity x turn rate over turn rate
// squared, summed over every registered scan (least squares through zero).
void ScanRegistration::Heading::learn(const Pose2& motion_per_s) {
  const Eigen::Vector2d v = motion_per_s.translation();
  const double w = motion_per_s.yaw_rad;
  if (!(v.allFinite() && std::isfinite(w))) return;
  velocity_by_turn += w * v;
  turn2 += w * w;
  if (std::abs(w) < kStraight_radps && v.norm() > kMoving_mps) {
    sxx += v.x() * v.x();
    sxy += v.x() * v.y();
    syy += v.y() * v.y();
    const double angle = 0.5 * std::atan2(2.0 * sxy, sxx - syy);
    forward = Eigen::Vector2d(std::cos(angle), std::sin(angle));
    const double mean = 0.5 * (sxx + syy);
    const double spread = std::sqrt(0.25 * (sxx - syy) * (sxx - syy) + sxy * sxy);
    clear = mean - spread <= kClearShare * (mean + spread);
  }
  sideways_per_turn_m = velocity_by_turn.dot(sideways()) / (turn2 + kPriorTurn2);
}

double ScanRegistration::learnt_heading_rad() const {
  return std::atan2(heading_.forward.y(), heading_.forward.x());
}

void ScanRegistration::hold_guess_sideways() {
  const Eigen::Vector2d side = heading_.sideways();
  Eigen::Vector2d v = velocity_per_s_.translation();
  v += (heading_.sideways_per_turn_m * velocity_per_s_.yaw_rad - v.dot(side)) * side;
  velocity_per_s_.x_m = v.x();
  velocity_per_s_.y_m = v.y();
}

inline ScanRegistration::Key ScanRegistration::key_of(const Eigen::Vector2d& p) const {
  return key_at(floor_index(p.x() / config_.voxel_size_m),
                floor_index(p.y() / config_.voxel_size_m));
}

template <typename F>
bool ScanRegistration::any_voxel_around(std::int64_t ix, std::int64_t iy, F&& f) const {
  constexpr std::array<std::int8_t, 9> kDx{0, -1, -1, -1, 0, 0, 1, 1, 1};
  constexpr std::array<std::int8_t, 9> kDy{0, -1, 0, 1, -1, 1, -1, 0, 1};
  for (std::size_t k = 0; k < kDx.size(); ++k) {
    const Voxel* v = map_.find(key_at(ix + kDx[k], iy + kDy[k]));
    if (v != nullptr && f(*v)) return true;
  }
  return false;
}

inline bool ScanRegistration::structure(const Voxel& v) const {
  return v.scans >= config_.explained_min_scans &&
         v.last_stamp_s - v.first_stamp_s >= (v.in_free_space ? config_.explained_min_span_in_free_s
                                                              : config_.explained_min_span_s);
}

bool ScanRegistration::explained(std::size_t b) const {
  if (b >= world_points_.size()) return false;
  const Eigen::Vector2d& p = world_points_[b];
  if (!std::isfinite(p.x())) return false;
  const auto ix = floor_index(p.x() / config_.voxel_size_m);
  const auto iy = floor_index(p.y() / config_.voxel_size_m);
  // The points around it that can explain it, found once for consecutive beams in the same voxel
  // (until the next registration or add()).
  if (!explaining_valid_ || ix != explaining_ix_ || iy != explaining_iy_) {
    explaining_.clear();
    any_voxel_around(ix, iy, [&](const Voxel& v) {
      // Structure explains only while it is still seen: someone who stood there and left
      // explains no one who comes by later.
      if (!structure(v) || last_stamp_s_ - v.last_stamp_s > config_.explained_max_age_s) {
        return false;
      }
      const double min_age =
          v.in_free_space ? config_.explained_min_span_in_free_s : config_.explained_min_span_s;
      for (std::uint8_t i = 0; i < v.count; ++i) {
        if (last_stamp_s_ - v.stamps_s[i] >= min_age)
          explaining_.push_back(v.points[i].cast<double>());
      }
      return false;  // Every voxel around.
    });
    explaining_valid_ = true;
    explaining_ix_ = ix;
    explaining_iy_ = iy;
  }
  const double limit2 = config_.explained_distance_m * config_.explained_distance_m;
  for (const Eigen::Vector2d& q : explaining_) {
    if ((q - p).squaredNorm() <= limit2) return true;
  }
  return false;
}

bool ScanRegistration::seen_before(std::size_t b, double before_s) const {
  if (b >= world_points_.size()) return false;
  const Eigen::Vector2d& p = world_points_[b];
  if (!std::isfinite(p.x())) return false;
  const auto ix = floor_index(p.x() / config_.voxel_size_m);
  const auto iy = floor_index(p.y() / config_.voxel_size_m);
  const double limit2 = config_.explained_distance_m * config_.explained_distance_m;
  return any_voxel_around(ix, iy, [&](const Voxel& v) {
    for (std::uint8_t i = 0; i < v.count; ++i) {
      if (v.stamps_s[i] < before_s && (v.points[i].cast<double>() - p).squaredNorm() <= limit2) {
        return true;
      }
    }
    return false;
  });
}

namespace {

// The normal (unit, either sign) of the line through @p count points given their sum and the sum
// of their outer products, when they lie along a line (the smaller spread under a tenth of the
// larger, as variances), not in a blob; zero otherwise. The eigenvalues of the symmetric 2x2
// covariance in closed form; the line's direction is the eigenvector of the larger one.
Eigen::Vector2d line_normal(Eigen::Vector2d sum, const Eigen::Matrix2d& sum_outer, int count) {
  sum /= count;
  const Eigen::Matrix2d cov = sum_outer / count - sum * sum.transpose();
  const double a = cov(0, 0), off = cov(0, 1), d = cov(1, 1);
  const double half_sum = 0.5 * (a + d);
  const double spread = std::sqrt(0.25 * (a - d) * (a - d) + off * off);
  const double large = half_sum + spread, small = half_sum - spread;
  if (!(small < 0.1 * large)) return Eigen::Vector2d::Zero();
  const double direction = 0.5 * std::atan2(2.0 * off, a - d);
  return {-std::sin(direction), std::cos(direction)};
}

}  // namespace

// Beam points in the sensor frame at the scan's stamp: each beam moved back by the sensor's
// motion between the stamp and its own time (time_increment); the sample for the registration
// thinned to scan_spacing_m. Returns whether the beams were de-skewed.
bool ScanRegistration::thin_and_deskew(const LaserScan& scan, const Pose2& motion_per_s,
                                       bool deskew_wanted) {
  const std::size_t n = scan.size();
  const std::vector<Eigen::Vector2d>& unit = directions_.of(scan);
  local_points_.assign(n, Eigen::Vector2d(kNaN, kNaN));
  sample_.clear();
  const double ti = scan.time_increment_s;
  const bool deskew = deskew_wanted && config_.deskew && std::isfinite(ti) && ti > 0.0 &&
                      ti * static_cast<double>(n) <= 1.0;
  // The motion from the stamp to beam b's time is b steps of one beam's: its rotation by
  // recurrence (one sine and cosine per scan), its translation to first order in time.
  const double step_yaw = motion_per_s.yaw_rad * ti;
  deskew_turn_per_beam_rad_ = deskew ? step_yaw : 0.0;
  SteppedRotation turn(step_yaw);
  for (std::size_t b = 0; b < n; ++b) {
    if (b > 0 && deskew) turn.advance();
    if (!scan.is_valid(b)) continue;
    const double r = scan.ranges_m[b];
    Eigen::Vector2d p = r * unit[b];
    if (deskew) {
      const double t = ti * static_cast<double>(b);
      p = turn.rotate(p) + t * Eigen::Vector2d(motion_per_s.x_m, motion_per_s.y_m);
    }
    local_points_[b] = p;
  }
  const double spacing2 = config_.scan_spacing_m * config_.scan_spacing_m;
  const double max_r2 = config_.max_range_m * config_.max_range_m;
  Eigen::Vector2d last(kNaN, kNaN);
  for (std::size_t b = 0; b < n; ++b) {
    const Eigen::Vector2d& p = local_points_[b];
    if (!std::isfinite(p.x()) || p.squaredNorm() > max_r2) continue;
    if (std::isfinite(last.x()) && (p - last).squaredNorm() < spacing2) continue;
    sample_.push_back(static_cast<std::int32_t>(b));
    last = p;
  }
  return deskew;
}

// The normal of beam b's surface in the sensor frame: the direction of least spread of the
// neighbouring beams' points on the same surface (within 0.3 m, up to 4 beams either side), when
// there are at least 3 of them and they lie along a line, not in a blob; zero otherwise. Asked
// only for the points that enter the map.
Eigen::Vector2d ScanRegistration::normal_at(std::size_t b) const {
  const std::size_t n = local_points_.size();
  const Eigen::Vector2d& p = local_points_[b];
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  int count = 0;
  const std::size_t lo = b >= 4 ? b - 4 : 0, hi = std::min(n - 1, b + 4);
  for (std::size_t j = lo; j <= hi; ++j) {
    const Eigen::Vector2d& q = local_points_[j];
    if (!std::isfinite(q.x()) || (q - p).squaredNorm() > 0.09) continue;
    mean += q;
    cov += q * q.transpose();
    ++count;
  }
  if (count < 3) return Eigen::Vector2d::Zero();
  Eigen::Vector2d normal = line_normal(mean, cov, count);
  if (normal.dot(p) > 0.0) normal = -normal;  // Facing the sensor.
  return normal;
}

// The normal of a map point that has none from its scan (a wall seen at a grazing angle: its
// beams too far apart for a line within 0.3 m): the direction of least spread of the map's points
// within kMapNormalRadius_m of it, left there by the scans that passed, when there are at least
// kMapNormalMinPoints of them along a line; zero otherwise. Sought once per map point and kept.
Eigen::Vector2d ScanRegistration::map_normal(const Voxel& voxel, std::uint8_t slot) {
  auto& v = const_cast<Voxel&>(voxel);  // The map is ours; candidates only see it as const.
  const auto bit = static_cast<std::uint8_t>(1U << slot);
  if ((v.map_normal_sought & bit) == 0) {
    v.map_normal_sought |= bit;
    const Eigen::Vector2d m = v.points[slot].cast<double>();
    const double size = config_.voxel_size_m;
    const auto reach = static_cast<std::int64_t>(std::ceil(kMapNormalRadius_m / size));
    const auto mx = floor_index(m.x() / size);
    const auto my = floor_index(m.y() / size);
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
    int count = 0;
    for (std::int64_t x = mx - reach; x <= mx + reach; ++x) {
      for (std::int64_t y = my - reach; y <= my + reach; ++y) {
        const Voxel* near = map_.find(key_at(x, y));
        if (near == nullptr) continue;
        for (std::uint8_t j = 0; j < near->count; ++j) {
          const Eigen::Vector2d q = near->points[j].cast<double>();
          if ((q - m).squaredNorm() > kMapNormalRadius_m * kMapNormalRadius_m) continue;
          mean += q;
          cov += q * q.transpose();
          ++count;
        }
      }
    }
    if (count >= kMapNormalMinPoints) {
      const Eigen::Vector2d normal = line_normal(mean, cov, count);
      if (normal.squaredNorm() > 0.25) {
        v.normals[slot] = normal.cast<float>();
        v.map_normal_found |= bit;
      }
    }
  }
  return (v.map_normal_found & bit) != 0 ? Eigen::Vector2d(v.normals[slot].cast<double>())
                                         : Eigen::Vector2d::Zero();
}

// The cache's miss (candidate_voxel()).
const ScanRegistration::Voxel* ScanRegistration::look_up_candidate_voxel(Key key) {
  CacheSlot& slot = cache_[static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ULL) >> kCacheShift)];
  const Voxel* v = map_.find(key);
  slot = {key, v != nullptr && (!structure_only_ || structure(*v)) ? v : nullptr,
          cache_generation_};
  return slot.voxel;
}

void ScanRegistration::forget_candidate_voxels() {
  if (cache_.empty()) cache_.assign(std::size_t{1} << (64 - kCacheShift), CacheSlot{});
  if (++cache_generation_ == 0) {  // Wrapped: no slot may look current.
    std::fill(cache_.begin(), cache_.end(), CacheSlot{});
    cache_generation_ = 1;
  }
}

// Sample point i's candidates are the map points of the voxels within reach_ of its voxel at the
// seed that lie within radius_ of it there (the registration moves a point by less than that).
// Finds the nearest of them to @p q (of equals, the first in their order: voxels by x, then y,
// then slot) and the ones within kNearby_m of q, its nearby list. Most points have a candidate
// that near: only the voxels within kNearby_m of q are visited then. Otherwise (a nearest
// farther away can still be a correspondence), or when @p need_any, the point's candidates are
// listed once (candidates_) and walked whole from then on. Returns whether it has any candidate
// (known only with @p need_any or when one was found). The radius is the threshold plus the
// largest correction a registration may make (max_correction_m): twice the threshold alone lost
// matches the registration needed (a simulated warehouse seed kept 0.990 of its walls instead of
// 0.999).
bool ScanRegistration::nearest_candidate(std::size_t i, const Eigen::Vector2d& q, double threshold,
                                         bool need_any, double& best, Reference& found) {
  const Eigen::Vector2d& at_seed = seed_points_[i];
  const double size = config_.voxel_size_m;
  const auto sx = floor_index(at_seed.x() / size);
  const auto sy = floor_index(at_seed.y() / size);
  const double radius2 = radius_ * radius_;
  Nearby& nearby = nearby_[i];
  const auto take = [&](const Eigen::Vector2d& point, const Reference& r) {
    const double d2 = (point - q).squaredNorm();
    if (d2 < best) {  // Visited in their order: the first of equals stays.
      best = d2;
      found = r;
    }
    if (d2 <= kNearby_m * kNearby_m) {
      if (nearby.count <= kNearbyMax) {
        nearby.near[static_cast<std::size_t>(nearby.count)] = r;
        nearby.near_points[static_cast<std::size_t>(nearby.count)] = point.cast<float>();
      }
      ++nearby.count;
    }
  };
  const auto walk_list = [&]() {
    nearby.origin = q;
    nearby.count = 0;
    for (std::int32_t k = listed_[i].begin; k < listed_[i].end; ++k) {
      const Candidate& c = candidates_[static_cast<std::size_t>(k)];
      take(c.point.cast<double>(), c.reference);
    }
    if (nearby.count > kNearbyMax) nearby.count = -1;
    return listed_[i].end > listed_[i].begin;
  };
  if (listed_[i].begin >= 0) return walk_list();
  // The voxels within kNearby_m of q along each axis (a stored point may lie a float's rounding
  // outside its voxel: a margin), within the seed's reach.
  constexpr double kMargin_m = 1e-4;
  const auto cell = [&](double v) { return floor_index(v / size); };
  const std::int64_t near_x0 = std::max(sx - reach_, cell(q.x() - kNearby_m - kMargin_m));
  const std::int64_t near_x1 = std::min(sx + reach_, cell(q.x() + kNearby_m + kMargin_m));
  const std::int64_t near_y0 = std::max(sy - reach_, cell(q.y() - kNearby_m - kMargin_m));
  const std::int64_t near_y1 = std::min(sy + reach_, cell(q.y() + kNearby_m + kMargin_m));
  // Calls @p f(point, reference) for each candidate in the voxels [x0, x1] x [y0, y1].
  const auto each_candidate = [&](std::int64_t x0, std::int64_t x1, std::int64_t y0,
                                  std::int64_t y1, const auto& f) {
    for (std::int64_t x = x0; x <= x1; ++x) {
      for (std::int64_t y = y0; y <= y1; ++y) {
        const Voxel* v = candidate_voxel(x, y);
        if (v == nullptr) continue;
        for (std::uint8_t j = 0; j < v->count; ++j) {
          const Eigen::Vector2d point = v->points[j].cast<double>();
          if ((point - at_seed).squaredNorm() <= radius2) f(point, Reference{v, j});
        }
      }
    }
  };
  if (!exhaustive_) {
    nearby.origin = q;
    nearby.count = 0;
    bool any = false;
    each_candidate(near_x0, near_x1, near_y0, near_y1,
                   [&](const Eigen::Vector2d& point, const Reference& r) {
                     any = true;
                     take(point, r);
                   });
    if (best <= kNearby_m * kNearby_m || (threshold <= kNearby_m && !need_any)) {
      if (nearby.count > kNearbyMax) nearby.count = -1;
      return any;
    }
  }
  // All of its candidates, listed in their order.
  listed_[i].begin = static_cast<std::int32_t>(candidates_.size());
  each_candidate(sx - reach_, sx + reach_, sy - reach_, sy + reach_,
                 [&](const Eigen::Vector2d& point, const Reference& r) {
                   candidates_.push_back(Candidate{point.cast<float>(), r});
                 });
  listed_[i].end = static_cast<std::int32_t>(candidates_.size());
  best = kInfinity;
  found = Reference{nullptr, 0};
  return walk_list();
}

// Aligns the thinned scan with the map from @p seed (@p delta: the seed's motion since the
// previous scan; @p noise: whose noise the seed has; report.seeded_by_odometry: whether there is
// odometry to fall back on). Fills the report's alignment fields and returns the registered
// pose, or @p seed with report.fallback set.
Pose2 ScanRegistration::align(const Pose2& seed, const Pose2& delta, double threshold,
                              SeedNoise noise, RegistrationReport& report, const Pose2* prior_at) {
  const Pose2& prior_pose = prior_at != nullptr ? *prior_at : seed;
  Pose2 pose = seed;
  ++alignments_;
  // Candidates: the points of the voxels around each sample point at the seed (see
  // nearest_candidate()). A young map (the first scans, or a scene that has just changed) has
  // no structure yet: when fewer than min_points sample points have a candidate in structure,
  // every voxel is a candidate (the first iteration is done again).
  reach_ = static_cast<int>(std::ceil(threshold / config_.voxel_size_m));
  radius_ = threshold + config_.max_correction_m;
  const auto start_candidates = [&](bool structure_only) {
    structure_only_ = structure_only;
    forget_candidate_voxels();
    candidates_.clear();
    listed_.assign(sample_.size(), Listed{});
  };
  start_candidates(true);
  seed_points_.resize(sample_.size());
  {
    const PoseTransform to_seed(seed);
    for (std::size_t i = 0; i < sample_.size(); ++i) {
      seed_points_[i] = to_seed(local_points_[static_cast<std::size_t>(sample_[i])]);
    }
  }
  // Laser-only: what is known to move is left out (leave_out_moving).
  left_out_.assign(sample_.size(), 0);
  std::size_t used = sample_.size();
  if (leave_out_ != nullptr && *leave_out_) {
    for (std::size_t i = 0; i < sample_.size(); ++i) {
      if ((*leave_out_)(seed_points_[i])) {
        left_out_[i] = 1;
        --used;
      }
    }
  }
  report.left_out = static_cast<std::int32_t>(sample_.size() - used);
  nearby_.resize(sample_.size());  // Each filled at the first iteration.
  const double kappa = threshold / 3.0;
  const double threshold2 = threshold * threshold;
  Eigen::Matrix3d h_data = Eigen::Matrix3d::Zero();
  std::int32_t inliers = 0;
  double sum_e2 = 0.0;
  for (int iteration = 0; iteration < config_.max_iterations; ++iteration) {
    Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    inliers = 0;
    sum_e2 = 0.0;
    const Eigen::Vector2d c = pose.translation();
    const PoseTransform to_fixed(pose);
    std::int32_t covered = 0;
    for (std::size_t i = 0; i < sample_.size(); ++i) {
      if (left_out_[i] != 0) continue;
      const Eigen::Vector2d q = iteration == 0
                                    ? seed_points_[i]
                                    : to_fixed(local_points_[static_cast<std::size_t>(sample_[i])]);
      // The nearest candidate (the first of equals), used when within the threshold: from
      // the second iteration on, among the point's nearby candidates when they hold it;
      // among all of them otherwise, finding the nearby ones around where the point is now.
      Nearby& nearby = nearby_[i];
      double best = kInfinity;
      Reference found{nullptr, 0};
      Eigen::Vector2d found_point;
      const double moved = iteration > 0 ? (q - nearby.at).norm() : 0.0;
      if (iteration > 0 && listed_[i].begin >= 0 && !exhaustive_ &&
          nearby.nearest_m - moved >= threshold + kDistanceMargin_m) {
        // Its nearest candidate was this far from where it was (all its candidates are listed:
        // the distance is exact), and it has not moved enough to come within the threshold.
        continue;
      }
      if (iteration > 0 && nearby.count >= 0 && !exhaustive_ &&
          nearby.nearest_m + moved + (q - nearby.origin).norm() + kDistanceMargin_m <= kNearby_m) {
        // The list is in the candidates' order: the first of equals is the first found.
        std::int32_t nearest = -1;
        for (std::int32_t k = 0; k < nearby.count; ++k) {
          const double d2 =
              (nearby.near_points[static_cast<std::size_t>(k)].cast<double>() - q).squaredNorm();
          if (d2 < best) {
            best = d2;
            nearest = k;
          }
        }
        if (nearest >= 0) {
          found = nearby.near[static_cast<std::size_t>(nearest)];
          found_point = nearby.near_points[static_cast<std::size_t>(nearest)].cast<double>();
        }
      } else {
        if (nearest_candidate(i, q, threshold, iteration == 0 && structure_only_, best, found)) {
          ++covered;
        }
        if (found.voxel != nullptr) found_point = found.voxel->points[found.slot].cast<double>();
      }
      nearby.at = q;
      nearby.nearest_m = std::sqrt(best);
      if (!(best < threshold2)) continue;
      ++inliers;
      const Eigen::Vector2d diff = q - found_point;
      Eigen::Vector2d normal = found.voxel->normals[found.slot].cast<double>();
      if (map_normals_) {
        // With odometry, a map point without a normal from its scan gets one from the map:
        // matched point to point, far walls seen at grazing angles (70 % of the matches on the
        // simulated office loop) pulled the scan along the corridors, 1.6 cm over 1 s; 1.2 cm
        // with these. Laser-only they are kept point to point: there they are most of what the
        // scan knows along a corridor (negative_2's rear laser removed 0.61 % of its beams and
        // person_following_outdoor_1's person 0.49 with map normals, against 0.10 % and 0.77).
        if (normal.squaredNorm() < 0.25) normal = map_normal(*found.voxel, found.slot);
      } else if ((found.voxel->map_normal_found & (1U << found.slot)) != 0) {
        normal = Eigen::Vector2d::Zero();
      }
      if (normal.squaredNorm() < 0.25) {  // No normal: point to point along the difference.
        if (best < 1e-18) continue;
        normal = diff / std::sqrt(best);
      }
      const double e = normal.dot(diff);
      const Eigen::Vector3d j(normal.x(), normal.y(), normal.dot(perp(q - c)));
      const double w = kappa * kappa / ((kappa + e * e) * (kappa + e * e));
      h.noalias() += w * j * j.transpose();
      g.noalias() += w * e * j;
      sum_e2 += e * e;
    }
    if (iteration == 0 && structure_only_ && covered < config_.min_points) {
      // Too little structure: every voxel is a candidate; the first iteration again.
      start_candidates(false);
      --iteration;
      continue;
    }
    h_data = h;
    if (inliers < config_.min_points) break;
    // The residuals count with the range noise (range_noise_m); the seed is a measurement
    // too: the odometry's motion within its own noise (odometry_noise_m / _rad per scan),
    // a constant-velocity guess within far wider bounds. It decides the directions the scan
    // does not constrain (a corridor's length) and holds against a few points that fit.
    h /= config_.range_noise_m * config_.range_noise_m;
    g /= config_.range_noise_m * config_.range_noise_m;
    // The odometry's noise grows with the motion (5 % of it, and 0.01 rad per metre).
    const double moved = delta.translation().norm(), turned = std::abs(delta.yaw_rad);
    const bool odometry = noise == SeedNoise::kOdometry;
    const double sigma_t =
        odometry ? config_.odometry_noise_m + 0.05 * moved : config_.constant_velocity_noise_m;
    const double sigma_r = odometry ? config_.odometry_noise_rad + 0.05 * turned + 0.01 * moved
                                    : config_.constant_velocity_noise_rad;
    const double prior_t = 1.0 / (sigma_t * sigma_t);
    const double prior_r = 1.0 / (sigma_r * sigma_r);
    const Eigen::Vector3d off(pose.x_m - prior_pose.x_m, pose.y_m - prior_pose.y_m,
                              wrap_angle(pose.yaw_rad - prior_pose.yaw_rad));
    if (sideways_sigma_m_ > 0.0 && !odometry) {
      // Laser-only: along the learnt direction the guess's noise, sideways (beyond the turn's
      // share, which the guess holds) sideways_sigma_m_; both turned into the fixed frame.
      const Eigen::Vector2d side = PoseTransform(prior_pose).rotate(heading_.sideways());
      const Eigen::Matrix2d prior =
          prior_t * (Eigen::Matrix2d::Identity() - side * side.transpose()) +
          side * side.transpose() / (sideways_sigma_m_ * sideways_sigma_m_);
      h.topLeftCorner<2, 2>() += prior;
      g.head<2>() += prior * off.head<2>();
      report.held_sideways = true;
    } else {
      h(0, 0) += prior_t;
      h(1, 1) += prior_t;
      g.head<2>() += prior_t * off.head<2>();
    }
    h(2, 2) += prior_r;
    g(2) += prior_r * off.z();
    const Eigen::Vector3d step = -h.ldlt().solve(g);
    if (!step.allFinite()) break;
    pose.x_m += step.x();
    pose.y_m += step.y();
    pose.yaw_rad = wrap_angle(pose.yaw_rad + step.z());
    report.iterations = iteration + 1;
    ++total_iterations_;
    // Converged: a step of 1 mm and 0.1 mrad is far below the returns' noise. (1e-4 and 1e-5
    // ran to max_iterations on most scans, the Geman-McClure weights and the correspondences
    // trading places at that scale.)
    if (step.head<2>().norm() < 1e-3 && std::abs(step.z()) < 1e-4) break;
  }
  // With odometry to fall back on, a scan must match more structure to be trusted over it.
  const bool enough = inliers >= (report.seeded_by_odometry ? config_.min_points_with_odometry
                                                            : config_.min_points);
  report.inlier_share =
      static_cast<double>(inliers) / static_cast<double>(std::max<std::size_t>(1, used));
  report.residual_m = inliers > 0 ? std::sqrt(sum_e2 / inliers) : 0.0;
  // Degeneracy: the translation information's eigenvalues (closed form, 2x2 symmetric).
  const double a = h_data(0, 0), b = h_data(0, 1), d = h_data(1, 1);
  const double mean = 0.5 * (a + d);
  const double spread = std::sqrt(0.25 * (a - d) * (a - d) + b * b);
  report.degeneracy = mean + spread > 0.0 ? std::max(0.0, mean - spread) / (mean + spread) : 0.0;
  report.correction = seed.inverse() * pose;
  if (!enough || report.inlier_share < config_.min_inlier_share ||
      report.correction.translation().norm() > config_.max_correction_m ||
      std::abs(report.correction.yaw_rad) > config_.max_correction_rad ||
      !std::isfinite(pose.x_m + pose.y_m + pose.yaw_rad)) {
    report.fallback = true;
    report.correction = Pose2{};
    return seed;
  }
  report.registered = true;
  report.degenerate = report.degeneracy < config_.degeneracy_ratio;
  return pose;
}

Pose2 ScanRegistration::register_scan(const LaserScan& scan,
                                      const std::optional<Pose2>& odometry_pose,
                                      RegistrationReport& report,
                                      const std::function<bool(const Eigen::Vector2d&)>& moving) {
  report = RegistrationReport{};
  leave_out_ = !odometry_pose && config_.leave_out_moving ? &moving : nullptr;
  alignments_ = total_iterations_ = 0;
  ++scan_count_;
  explaining_valid_ = false;
  const double dt = have_previous_ ? scan.stamp_s - previous_stamp_s_ : 0.0;
  sideways_sigma_m_ =
      !odometry_pose && config_.lateral_noise_mps > 0.0 && heading_.clear && dt > 0.0 && sparse_
          ? config_.lateral_noise_mps * dt
          : 0.0;
  // The seed: the odometry's motion since the previous scan, else constant velocity.
  Pose2 seed, delta;
  if (!have_previous_) {
    seed = odometry_pose.value_or(Pose2{});
  } else if (odometry_pose && previous_odometry_) {
    delta = previous_odometry_->inverse() * *odometry_pose;
    seed = previous_pose_ * delta;
    report.seeded_by_odometry = true;
  } else {
    delta = scaled(velocity_per_s_, dt);
    seed = previous_pose_ * delta;
  }
  const Pose2 motion_per_s =
      dt > 0.0 ? Pose2{delta.x_m / dt, delta.y_m / dt, delta.yaw_rad / dt} : velocity_per_s_;
  // By the odometry's motion. Laser-only, by the guess's turn alone: de-skewing by the guess's
  // translation feeds its error back into the registration (a guess too slow shortens the scan
  // along the motion, which then registers slower still): laser-only ran away along a corridor
  // with it. A turn is what the scan itself measures well (see kLaserOnlyRebend_m).
  const bool laser_only_turn =
      !odometry_pose && config_.deskew_laser_only_turn && have_previous_ && dt > 0.0;
  thin_and_deskew(scan, laser_only_turn ? Pose2{0.0, 0.0, motion_per_s.yaw_rad} : motion_per_s,
                  report.seeded_by_odometry || laser_only_turn);
  map_normals_ = odometry_pose.has_value();  // Also for the constant-velocity guess, tried below.
  report.points = static_cast<std::int32_t>(sample_.size());

  Pose2 pose = seed;
  const double threshold =
      model_error_count_ > 0
          ? std::clamp(3.0 * std::sqrt(model_error_sum_ / static_cast<double>(model_error_count_)),
                       config_.min_threshold_m, config_.max_threshold_m)
          : config_.initial_threshold_m;
  report.threshold_m = threshold;
  if (have_previous_ && !map_.empty() && config_.align) {
    if (report.points < config_.min_points) {
      report.fallback = true;
    } else {
      const SeedNoise noise = report.seeded_by_odometry ? SeedNoise::kOdometry : SeedNoise::kGuess;
      pose = align(seed, delta, threshold, noise, report);
      Pose2 deskewed_per_s = motion_per_s;  // The motion the scan is de-skewed with.
      Pose2 used_seed = seed;
      // A wheel that slips turns the odometry by degrees within a scan, farther than the
      // registration's reach from the seed: the scan then registers poorly or not at all, and
      // the map goes on from a pose rotated by the slip. When the odometry's motion and the
      // constant-velocity guess (the registered motion of the scans before) part by more than a
      // robot's motors can change within a scan, the guess is tried too, on the scan de-skewed
      // by the guess (the odometry's motion is what is in doubt), and the alignment that matched
      // more of the scan is kept.
      if (report.seeded_by_odometry && velocity_per_s_initialised_ && dt > 0.0) {
        const Pose2 guess_delta = scaled(velocity_per_s_, dt);
        const Pose2 apart = delta.inverse() * guess_delta;
        if (std::abs(apart.yaw_rad) > kSeedsApart_rad ||
            apart.translation().norm() > kSeedsApart_m) {
          RegistrationReport guessed = report;
          guessed.seeded_by_odometry = false;
          guessed.registered = guessed.fallback = guessed.degenerate = false;
          const bool deskewed = thin_and_deskew(scan, velocity_per_s_, true);
          const Pose2 from_guess = align(previous_pose_ * guess_delta, guess_delta, threshold,
                                         SeedNoise::kGuess, guessed);
          if (guessed.registered &&
              guessed.inlier_share * guessed.points >= config_.min_points_with_odometry &&
              (!report.registered || guessed.inlier_share > report.inlier_share + kBetterShare)) {
            guessed.odometry_overruled = true;
            report = guessed;
            pose = from_guess;
            deskewed_per_s = velocity_per_s_;
            used_seed = previous_pose_ * guess_delta;
          } else if (deskewed) {
            thin_and_deskew(scan, motion_per_s, true);
          }
        }
      }
      // De-skews the scan by its registered turn and aligns it again from the registered pose
      // while that turn bends the sweep by more than @p rebend_m at kThresholdRange_m against the
      // turn it was de-skewed by (@p bent_by, whose translation is kept), up to @p times.
      // The prior is at @p prior_at, or at each alignment's start when nullptr (constant-velocity
      // noise either way); the correction is counted from @p from_seed.
      const auto bend_back = [&](int times, double rebend_m, Pose2 bent_by, const Pose2& from_seed,
                                 const Pose2* prior_at) {
        const double sweep_s = scan.time_increment_s * static_cast<double>(scan.size());
        for (int again = 0; again < times && report.registered; ++again) {
          const Pose2 moved = previous_pose_.inverse() * pose;
          const double turn_per_s = moved.yaw_rad / dt;
          const double bend_m =
              std::abs(turn_per_s - bent_by.yaw_rad) * sweep_s * kThresholdRange_m;
          if (!(bend_m > rebend_m)) break;
          const Pose2 turned{bent_by.x_m, bent_by.y_m, turn_per_s};
          if (!thin_and_deskew(scan, turned, true)) break;
          RegistrationReport realigned = report;
          realigned.registered = realigned.fallback = realigned.degenerate = false;
          const Pose2 p =
              prior_at != nullptr
                  ? align(pose, delta, threshold, SeedNoise::kGuess, realigned, prior_at)
                  : align(pose, moved, threshold, SeedNoise::kGuess, realigned);
          if (!realigned.registered) {
            thin_and_deskew(scan, bent_by, true);
            break;
          }
          realigned.correction = from_seed.inverse() * p;
          ++realigned.realignments;
          report = realigned;
          pose = p;
          bent_by = turned;
        }
      };
      // The scan was de-skewed by a turn that the registration then found wrong (a slip starts or
      // ends within the odometry's motion since the previous scan): when the difference bends
      // the sweep by more than kRebend_m, it is bent back from the registered pose, which the
      // odometry no longer holds; up to kMaxRealignments times, as each alignment of a bent scan
      // is itself a little off.
      if (odometry_pose && dt > 0.0) {
        bend_back(kMaxRealignments, kRebend_m, deskewed_per_s, used_seed, nullptr);
      }
      // Laser-only, the scan was de-skewed by the guess's turn: it is bent back by the registered
      // turn beyond kLaserOnlyRebend_m, up to kLaserOnlyRealignments times. The guess stays the
      // prior (each alignment from an earlier one's pose with the prior there walked along a
      // corridor, where the scan says little).
      if (laser_only_turn) {
        bend_back(kLaserOnlyRealignments, kLaserOnlyRebend_m, Pose2{0.0, 0.0, motion_per_s.yaw_rad},
                  seed, &seed);
      }
      if (report.registered &&
          (delta.translation().norm() > kMinMotionForThreshold_m ||
           std::abs(delta.yaw_rad) > kMinMotionForThreshold_m / kThresholdRange_m)) {
        const double error =
            report.correction.translation().norm() +
            2.0 * kThresholdRange_m * std::sin(0.5 * std::abs(report.correction.yaw_rad));
        model_error_sum_ += error * error;
        ++model_error_count_;
      }
    }
  }
  if (have_previous_ && dt > 0.0) {
    const Pose2 moved = previous_pose_.inverse() * pose;
    // Smoothed: one scan's registered motion is noisy (a few cm in a fraction of a second), and a
    // constant-velocity guess that follows the noise overshoots, and the next correction with it
    // (it diverged along a corridor at 1 m/s).
    const double a = velocity_per_s_initialised_ ? config_.velocity_smoothing : 1.0;
    velocity_per_s_ = {a * moved.x_m / dt + (1.0 - a) * velocity_per_s_.x_m,
                       a * moved.y_m / dt + (1.0 - a) * velocity_per_s_.y_m,
                       a * moved.yaw_rad / dt + (1.0 - a) * velocity_per_s_.yaw_rad};
    velocity_per_s_initialised_ = true;
    // Within what the robot can do (SpeedLimits).
    const double speed = velocity_per_s_.translation().norm();
    const bool too_fast = speed > limits_.speed_mps;
    report.guess_limited = too_fast || std::abs(velocity_per_s_.yaw_rad) > limits_.turn_rate_radps;
    if (too_fast) {
      velocity_per_s_.x_m *= limits_.speed_mps / speed;
      velocity_per_s_.y_m *= limits_.speed_mps / speed;
    }
    velocity_per_s_.yaw_rad =
        std::clamp(velocity_per_s_.yaw_rad, -limits_.turn_rate_radps, limits_.turn_rate_radps);
    if (!odometry_pose) {
      if (report.fallback && config_.fallback_turn_decay_s > 0.0) {
        velocity_per_s_.yaw_rad *= std::exp(-dt / config_.fallback_turn_decay_s);
      }
      // Learnt only from scans that matched as many points as a scan seeded by odometry must:
      // with fewer, the registered motion is as likely the sparse scene's error (a turn about a
      // point ahead, sliding sideways) as the robot's.
      const double matched = report.inlier_share * (report.points - report.left_out);
      const bool rich = report.registered && matched >= config_.min_points_with_odometry;
      if (rich && !report.degenerate) {
        heading_.learn(Pose2{moved.x_m / dt, moved.y_m / dt, moved.yaw_rad / dt});
      }
      sparse_ = !rich;
      if (config_.lateral_noise_mps > 0.0 && heading_.clear && sparse_) hold_guess_sideways();
    }
  }
  leave_out_ = nullptr;  // @p moving lives for this call only.
  report.alignments = alignments_;
  report.total_iterations = total_iterations_;
  previous_pose_ = pose;
  previous_stamp_s_ = scan.stamp_s;
  previous_odometry_ = odometry_pose;
  have_previous_ = true;
  last_pose_ = pose;
  last_stamp_s_ = scan.stamp_s;
  world_points_.resize(local_points_.size());
  const PoseTransform to_fixed(pose);
  for (std::size_t b = 0; b < local_points_.size(); ++b) {
    world_points_[b] = std::isfinite(local_points_[b].x()) ? to_fixed(local_points_[b])
                                                           : Eigen::Vector2d(kNaN, kNaN);
  }
  return pose;
}

void ScanRegistration::add(const std::vector<char>& keep,
                           const std::function<bool(const Eigen::Vector2d&)>& in_free_space,
                           const std::function<bool(const Eigen::Vector2d&)>& long_free) {
  explaining_valid_ = false;
  const double max_r2 = config_.max_range_m * config_.max_range_m;
  const PoseTransform to_fixed(last_pose_);
  // Consecutive beams mostly fall in the same voxel: it is looked up once for them (the pointer
  // is used only until the next lookup, which may insert and move the voxels).
  Voxel* voxel = nullptr;
  Key last_key = 0;
  for (std::size_t b = 0; b < world_points_.size() && b < keep.size(); ++b) {
    if (keep[b] == 0 || !std::isfinite(world_points_[b].x())) continue;
    if (local_points_[b].squaredNorm() > max_r2) continue;
    const Key key = key_of(world_points_[b]);
    if (voxel == nullptr || key != last_key) {
      voxel = &map_[key];
      last_key = key;
    }
    if (voxel->last_scan != scan_count_) {
      // Hit again after a time unseen where the scanner has long seen through: what stood there
      // left. Its points would explain what comes by next along the same line (a cart driving to
      // and fro explained its side by its earlier passes: the simulated warehouse's cart kept most
      // of its beams).
      if (voxel->scans > 0 && last_stamp_s_ - voxel->last_stamp_s > config_.explained_max_age_s &&
          long_free && long_free(world_points_[b])) {
        *voxel = Voxel{};
        ++voxels_restarted_;
      }
      if (voxel->scans == 0) {
        voxel->first_stamp_s = last_stamp_s_;
        voxel->in_free_space = in_free_space && in_free_space(world_points_[b]);
      }
      ++voxel->scans;
      voxel->last_scan = scan_count_;
      voxel->last_stamp_s = last_stamp_s_;
    }
    if (voxel->count < config_.max_points_per_voxel) {
      voxel->points[voxel->count] = world_points_[b].cast<float>();
      voxel->stamps_s[voxel->count] = last_stamp_s_;
      voxel->normals[voxel->count] = to_fixed.rotate(normal_at(b)).cast<float>();
      ++voxel->count;
    }
  }
  // Every tenth scan: forget what lies beyond the local map and the trails of passers-by.
  if (scan_count_ % 10 != 0) return;
  const double radius2 = config_.local_map_radius_m * config_.local_map_radius_m;
  const Eigen::Vector2d center = last_pose_.translation();
  map_.erase_if([&](Key /*key*/, const Voxel& v) {
    const bool far = (v.points[0].cast<double>() - center).squaredNorm() > radius2;
    const bool transient = v.scans < config_.explained_min_scans &&
                           last_stamp_s_ - v.last_stamp_s > kTransientMemory_s;
    return far || transient;
  });
}

}  // namespace dispel
