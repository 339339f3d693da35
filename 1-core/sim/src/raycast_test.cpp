#include "dispel/sim/raycast.hpp"

#include <gtest/gtest.h>

#include <algorithm>
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

TEST(Raycast, AThingThatReturnsSomeBeamsLetsTheOthersThroughDifferentlyInEachScan) {
  // A bush 1 m across at 2 m before a wall at 4 m, returning 40 % of the beams that reach it.
  World world;
  world.segments = {{{4.0, -3.0}, {4.0, 3.0}}};
  Circle bush{{2.0, 0.0}, 0.5};
  bush.return_share = 0.4;
  world.circles = {bush};
  const ScanGeometry g{-0.2, 0.001, 401, 0.1F, 10.0F};  // 0.4 rad: all of it, beams 2 mm apart.
  std::vector<std::int32_t> hit, before;
  int returned = 0, reached = 0, changed = 0;
  for (std::uint64_t scan = 0; scan < 10; ++scan) {
    world.flicker_seed = scan;
    const LaserScan s = raycast(world, Pose2{}, g, &hit);
    for (std::size_t i = 0; i < s.size(); ++i) {
      const double bearing = s.bearing_rad(i);
      if (std::abs(2.0 * std::tan(bearing)) >= 0.45) continue;  // Not surely through the bush.
      ++reached;
      if (hit[i] == 1) {
        ++returned;
        EXPECT_LT(s.ranges_m[i], 2.0F);
      } else {
        EXPECT_EQ(hit[i], 0);  // Through it to the wall.
      }
      if (!before.empty() && before[i] != hit[i]) ++changed;
    }
    // The same seed draws the same beams.
    EXPECT_EQ(raycast(world, Pose2{}, g).ranges_m, s.ranges_m);
    before = hit;
  }
  EXPECT_NEAR(static_cast<double>(returned) / reached, 0.4, 0.05);
  EXPECT_GT(changed, reached / 4);  // Different beams in each scan (0.48 expected).
  world.circles[0].return_share = 1.0;
  raycast(world, Pose2{}, g, &hit);
  EXPECT_EQ(std::count(hit.begin(), hit.end(), 0) + std::count(hit.begin(), hit.end(), 1), 401);
  EXPECT_EQ(hit[200], 1);
}

// Glass (Segment::returns_within_rad): a beam that meets the pane nearly square returns from it,
// the others pass through to what lies behind, as real glass and polished panels do.
TEST(Raycast, GlassReturnsOnlyTheBeamsThatMeetItNearlySquare) {
  World world;
  world.segments = {{{2.0, -5.0}, {2.0, 5.0}, 5.0 * kPi / 180.0},  // Glass 2 m ahead,
                    {{6.0, -20.0}, {6.0, 20.0}}};                  // a wall behind it.
  // Beams at 0, 4 and 8 degrees.
  const ScanGeometry g{0.0, 4.0 * kPi / 180.0, 3, 0.1F, 30.0F};
  std::vector<std::int32_t> hit;
  const LaserScan scan = raycast(world, Pose2{0.0, 0.0, 0.0}, g, &hit);
  EXPECT_EQ(hit[0], 0);
  EXPECT_NEAR(scan.ranges_m[0], 2.0F, 1e-5);
  EXPECT_EQ(hit[1], 0);  // 4 degrees from its normal: within 5.
  EXPECT_EQ(hit[2], 1);  // 8 degrees: through the glass to the wall.
  EXPECT_NEAR(scan.ranges_m[2], 6.0 / std::cos(8.0 * kPi / 180.0), 1e-4);
  // From beside the pane's normal the same beam directions all pass through.
  const LaserScan beside = raycast(world, Pose2{0.0, 0.0, 0.3}, g, &hit);
  for (std::int32_t h : hit) EXPECT_EQ(h, 1);
  EXPECT_EQ(beside.size(), 3U);
}

TEST(Raycast, HitsBeyondRangeMaxAreNoReturn) {
  World world;
  world.segments = {{{20.0, -1.0}, {20.0, 1.0}}};
  const LaserScan scan = raycast(world, Pose2{}, {0.0, 0.01, 1, 0.1F, 10.0F});
  EXPECT_TRUE(std::isinf(scan.ranges_m[0]));
}

}  // namespace
}  // namespace dispel::sim
