#include "dispel/core/free_space_map.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

namespace dispel {
namespace {

// A 180-degree scan with every beam returning at `range`.
LaserScan ring(float range) {
  LaserScan s;
  s.angle_min_rad = -kPi / 2.0;
  s.angle_increment_rad = kPi / 360.0;
  s.range_min_m = 0.05F;
  s.range_max_m = 30.0F;
  s.ranges_m.assign(361, range);
  return s;
}

TEST(FreeSpaceMap, SpaceSeenThroughIsFreeButNotTheSurfaceOrBeyondIt) {
  FreeSpaceConfig c;
  c.enabled = true;
  FreeSpaceMap map(c);
  EXPECT_FALSE(map.known_free({1.0, 0.0}));  // Nothing seen yet.
  for (int k = 0; k < 3; ++k) map.add_scan(ring(4.0F), Pose2{});
  EXPECT_TRUE(map.known_free({1.0, 0.0}));
  EXPECT_TRUE(map.known_free({2.0, 1.0}));
  EXPECT_FALSE(map.known_free({3.9, 0.0}));   // Within the margin of the surface.
  EXPECT_FALSE(map.known_free({5.0, 0.0}));   // Behind it.
  EXPECT_FALSE(map.known_free({-1.0, 0.0}));  // Never in view.
  // Something now stands at 2 m. For a few scans its cell is still "free" (it may be passing
  // through); after max_recent_hits scans in a row it stands there.
  for (int k = 0; k < c.max_recent_hits; ++k) map.add_scan(ring(2.0F), Pose2{});
  EXPECT_TRUE(map.known_free({2.0, 0.0}));
  map.add_scan(ring(2.0F), Pose2{});
  EXPECT_FALSE(map.known_free({2.0, 0.0}));
  EXPECT_TRUE(map.known_free({1.0, 0.0}));
  map.clear();
  EXPECT_FALSE(map.known_free({1.0, 0.0}));
}

TEST(FreeSpaceMap, NeedsEnoughObservationsAndFollowsTheSensorPose) {
  FreeSpaceConfig c;
  c.min_free_observations = 2;
  FreeSpaceMap map(c);
  map.add_scan(ring(4.0F), Pose2{10.0, 5.0, kPi / 2.0});  // Looking along +y from (10, 5).
  EXPECT_FALSE(map.known_free({10.0, 7.0}));
  map.add_scan(ring(4.0F), Pose2{10.0, 5.0, kPi / 2.0});
  EXPECT_TRUE(map.known_free({10.0, 7.0}));
  EXPECT_FALSE(map.known_free({12.0, 5.0 - 1.0}));
}

TEST(FreeSpaceConfig, BadValuesAreRejectedByName) {
  FreeSpaceConfig c;
  c.cell_size_m = 0.0;
  EXPECT_THROW(c.validate(), std::invalid_argument);
  c = FreeSpaceConfig{};
  c.min_object_share = 1.5;
  try {
    c.validate();
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("free_space.min_object_share"), std::string::npos);
  }
}

}  // namespace
}  // namespace dispel
