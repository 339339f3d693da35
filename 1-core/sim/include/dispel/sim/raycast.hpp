#pragma once
/// @file
/// Ray casting of a 2D LiDAR in a world of line segments and circles: the geometry under the
/// simulator, the benchmarks and the tests' scenes.

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <vector>

#include "dispel/core/laser_scan.hpp"
#include "dispel/core/pose2.hpp"

namespace dispel::sim {

/// A wall or any flat face, world frame, metres.
struct Segment {
  Eigen::Vector2d a = Eigen::Vector2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  /// Glass or a polished panel: only a beam that meets it within this angle (radians) of its
  /// normal returns from it, as a reflection straight back; every other beam passes through, as
  /// if it were not there. Infinity (the default): every beam returns.
  double returns_within_rad = std::numeric_limits<double>::infinity();
};

/// A pillar, a leg, a barrel: world frame, metres.
struct Circle {
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  double radius_m = 0.0;
  /// Beams that reach it from farther than this pass over it (a chair seat or a box just below a
  /// scan plane tilted up: only the near part of the plane is low enough to hit it).
  double seen_within_m = std::numeric_limits<double>::infinity();
  /// The share of the beams reaching it that return from it (foliage, a wire basket, a chair's
  /// open back): each other beam passes through, as if it were not there. Which beams pass is
  /// drawn from World::flicker_seed and the beam's direction, so it changes from scan to scan.
  double return_share = 1.0;
};

/// Everything a beam can hit. Shape ids: segments are 0..S-1, circles S..S+C-1.
struct World {
  std::vector<Segment> segments;
  std::vector<Circle> circles;
  /// Draws which beams pass through circles whose return_share is below 1 (change it per scan).
  std::uint64_t flicker_seed = 0;
};

/// The beams of a scanner.
struct ScanGeometry {
  double angle_min_rad = 0.0;
  double angle_increment_rad = 0.0;
  std::int32_t beam_count = 0;
  float range_min_m = 0.0F;
  float range_max_m = 0.0F;
};

/// Label for a beam that hit nothing within range.
inline constexpr std::int32_t kNoHit = -1;

/// Casts every beam of @p geometry from @p sensor_pose (laser frame in the world) and returns the
/// scan: the range to the nearest surface, or +infinity when nothing lies within range_max_m
/// (REP 117). When @p hit_shape is given it receives, per beam, the id of the shape hit or kNoHit.
LaserScan raycast(const World& world, const Pose2& sensor_pose, const ScanGeometry& geometry,
                  std::vector<std::int32_t>* hit_shape = nullptr);

/// Distance along the unit ray (origin, direction) to @p shape, or +infinity if missed.
double ray_distance(const Segment& shape, const Eigen::Vector2d& origin,
                    const Eigen::Vector2d& direction);
double ray_distance(const Circle& shape, const Eigen::Vector2d& origin,
                    const Eigen::Vector2d& direction);

/// |cos| of the angle between the unit @p direction and @p shape's normal (1: square on); NaN for
/// a segment of zero length.
double incidence_cosine(const Segment& shape, const Eigen::Vector2d& direction);

/// A number in [0, 1) that depends only on @p seed, @p a and @p b (splitmix64): a draw that
/// takes nothing from a random stream, so that drawing it leaves every other draw as it was.
double unit_draw(std::uint64_t seed, std::uint64_t a, std::uint64_t b);

}  // namespace dispel::sim
