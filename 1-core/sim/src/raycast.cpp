#include "dispel/sim/raycast.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace dispel::sim {
namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}
}  // namespace

double ray_distance(const Segment& shape, const Eigen::Vector2d& origin,
                    const Eigen::Vector2d& direction) {
  // origin + t * direction = a + u * (b - a), t >= 0, u in [0, 1].
  const Eigen::Vector2d edge = shape.b - shape.a;
  const double denom = cross(direction, edge);
  if (std::abs(denom) < 1e-15) return kInf;  // Parallel: a grazing ray sees no surface.
  const Eigen::Vector2d to_a = shape.a - origin;
  const double t = cross(to_a, edge) / denom;
  const double u = cross(to_a, direction) / denom;
  if (t < 0.0 || u < 0.0 || u > 1.0) return kInf;
  return t;
}

double ray_distance(const Circle& shape, const Eigen::Vector2d& origin,
                    const Eigen::Vector2d& direction) {
  const Eigen::Vector2d to_center = shape.center - origin;
  const double along = to_center.dot(direction);
  const double miss_sq = to_center.squaredNorm() - along * along;
  const double r_sq = shape.radius_m * shape.radius_m;
  if (miss_sq > r_sq) return kInf;
  const double half_chord = std::sqrt(r_sq - miss_sq);
  const double near = along - half_chord;
  if (near >= 0.0) return near;
  const double far = along + half_chord;  // Origin inside the circle: the far side.
  return far >= 0.0 ? far : kInf;
}

double unit_draw(std::uint64_t seed, std::uint64_t a, std::uint64_t b) {
  std::uint64_t z = seed ^ (a * 0x9e3779b97f4a7c15ULL) ^ (b * 0xbf58476d1ce4e5b9ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * 0x1.0p-53;
}

namespace {

// A number in [0, 1) drawn from the seed, the circle and the beam's direction.
double flicker_draw(std::uint64_t seed, std::size_t circle, double bearing_rad) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &bearing_rad, sizeof bits);
  return unit_draw(seed, bits, circle);
}

// Whether a beam along @p direction that reaches @p segment returns from it (Segment::
// returns_within_rad): the cosine of its angle with the segment's normal at least that of the
// limit.
bool returns_at(const Segment& segment, const Eigen::Vector2d& direction) {
  if (!(segment.returns_within_rad < 0.5 * kPi)) return true;
  return incidence_cosine(segment, direction) >= std::cos(segment.returns_within_rad);
}

}  // namespace

LaserScan raycast(const World& world, const Pose2& sensor_pose, const ScanGeometry& geometry,
                  std::vector<std::int32_t>* hit_shape) {
  LaserScan scan;
  scan.angle_min_rad = geometry.angle_min_rad;
  scan.angle_increment_rad = geometry.angle_increment_rad;
  scan.range_min_m = geometry.range_min_m;
  scan.range_max_m = geometry.range_max_m;
  const auto n = static_cast<std::size_t>(geometry.beam_count > 0 ? geometry.beam_count : 0);
  scan.ranges_m.resize(n);
  if (hit_shape != nullptr) hit_shape->assign(n, kNoHit);
  const Eigen::Vector2d origin = sensor_pose.translation();
  const auto segment_count = static_cast<std::int32_t>(world.segments.size());
  for (std::size_t i = 0; i < n; ++i) {
    const double bearing = sensor_pose.yaw_rad + scan.bearing_rad(i);
    const Eigen::Vector2d direction(std::cos(bearing), std::sin(bearing));
    double best = kInf;
    std::int32_t best_id = kNoHit;
    for (std::int32_t s = 0; s < segment_count; ++s) {
      const Segment& segment = world.segments[s];
      const double t = ray_distance(segment, origin, direction);
      if (t < best && returns_at(segment, direction)) {
        best = t;
        best_id = s;
      }
    }
    for (std::size_t c = 0; c < world.circles.size(); ++c) {
      const Circle& circle = world.circles[c];
      const double t = ray_distance(circle, origin, direction);
      if (t < best && t <= circle.seen_within_m &&
          (circle.return_share >= 1.0 ||
           flicker_draw(world.flicker_seed, c, bearing) < circle.return_share)) {
        best = t;
        best_id = segment_count + static_cast<std::int32_t>(c);
      }
    }
    if (best > geometry.range_max_m) {
      best = kInf;
      best_id = kNoHit;
    }
    scan.ranges_m[i] = static_cast<float>(best);
    if (hit_shape != nullptr) (*hit_shape)[i] = best_id;
  }
  return scan;
}

double incidence_cosine(const Segment& shape, const Eigen::Vector2d& direction) {
  const Eigen::Vector2d along = shape.b - shape.a;
  const double length = along.norm();
  if (!(length > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  return std::abs(direction.x() * along.y() - direction.y() * along.x()) / length;
}

}  // namespace dispel::sim
