#include "dispel/core/free_space_map.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <limits>
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
  // Something now stands at 2 m. Seen through in only 3 scans, one hit is enough to make its cell
  // not free.
  map.add_scan(ring(2.0F), Pose2{});
  EXPECT_FALSE(map.known_free({2.0, 0.0}));
  // Seen through for long, a cell stays free while something crosses it for up to
  // max_recent_hits scans (a walker), and not once something stands there longer.
  for (int k = 0; k < 50; ++k) map.add_scan(ring(4.0F), Pose2{});
  for (int k = 0; k < c.max_recent_hits; ++k) map.add_scan(ring(2.0F), Pose2{});
  EXPECT_TRUE(map.known_free({2.0, 0.0}));
  map.add_scan(ring(2.0F), Pose2{});
  EXPECT_FALSE(map.known_free({2.0, 0.0}));
  EXPECT_TRUE(map.known_free({1.0, 0.0}));
  map.clear();
  EXPECT_FALSE(map.known_free({1.0, 0.0}));
}

TEST(FreeSpaceMap, LongFreeIsSpaceSeenThroughInAsManyMoreScansAsTheBalanceCounts) {
  FreeSpaceConfig c;
  FreeSpaceMap map(c);
  const int cap = c.min_free_observations + c.max_recent_hits;  // 13.
  // Something stood at 2 m for 20 scans, then left: the space is known free after
  // min_free_observations + 20 scans seen through (the balance was clamped at +13), and long
  // free only once the balance reaches -13, 26 scans after the last hit.
  for (int k = 0; k < 20; ++k) map.add_scan(ring(2.0F), Pose2{});
  int to_known = -1, to_long = -1;
  for (int k = 1; k <= 40; ++k) {
    map.add_scan(ring(4.0F), Pose2{});
    if (to_known < 0 && map.known_free({2.0, 0.0})) to_known = k;
    if (to_long < 0 && map.long_free({2.0, 0.0})) to_long = k;
    EXPECT_FALSE(map.long_free({2.0, 0.0}) && !map.known_free({2.0, 0.0})) << k;
  }
  EXPECT_EQ(to_known, cap + c.min_free_observations);
  EXPECT_EQ(to_long, 2 * cap);
  EXPECT_FALSE(map.long_free({3.9, 0.0}));  // The surface's margin: never seen through.
  map.add_scan(ring(2.0F), Pose2{});        // Back again: one hit.
  EXPECT_TRUE(map.known_free({2.0, 0.0}));  // A walker crossing free space.
  EXPECT_FALSE(map.long_free({2.0, 0.0}));
}

TEST(FreeSpaceMap, ThinThingsNeedSpaceSeenThroughByBeamsDenseEnoughToHitThem) {
  // ring()'s beams are 0.5 degrees apart: 8.7 mm at 1 m, 44 mm at 5 m. A chair leg 2 cm wide at
  // 5 m can sit between two beams; at 1 m it cannot.
  FreeSpaceConfig c;
  FreeSpaceMap map(c);
  for (int k = 0; k < 3; ++k) map.add_scan(ring(8.0F), Pose2{});
  const Eigen::Vector2d far(5.0, 0.0);
  EXPECT_TRUE(map.known_free(far));
  EXPECT_TRUE(map.known_free(far, 0.05));   // Beams 44 mm apart there: a 10 cm thing is hit.
  EXPECT_FALSE(map.known_free(far, 0.01));  // A 2 cm thing could have been missed.
  // The same place seen through from 1 m away (the sensor 4 m along x): dense enough now.
  for (int k = 0; k < 3; ++k) map.add_scan(ring(8.0F), Pose2{4.0, 0.0, 0.0});
  EXPECT_TRUE(map.known_free(far, 0.01));
  EXPECT_FALSE(map.known_free(far, 0.001));
  EXPECT_FALSE(map.known_free({-1.0, 0.0}, 1.0));  // Never in view.
}

TEST(FreeSpaceMap, BeamsWithoutReturnSeeThroughUpToTheirReach) {
  FreeSpaceConfig c;
  c.free_range_m = 6.0;
  FreeSpaceMap map(c);
  LaserScan nothing = ring(std::numeric_limits<float>::infinity());
  for (int k = 0; k < 3; ++k) map.add_scan(nothing, Pose2{});
  EXPECT_TRUE(map.known_free({5.0, 0.0}));
  EXPECT_FALSE(map.known_free({7.0, 0.0}));  // Beyond the reach.
  // The scan's own maximum range caps the reach (a scanner cut to 5.5 m).
  FreeSpaceMap capped(c);
  nothing.range_max_m = 4.0F;
  for (int k = 0; k < 3; ++k) capped.add_scan(nothing, Pose2{});
  EXPECT_TRUE(capped.known_free({3.0, 0.0}));
  EXPECT_FALSE(capped.known_free({5.0, 0.0}));
  // Invalid measurements (NaN) say nothing; nor does "no return" when told so.
  FreeSpaceMap unknown(c);
  LaserScan masked = ring(std::numeric_limits<float>::quiet_NaN());
  for (int k = 0; k < 3; ++k) unknown.add_scan(masked, Pose2{});
  EXPECT_FALSE(unknown.known_free({1.0, 0.0}));
  c.no_return_is_free = false;
  FreeSpaceMap off(c);
  for (int k = 0; k < 3; ++k) off.add_scan(ring(std::numeric_limits<float>::infinity()), Pose2{});
  EXPECT_FALSE(off.known_free({1.0, 0.0}));
}

TEST(FreeSpaceMap, ASurfaceSeenThroughNowAndThenIsNeverFree) {
  // Beams through a cell that another beam of the same scan hits: the cell is not free; and a
  // dropout now and then on a surface does not make it free either.
  FreeSpaceConfig c;
  c.neighbourhood_cells = 0;
  FreeSpaceMap map(c);
  LaserScan s = ring(4.0F);
  s.ranges_m[180] = 2.0F;                                    // Straight ahead, a return at 2 m ...
  s.ranges_m[181] = std::numeric_limits<float>::infinity();  // ... beside a beam with none.
  for (int k = 0; k < 5; ++k) map.add_scan(s, Pose2{});
  EXPECT_FALSE(map.known_free({2.0, 0.0}));
  EXPECT_TRUE(map.known_free({1.0, 0.0}));
  LaserScan dropout = s;
  dropout.ranges_m[180] = std::numeric_limits<float>::infinity();
  for (int k = 0; k < 200; ++k) map.add_scan(k % 4 == 0 ? dropout : s, Pose2{});
  EXPECT_FALSE(map.known_free({2.0, 0.0}));
}

TEST(FreeSpaceMap, ABeamFreesEveryCellItCrossesAndNoOther) {
  FreeSpaceConfig c;
  c.neighbourhood_cells = 0;
  c.min_free_observations = 1;
  FreeSpaceMap map(c);
  LaserScan one;
  one.angle_min_rad = 0.5236;  // A single beam at 30 degrees, from an off-grid position.
  one.angle_increment_rad = 0.01;
  one.range_min_m = 0.05F;
  one.range_max_m = 30.0F;
  one.ranges_m = {5.0F};
  const Pose2 pose{0.337, -0.051, 0.2};
  map.add_scan(one, pose);
  const double bearing = pose.yaw_rad + one.angle_min_rad;
  const Eigen::Vector2d dir(std::cos(bearing), std::sin(bearing));
  const Eigen::Vector2d side(-dir.y(), dir.x());
  for (double s = 0.0; s < 5.0 - c.margin_m - 0.01; s += 0.01) {
    ASSERT_TRUE(map.known_free(pose.translation() + s * dir)) << s;
    EXPECT_FALSE(map.known_free(pose.translation() + s * dir + 0.25 * side)) << s;
  }
  EXPECT_FALSE(map.known_free(pose.translation() + 4.9 * dir));
}

TEST(FreeSpaceMap, ADenseScanLeavesNoHolesWhereItTracesSparsely) {
  // The thesis's scanner: 1617 beams over 275 degrees. Near the scanner only every 16th beam is
  // traced (the others cross the same cells); every cell inside the fan must still be seen.
  FreeSpaceConfig c;
  c.neighbourhood_cells = 0;
  c.min_free_observations = 1;
  FreeSpaceMap map(c);
  LaserScan s;
  s.angle_min_rad = -137.5 * kPi / 180.0;
  s.angle_increment_rad = 275.0 * kPi / 180.0 / 1616.0;
  s.range_min_m = 0.05F;
  s.range_max_m = 40.0F;
  s.ranges_m.assign(1617, 8.0F);
  // Something at 1 m casts a shadow over beams 805 to 823: beside it the space stays seen.
  for (std::size_t b = 805; b <= 823; ++b) s.ranges_m[b] = 1.0F;
  const double shadow_begin = s.bearing_rad(805), shadow_end = s.bearing_rad(823);
  const Pose2 pose{1.234, -0.567, 0.3};
  map.add_scan(s, pose);
  int checked = 0, shadowed = 0;
  for (double r = 0.2; r < 7.5; r += 0.05) {
    for (double a = -130.0; a <= 130.0; a += 0.25) {
      const double bearing = a * kPi / 180.0;
      const Eigen::Vector2d p =
          pose.translation() +
          r * Eigen::Vector2d(std::cos(pose.yaw_rad + bearing), std::sin(pose.yaw_rad + bearing));
      const double margin = 0.15 / r;  // A cell and a half.
      // Points just beside the shadow (half a beam beyond its last beam) must be seen.
      const double edge = 0.5 * s.angle_increment_rad;
      const bool near_occluder = std::abs(r - 1.0) < 0.4 && bearing > shadow_begin - 0.4 / r &&
                                 bearing < shadow_end + 0.4 / r;  // Its margin_m and cells.
      if (near_occluder) continue;
      if (bearing > shadow_begin - edge && bearing < shadow_end + edge) {
        if (r > 1.3 && bearing > shadow_begin + margin && bearing < shadow_end - margin) {
          EXPECT_FALSE(map.known_free(p)) << "in the shadow: r " << r << " a " << a;
          ++shadowed;
        }
        continue;
      }
      ASSERT_TRUE(map.known_free(p)) << "r " << r << " a " << a;
      ++checked;
    }
  }
  EXPECT_GT(checked, 100000);
  EXPECT_GT(shadowed, 50);
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

TEST(FreeSpaceMap, ScrollsWithTheSensorAndKeepsWhatIsWithinHalfAWindow) {
  // The window is 102.4 m. The sensor drives 40 m along -x (past the window's first edge, into
  // negative cells): what it saw at the start, 40 m behind, is still known; nothing is lost by
  // re-centring, and the way ahead is seen as on the first scan.
  FreeSpaceConfig c;
  FreeSpaceMap map(c);
  for (int k = 0; k < 3; ++k) map.add_scan(ring(4.0F), Pose2{0.0, 0.0, kPi});
  ASSERT_TRUE(map.known_free({-2.0, 0.0}));
  for (int step = 1; step <= 400; ++step) {
    map.add_scan(ring(4.0F), Pose2{-0.1 * step, 0.0, kPi});
  }
  EXPECT_TRUE(map.known_free({-2.0, 0.0}));  // Seen 40 m back, within the memory of 30 s.
  for (int k = 0; k < 3; ++k) map.add_scan(ring(4.0F), Pose2{-40.0, 0.0, kPi});
  EXPECT_TRUE(map.known_free({-42.0, 0.0}));
  EXPECT_FALSE(map.known_free({-44.5, 0.0}));  // Behind the surface.
  // Driving on for 1 km: each tile is started as the beams reach it, a few per scan, never the
  // window (128 x 128 tiles).
  map.take_tiles_started();
  std::int64_t most = 0;
  for (int step = 1; step <= 10000; ++step) {
    map.add_scan(ring(4.0F), Pose2{-40.0 - 0.1 * step, 0.0, kPi});
    most = std::max(most, map.take_tiles_started());
  }
  EXPECT_GT(most, 0);
  EXPECT_LE(most, 20);
  EXPECT_TRUE(map.known_free({-1042.0, 0.0}));
  // Far behind (more than half a window) is forgotten, whatever the slots hold now.
  EXPECT_FALSE(map.known_free({-2.0, 0.0}));
  EXPECT_FALSE(map.known_free({-980.0, 0.0}));
}

TEST(FreeSpaceMap, AWindowOfAnyNumberOfTilesScrollsTheSame) {
  // 60 m: 600 cells, 75 tiles a side (not a power of two: slots by the remainder, here of
  // negative tile coordinates too). Both maps see the same drive of 45 m; near the sensor they
  // agree (asked at cell centres; the two windows' corners are 51.2 m and 30 m from the first
  // pose, so a beam's path through the cells is computed from other numbers and may differ by a
  // rounding error where it grazes a corner).
  FreeSpaceConfig c;
  FreeSpaceMap wide(c);
  c.extent_m = 60.0;
  FreeSpaceMap narrow(c);
  for (int step = 0; step <= 450; ++step) {
    const double x = -0.1 * step;
    wide.add_scan(ring(4.0F), Pose2{x, 0.0, kPi});
    narrow.add_scan(ring(4.0F), Pose2{x, 0.0, kPi});
    if (step % 50 != 0 || step == 0) continue;
    int free_cells = 0, disagree = 0;
    for (int i = 0; i <= 120; ++i) {
      for (int j = 0; j <= 120; ++j) {
        const Eigen::Vector2d p(x - 6.05 + 0.1 * i, -6.05 + 0.1 * j);
        disagree += wide.known_free(p) != narrow.known_free(p) ? 1 : 0;
        EXPECT_LE(std::abs(wide.hit_balance(p) - narrow.hit_balance(p)), 1) << "step " << step;
        free_cells += wide.known_free(p) ? 1 : 0;
      }
    }
    EXPECT_LT(disagree, 121 * 121 / 100) << "step " << step;
    EXPECT_GT(free_cells, 1000) << "step " << step;
  }
  // 31 m behind: still known to the wide window (reach 63 tiles, 50.4 m), not to the narrow one
  // (37 tiles, 29.6 m).
  EXPECT_TRUE(wide.known_free({-14.05, 0.05}));
  EXPECT_FALSE(narrow.known_free({-14.05, 0.05}));
}

TEST(FreeSpaceMap, ClearForgetsEverythingAtOnceAndTheMapStartsAgainWhereTheSensorIs) {
  FreeSpaceConfig c;
  FreeSpaceMap map(c);
  for (int k = 0; k < 3; ++k) map.add_scan(ring(4.0F), Pose2{});
  const std::int64_t first = map.take_tiles_started();
  EXPECT_GT(first, 0);
  map.add_scan(ring(4.0F), Pose2{});
  EXPECT_EQ(map.take_tiles_started(), 0);  // The same place: every tile is held.
  map.clear();
  EXPECT_FALSE(map.known_free({1.0, 0.0}));
  EXPECT_EQ(map.hit_balance({4.0, 0.0}), 0);
  // Somewhere else entirely (a reset after a jump of 1e6 m): placed there, not 1e6 m away.
  for (int k = 0; k < 3; ++k) map.add_scan(ring(4.0F), Pose2{1e6, -1e6, 0.0});
  EXPECT_TRUE(map.known_free({1e6 + 1.0, -1e6}));
  EXPECT_FALSE(map.known_free({1.0, 0.0}));
  // Started afresh there: as many tiles as the first time, give or take the ring's edge (the
  // cells' boundaries fall a rounding error apart at 1e6 m).
  const std::int64_t again = map.take_tiles_started();
  EXPECT_GT(again, first / 2);
  EXPECT_LT(again, 2 * first);
}

// A map made from an earlier one (the runner makes the window before the first scan says how to
// scale the filter) forgets everything the earlier one held and works as a new one; a window of
// another size is made anew.
TEST(FreeSpaceMap, AMapMadeFromAnEarlierOneStartsEmptyAndWorksTheSame) {
  FreeSpaceConfig c;
  FreeSpaceMap earlier(c);
  for (int k = 0; k < 3; ++k) earlier.add_scan(ring(4.0F), Pose2{});
  ASSERT_TRUE(earlier.known_free({1.0, 0.0}));
  FreeSpaceConfig scaled = c;
  scaled.min_free_observations = 2;
  FreeSpaceMap map(scaled, std::move(earlier));
  EXPECT_FALSE(map.known_free({1.0, 0.0}));
  EXPECT_EQ(map.hit_balance({4.0, 0.0}), 0);
  EXPECT_EQ(map.config().min_free_observations, 2);
  FreeSpaceMap fresh(scaled);
  for (int k = 0; k < 2; ++k) {
    map.add_scan(ring(4.0F), Pose2{0.5, 0.0, 0.0});
    fresh.add_scan(ring(4.0F), Pose2{0.5, 0.0, 0.0});
  }
  EXPECT_TRUE(map.known_free({1.5, 0.0}));
  EXPECT_EQ(map.take_tiles_started(), fresh.take_tiles_started());
  for (double x = -6.0; x <= 6.0; x += 0.25) {
    for (double y = -6.0; y <= 6.0; y += 0.25) {
      ASSERT_EQ(map.known_free({x, y}), fresh.known_free({x, y})) << x << " " << y;
      ASSERT_EQ(map.hit_balance({x, y}), fresh.hit_balance({x, y})) << x << " " << y;
    }
  }
  FreeSpaceConfig smaller = c;
  smaller.extent_m = 51.2;
  FreeSpaceMap other(smaller, std::move(map));
  for (int k = 0; k < 3; ++k) other.add_scan(ring(4.0F), Pose2{});
  EXPECT_TRUE(other.known_free({1.0, 0.0}));
}

TEST(FreeSpaceMap, PointsOutOfReachOrNotFiniteAreNeverFree) {
  FreeSpaceConfig c;
  FreeSpaceMap map(c);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(map.known_free({nan, 0.0}));
  for (int k = 0; k < 3; ++k) map.add_scan(ring(4.0F), Pose2{});
  EXPECT_FALSE(map.known_free({nan, 0.0}));
  EXPECT_FALSE(map.known_free({inf, 0.0}));
  EXPECT_FALSE(map.known_free({1e300, -1e300}));
  EXPECT_EQ(map.occupied_scans({-1e300, 0.0}), 0);
  // A sensor pose that is not finite adds nothing and breaks nothing.
  map.add_scan(ring(4.0F), Pose2{nan, 0.0, 0.0});
  map.add_scan(ring(4.0F), Pose2{1e300, 0.0, 0.0});
  EXPECT_FALSE(map.known_free({1.0, 0.0}));  // Far away now: the map started again there.
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
