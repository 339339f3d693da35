#include "dispel/sim/raycast.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace dispel::sim {
namespace {

TEST(RayDistance, SegmentHitMissAndParallel) {
  const Segment s{{2.0, -1.0}, {2.0, 1.0}};
  EXPECT_NEAR(ray_distance(s, {0.0, 0.0}, {1.0, 0.0}), 2.0, 1e-12);
  EXPECT_TRUE(std::isinf(ray_distance(s, {0.0, 0.0}, {-1.0, 0.0})));
  EXPECT_TRUE(std::isinf(ray_distance(s, {0.0, 0.0}, {0.0, 1.0})));
  EXPECT_TRUE(std::isinf(ray_distance(s, {0.0, 5.0}, {1.0, 0.0})));
}

TEST(RayDistance, CircleFrontAndInside) {
  const Circle c{{3.0, 0.0}, 0.5};
  EXPECT_NEAR(ray_distance(c, {0.0, 0.0}, {1.0, 0.0}), 2.5, 1e-12);
  EXPECT_NEAR(ray_distance(c, {3.0, 0.0}, {1.0, 0.0}), 0.5, 1e-12);
  EXPECT_TRUE(std::isinf(ray_distance(c, {0.0, 0.0}, {0.0, 1.0})));
}

TEST(Raycast, NearestShapeWinsAndMissesAreInfinite) {
  World world;
  world.segments = {{{4.0, -1.0}, {4.0, 1.0}}};
  world.circles = {{{2.0, 0.0}, 0.25}};
  const ScanGeometry g{-0.1, 0.1, 3, 0.1F, 10.0F};
  std::vector<std::int32_t> hit;
  // Sensor turned by pi/2 then back: its own yaw is applied to every bearing.
  const LaserScan scan = raycast(world, Pose2{0.0, 0.0, 0.0}, g, &hit);
  ASSERT_EQ(scan.size(), 3u);
  EXPECT_EQ(hit[1], 1);  // The circle (after the one segment).
  EXPECT_NEAR(scan.ranges_m[1], 1.75F, 1e-6);
  const LaserScan away = raycast(world, Pose2{0.0, 0.0, 3.0}, g, &hit);
  for (float r : away.ranges_m) EXPECT_TRUE(std::isinf(r));
  for (std::int32_t h : hit) EXPECT_EQ(h, kNoHit);
}

TEST(Raycast, ALowThingIsHitOnlyFromNearerThanItsSeenWithin) {
  // A box below a scan plane tilted up: the beams pass over it from afar and see the wall.
  World world;
  world.segments = {{{4.0, -1.0}, {4.0, 1.0}}};
  world.circles = {{{2.0, 0.0}, 0.2, 1.5}};
  const ScanGeometry g{0.0, 0.1, 1, 0.1F, 10.0F};
  std::vector<std::int32_t> hit;
  LaserScan far = raycast(world, Pose2{0.0, 0.0, 0.0}, g, &hit);
  EXPECT_NEAR(far.ranges_m[0], 4.0F, 1e-5F);
  EXPECT_EQ(hit[0], 0);
  LaserScan near = raycast(world, Pose2{0.5, 0.0, 0.0}, g, &hit);  // 1.3 m to its face.
  EXPECT_NEAR(near.ranges_m[0], 1.3F, 1e-5F);
  EXPECT_EQ(hit[0], 1);
}

TEST(Raycast, HitsBeyondRangeMaxAreNoReturn) {
  World world;
  world.segments = {{{20.0, -1.0}, {20.0, 1.0}}};
  const LaserScan scan = raycast(world, Pose2{}, {0.0, 0.01, 1, 0.1F, 10.0F});
  EXPECT_TRUE(std::isinf(scan.ranges_m[0]));
}

}  // namespace
}  // namespace dispel::sim
