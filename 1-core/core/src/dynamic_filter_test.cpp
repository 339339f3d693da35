// The dynamic filter on scripted scenes ray-cast at 20 Hz with the thesis's scanner: what each
// of the thesis's mechanisms (and dispel's rules beside them) must do. Recorded data and
// dispel's default: dynamic_filter_defaults_test.cpp; bad input: dynamic_filter_input_test.cpp.
#include "dispel/core/dynamic_filter.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "filter_scenes.hpp"

namespace dispel {
namespace {

using namespace scenes;  // NOLINT: the scenes' vocabulary.

// --- Configuration ------------------------------------------------------------------------------

TEST(DynamicFilterConfig, DefaultsAreValidAndBadValuesNameTheField) {
  DynamicFilterConfig c;  // dispel's default.
  EXPECT_NO_THROW(c.validate());
  EXPECT_DOUBLE_EQ(c.tracking.match_distance_m, 0.25);
  EXPECT_EQ(c.tracking.matching, Matching::kGlobal);
  EXPECT_EQ(c.classification.dynamic_weight_limit, 8);
  EXPECT_EQ(c.classification.static_weight_limit, 50);
  EXPECT_DOUBLE_EQ(c.classification.speed_limit_mps, 0.08);
  EXPECT_DOUBLE_EQ(c.velocity.velocity_decay, 0.8);
  EXPECT_DOUBLE_EQ(c.velocity.measurement_variance_m2, 0.1);
  EXPECT_TRUE(c.free_space.enabled);
  const DynamicFilterConfig t = thesis_config();  // Appendix A and the thesis's rules.
  EXPECT_NO_THROW(t.validate());
  EXPECT_EQ(t.classification.dynamic_weight_limit, 18);
  EXPECT_DOUBLE_EQ(t.velocity.measurement_variance_m2, 15.0);
  EXPECT_DOUBLE_EQ(t.velocity.position_variance_m2, 0.75);
  EXPECT_EQ(t.tracking.matching, Matching::kNearestNeighbour);
  EXPECT_EQ(t.segmentation.gap_metric, GapMetric::kRangeDifference);
  EXPECT_FALSE(t.classification.slow_scans_reduce_dynamic_weight);
  EXPECT_EQ(t.classification.still_scans_to_static, 0);
  EXPECT_FALSE(t.tracking.inherit_on_split);
  EXPECT_EQ(t.tracking.companion_distance_m, 0.0);
  EXPECT_EQ(t.tracking.fragment_distance_m, 0.0);
  EXPECT_FALSE(t.free_space.enabled);
  const auto expect_bad = [](const DynamicFilterConfig& bad, const std::string& field) {
    try {
      DynamicFilter f{bad};
      ADD_FAILURE() << "accepted bad " << field;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  c.tracking.match_distance_m = 0.0;
  expect_bad(c, "tracking.match_distance_m");
  c = DynamicFilterConfig{};
  c.segmentation.min_points = 0;
  expect_bad(c, "segmentation.min_points");
  c = DynamicFilterConfig{};
  c.max_pose_jump_m = -1.0;
  expect_bad(c, "max_pose_jump_m");
  c = DynamicFilterConfig{};
  c.tracking.max_missed_scans = -1;
  expect_bad(c, "tracking.max_missed_scans");
}

// --- Scenes -------------------------------------------------------------------------------------

TEST(DynamicFilter, WalkerCrossingTheViewIsRemovedWithinABoundedNumberOfScans) {
  Scenario s;
  s.walls = room(10.0, 8.0);
  s.pillars = {{{6.0, 3.0}, 0.3}};
  s.movers = {walker({4.0, -3.0}, {0.0, 1.2})};  // Across the view at 4 m, 1.2 m/s.
  DynamicFilter filter{DynamicFilterConfig{}};
  const auto st = run(s, filter, 100);
  const int delay = scans_until_removed(st, 1);
  RecordProperty("scans_until_removed", delay);
  ASSERT_GE(delay, 0) << "walker never removed";
  // With the thesis's filter the velocity passes L_v after about 9 scans and L_d = 18 more are
  // needed; dispel's default is far quicker. The bound holds for both.
  EXPECT_LE(delay, 32);
  EXPECT_EQ(static_removed(st), 0);
}

TEST(DynamicFilter, StaticSceneIsNeverDynamicWhileTheSensorTurnsAndDrives) {
  Scenario s;
  s.walls = room(8.0, 6.0);
  s.walls.push_back({{-3.0, 2.0}, {1.0, 2.5}});  // A rack at an angle.
  s.pillars = {{{3.0, 3.0}, 0.3}, {{-4.0, -2.0}, 0.2}, {{2.0, -3.5}, 0.5}, {{5.0, 0.5}, 0.1}};
  s.sensor = [](double t) { return Pose2{-2.0 + 0.5 * t, -1.0 + 0.2 * t, 0.6 * t}; };
  for (Presumption p : {Presumption::kInnocence, Presumption::kGuilt}) {
    DynamicFilterConfig config;
    config.classification.presumption = p;
    DynamicFilter filter{config};
    std::vector<ScanStats> st;
    int old_tracks_seen = 0;
    for (int k = 0; k < 200; ++k) {
      const Frame f = render(s, k * kPeriod);
      const FilterResult r = filter.process(f.scan, f.pose);
      st.push_back(stats_of(f, r));
      // Under POG an object is removed until proven static; one followed for 2 L_s scans must be.
      for (const TrackedObject& t : r.tracks) {
        if (t.object_index < 0 || t.age_scans <= 2 * config.classification.static_weight_limit) {
          continue;
        }
        ++old_tracks_seen;
        EXPECT_EQ(t.object_class, ObjectClass::kStatic) << "track " << t.id << " scan " << k;
      }
    }
    EXPECT_EQ(filter.counters().beams_removed_dynamic, 0) << "presumption " << static_cast<int>(p);
    EXPECT_GT(old_tracks_seen, 100);
    if (p == Presumption::kInnocence) {
      EXPECT_EQ(static_removed(st), 0);
    }
  }
}

TEST(DynamicFilter, WallBehindAWalkerStaysStaticWhileTheWalkerIsRemoved) {
  // Thesis Figure 3.6: the walker cuts the wall behind it in two, and the cut edges move with it.
  Scenario s;
  s.walls = {{{3.0, -6.0}, {3.0, 6.0}}};
  s.movers = {walker({2.0, -2.0}, {0.0, 1.0})};
  DynamicFilter filter{DynamicFilterConfig{}};
  const auto st = run(s, filter, 80);
  EXPECT_EQ(static_removed(st), 0);
  const int delay = scans_until_removed(st, 1);
  ASSERT_GE(delay, 0);
  EXPECT_LE(delay, 32);
}

TEST(DynamicFilter, WallSeenBetweenTwoPeopleWalkingTogetherStaysStatic) {
  // The piece of wall visible between two people walking side by side has both edges cut by
  // them: both edges and its centroid move with the people, in the same direction. Only because
  // occluded edges are not trusted does that piece keep the wall's zero velocity.
  Scenario s;
  s.walls = {{{3.0, -8.0}, {3.0, 8.0}}};
  s.movers = {walker({2.0, -2.5}, {0.0, 1.0}, 0.2), walker({2.0, -1.7}, {0.0, 1.0}, 0.2)};
  DynamicFilter filter{DynamicFilterConfig{}};
  const auto st = run(s, filter, 90);
  EXPECT_EQ(static_removed(st), 0);
  EXPECT_GE(scans_until_removed(st, 1), 0);
  EXPECT_GE(scans_until_removed(st, 2), 0);
}

TEST(DynamicFilter, ObjectsEnteringAtTheFieldOfViewEdgeWhileTurningStayStatic) {
  // A 180-degree scanner turning at 0.8 rad/s: pillars and walls sweep in at the edge of the view.
  Scenario s;
  s.walls = room(6.0, 5.0);
  s.pillars = {{{2.0, 2.5}, 0.4}, {{-2.5, 1.0}, 0.3}, {{-1.0, -3.0}, 0.5}, {{3.0, -2.0}, 0.25}};
  s.sensor = [](double t) { return Pose2{0.0, 0.0, 0.8 * t}; };
  s.geometry = {-90.0 * kDeg, 0.25 * kDeg, 721, 0.05F, 30.0F};
  DynamicFilter filter{DynamicFilterConfig{}};
  const auto st = run(s, filter, 240);  // More than two full turns.
  EXPECT_EQ(static_removed(st), 0);
  EXPECT_EQ(filter.counters().beams_removed_dynamic, 0);
}

TEST(DynamicFilter, SurfacesCutByTheViewLimitsStayStaticWhileTheSensorTurns) {
  // The thesis's scanner: 275 degrees with mirrors folding two sectors to the floor, leaving sides
  // of 85 degrees and a centre of 19. Turning in place inside a round tank of 1.5 m, each usable
  // sector sees an arc whose two edges are the sector's limits: both edges and the centroid sweep
  // along with the turn, in the same direction, although nothing moves. Only the ambiguity rule
  // (decay, no evidence at view limits; thesis 3.2.2) keeps the arcs static.
  Scenario s;
  s.pillars = {{{0.0, 0.0}, 1.5}};  // The sensor is inside the circle: it sees the far side.
  s.sensor = [](double t) { return Pose2{0.0, 0.0, 0.5 * t}; };
  DynamicFilterConfig config;
  config.segmentation.masked_sectors = {{-52.5 * kDeg, -9.5 * kDeg}, {9.5 * kDeg, 52.5 * kDeg}};
  DynamicFilter filter{config};
  const auto st = run(s, filter, 200);
  EXPECT_EQ(static_removed(st), 0);
  EXPECT_EQ(filter.counters().beams_removed_dynamic, 0);
}

TEST(DynamicFilter, GuiltRemovesANewObjectUntilItHasBeenStillForLsScans) {
  Scenario s;
  s.walls = room(8.0, 6.0);
  // A box is put down at 3 s (scan 60), 3 m in front of the sensor.
  s.movers = {{[](double t) {
                 return t < 2.999 ? Eigen::Vector2d(100.0, 100.0) : Eigen::Vector2d(3.0, 0.5);
               },
               0.3}};
  // The thesis's filter: with free-space evidence a box put down on floor seen empty would be
  // dynamic at once, not unknown.
  DynamicFilterConfig config = thesis_config();
  config.classification.presumption = Presumption::kGuilt;
  DynamicFilter filter{config};
  const auto st = run(s, filter, 160);
  const int ls = config.classification.static_weight_limit;
  int first = -1;
  for (int k = 0; k < 160; ++k) {
    if (st[k].beams.count(1) != 0) {
      first = k;
      break;
    }
  }
  ASSERT_EQ(first, 60);
  // Removed while its static weight grows (one per scan after the first), kept from then on.
  for (int k = first; k < first + ls; ++k) {
    EXPECT_EQ(st[k].removed.at(1), st[k].beams.at(1)) << "scan " << k;
  }
  for (int k = first + ls; k < 160; ++k) {
    EXPECT_EQ(st[k].removed.count(1), 0u) << "scan " << k;
  }
  EXPECT_EQ(filter.counters().beams_removed_dynamic, 0);
}

// Two people walk past each other; the farther one is hidden by the nearer one for a few scans.
// Returns for each mover the set of track ids that followed it, before and after they passed.
std::pair<std::set<std::uint64_t>, std::set<std::uint64_t>> crossing_ids(Matching matching,
                                                                         int mover) {
  Scenario s;
  s.walls = room(10.0, 8.0);
  s.movers = {walker({3.0, -2.0}, {0.0, 1.2}, 0.2), walker({3.6, 2.0}, {0.0, -1.2}, 0.2)};
  DynamicFilterConfig config;
  config.tracking.matching = matching;
  config.tracking.inherit_on_split = false;
  // The matching alone: a walker half hidden by the other is followed through its fragments
  // whatever the matching (tracking.follow_fragments keeps the thesis's matching's track too).
  config.tracking.follow_fragments = false;
  DynamicFilter filter{config};
  std::set<std::uint64_t> before;
  std::set<std::uint64_t> after;
  for (int k = 0; k < 70; ++k) {
    const Frame f = render(s, k * kPeriod);
    const FilterResult r = filter.process(f.scan, f.pose);
    const std::uint64_t id = track_of_mover(f, r, mover);
    if (id == 0) continue;
    if (k >= 10 && k < 25) before.insert(id);  // Well apart, both in full view.
    if (k >= 50 && k < 65) after.insert(id);
  }
  return {before, after};
}

TEST(DynamicFilter, TwoWalkersPassingKeepTheirTrackIdsWithGlobalMatching) {
  for (int mover : {1, 2}) {
    const auto [before, after] = crossing_ids(Matching::kGlobal, mover);
    ASSERT_EQ(before.size(), 1u) << "mover " << mover;
    EXPECT_EQ(after, before) << "mover " << mover;
  }
}

TEST(DynamicFilter, NearestNeighbourMatchingLosesAWalkerHiddenWhileThePathsCross) {
  // The thesis's matching compares with where a track was last seen; the hidden walker
  // reappears farther than D from there and gets a new id.
  int lost = 0;
  for (int mover : {1, 2}) {
    const auto [before, after] = crossing_ids(Matching::kNearestNeighbour, mover);
    ASSERT_EQ(before.size(), 1u);
    lost += after == before ? 0 : 1;
  }
  EXPECT_GE(lost, 1);
}

// The second leg of a walker, tracked on its own from a later scan (it was hidden), is removed
// as soon as it is seen moving beside the first with the companion rule, not L_d scans later.
int scans_until_second_leg_removed(double companion_distance_m) {
  Scenario s;
  s.walls = room(10.0, 8.0);
  // Legs 25 cm apart, one behind the other as they walk across at 1 m/s (too far apart for the
  // two-legs merge); the second leg
  // shows up only after 1.5 s.
  s.movers = {walker({3.0, -3.0}, {0.0, 1.0}, 0.06),
              {[](double t) {
                 return t < 1.5 ? Eigen::Vector2d(50.0, 50.0) : Eigen::Vector2d(3.0, -3.25 + t);
               },
               0.06}};
  DynamicFilterConfig config = mechanism_config();
  config.tracking.companion_distance_m = companion_distance_m;
  config.tracking.inherit_on_split = false;  // That would hand the class over on its own.
  // The default's velocity filter, which follows a walker within a few scans (with the thesis's,
  // the second leg is slow to show any speed at all).
  config.velocity.measurement_variance_m2 = 0.1;
  config.velocity.position_variance_m2 = 0.001;
  DynamicFilter filter{config};
  const auto st = run(s, filter, 100);
  EXPECT_EQ(static_removed(st), 0);
  return scans_until_removed(st, 2);
}

TEST(DynamicFilter, CompanionRuleRemovesTheSecondLegWithTheFirst) {
  const int alone = scans_until_second_leg_removed(0.0);
  const int with_companion = scans_until_second_leg_removed(0.6);
  RecordProperty("second_leg_alone", alone);
  RecordProperty("second_leg_with_companion", with_companion);
  ASSERT_GE(alone, 0);
  ASSERT_GE(with_companion, 0);
  EXPECT_LE(with_companion + 5, alone);
}

TEST(DynamicFilter, SomeoneSteppingIntoSpaceSeenEmptyIsDynamicAtOnceWithFreeSpaceEvidence) {
  // A person steps out from behind a pillar into floor the scanner has been seeing through.
  Scenario s;
  s.walls = room(10.0, 8.0);
  s.pillars = {{{4.0, 2.0}, 0.5}};
  s.movers = {{[](double t) {
                 // Hidden behind the pillar for 2 s, then walking out across the view.
                 return t < 2.0 ? Eigen::Vector2d(5.0, 2.4) : Eigen::Vector2d(5.0, 2.4 - (t - 2.0));
               },
               0.2}};
  for (bool free_space : {false, true}) {
    DynamicFilterConfig config = mechanism_config();
    config.free_space.enabled = free_space;
    DynamicFilter filter{config};
    const auto st = run(s, filter, 120);
    EXPECT_EQ(static_removed(st), 0) << "free space " << free_space;
    const int delay = scans_until_removed(st, 1);
    ASSERT_GE(delay, 0);
    if (free_space) {
      // It must first step clear of the pillar's shadow (never seen) by the neighbourhood of
      // free cells (the default's 3 cells, 0.3 m): 9 scans.
      EXPECT_LE(delay, 10);
    } else {
      EXPECT_GE(delay, 19);  // L_d scans at least.
    }
  }
}

// Removed beams of mover m per scan.
std::vector<int> removed_per_scan(const std::vector<ScanStats>& st, int m) {
  std::vector<int> out;
  for (const ScanStats& s : st) {
    const auto r = s.removed.find(m);
    out.push_back(r == s.removed.end() ? 0 : r->second);
  }
  return out;
}

TEST(DynamicFilter, SomethingSeenOnlyUpCloseThatStaysPutIsStaticAgainAfterItsFreeSpaceEvidence) {
  // A tilted scan plane passes over a low thing (a chair seat, a box) from afar and hits it only
  // up close: beams saw "through" the place where it then appears. negative_2 (a real robot, no
  // people) lost most of its removed beams this way. Its free-space evidence makes it dynamic
  // at once; staying put refutes it within kFreeSpaceDecision_s (0.4 s, 8 scans here).
  const Eigen::Vector2d post(2.0, 0.8);
  Scenario s;
  s.walls = room(10.0, 6.0);
  s.pillars = {{{5.0, 3.0}, 0.3}, {{-4.0, -2.5}, 0.4}};
  s.sensor = [](double t) { return Pose2{-4.0 + 1.0 * t, 0.0, 0.0}; };  // 1 m/s along x.
  s.movers = {{[post, sensor = s.sensor](double t) {
                 const bool near = (sensor(t).translation() - post).norm() < 1.5;
                 return near ? post : Eigen::Vector2d(50.0, 50.0);  // Else out of the room.
               },
               0.08}};
  DynamicFilter filter{DynamicFilterConfig{}};
  const auto st = run(s, filter, 160);  // 8 s: from 1.5 m before the post to past it.
  const std::vector<int> removed = removed_per_scan(st, 1);
  int first_seen = -1, seen = 0;
  for (int k = 0; k < static_cast<int>(st.size()); ++k) {
    const auto b = st[k].beams.find(1);
    if (b == st[k].beams.end()) continue;
    if (first_seen < 0) first_seen = k;
    ++seen;
    if (k > first_seen + 9) {
      EXPECT_EQ(removed[k], 0) << "scan " << k;
    }
  }
  ASSERT_GE(first_seen, 0);
  EXPECT_GT(seen, 40);
  EXPECT_EQ(static_removed(st), 0);
  EXPECT_GE(filter.counters().free_space_refuted, 1);
}

TEST(DynamicFilter, ALongThingWhoseSeenPartGrowsAlongItselfIsStaticAgainAfterItsFreeSpaceEvidence) {
  // A long low thing (a bench, a shelf's lowest board) that a tilted scan plane reaches only
  // within 2.5 m: from 1 s on, as the sensor drives along it at 1 m/s, the part seen grows along
  // it from the far end, in space the beams passed through before. Its centroid slides at half
  // the sensor's speed, 0.2 m in the 0.4 s after free space marks it: a walker's motion by the
  // centroid. Along itself only its edges can show motion, and they part (the far one stays):
  // nothing has moved, and it is static again after kFreeSpaceDecision_s (8 scans), as
  // negative_2's rear laser showed with a wall seen between dropouts.
  Scenario s;
  s.walls = room(10.0, 6.0);
  s.pillars = {{{5.0, 3.0}, 0.3}, {{-4.0, -2.5}, 0.4}};
  s.sensor = [](double t) { return Pose2{-4.0 + 1.0 * t, 0.0, 0.0}; };
  s.pieces = [](double t, const Pose2& sensor) -> std::vector<sim::Segment> {
    // The board from x = -2 to x = 2 at y = 1.5, seen where it is within 2.5 m (|dx| <= 2).
    const double from = std::max(-2.0, sensor.x_m - 2.0), to = std::min(2.0, sensor.x_m + 2.0);
    if (t < 1.0 || to - from < 0.05) return {};
    return {{{from, 1.5}, {to, 1.5}}};
  };
  DynamicFilter filter{DynamicFilterConfig{}};
  const auto st = run(s, filter, 50);  // 2.5 s: the seen part grows from 1 m to 2.5 m.
  int marked_at = -1;
  for (int k = 0; k < static_cast<int>(st.size()); ++k) {
    const auto r = st[k].removed.find(0);
    if (r != st[k].removed.end() && r->second > 0 && marked_at < 0) marked_at = k;
    if (marked_at >= 0 && k > marked_at + 9) {
      EXPECT_EQ(r == st[k].removed.end() ? 0 : r->second, 0) << "scan " << k;
    }
  }
  ASSERT_GE(marked_at, 0) << "free space never marked it: the scene tests nothing";
  EXPECT_GE(filter.counters().free_space_refuted, 1);
}

TEST(DynamicFilter, FreeSpaceNeverConfirmsATrackThatTookAPieceOfAKnownSurface) {
  // negative_2's left laser: a short thing appeared in space seen free (free space made its track
  // dynamic until it could tell) and was gone the next scans; its track, unseen, could take any
  // object within its widening gate, and took a piece of a wall that error-coded beams had cut off
  // (an object no other track continued). The piece was 0.6 m from where the thing had been, so
  // "it moved" confirmed the track, which then went from piece to piece of the walls for 13 s,
  // removing what the map did not explain. A surface the map explains has stood there: it did not
  // come from where the thing was. Here a still scanner, a wall 2 m ahead, a thing beside the
  // wall's end for two scans, and from 0.5 s later the wall's end cut off by two beams that
  // return nothing.
  Scenario s;
  s.walls = room(10.0, 6.0);
  s.walls.push_back({{-1.0, 2.0}, {1.0, 2.0}});
  s.pieces = [](double t, const Pose2& /*sensor*/) -> std::vector<sim::Segment> {
    const auto k = static_cast<int>(std::lround(t / kPeriod));
    if (k < 20 || k > 21) return {};
    return {{{1.45, 2.0}, {1.6, 2.0}}};
  };
  const double cut_from = std::atan2(2.0, 0.8), cut_to = std::atan2(2.0, 0.7);
  DynamicFilter filter{DynamicFilterConfig{}};
  int marked = 0, dynamic_late = 0, cut = 0;
  for (int k = 0; k < 60; ++k) {
    Frame f = render(s, k * kPeriod);
    for (std::size_t b = 0; b < f.scan.size() && k >= 30; ++b) {
      const double bearing =
          f.scan.angle_min_rad + static_cast<double>(b) * f.scan.angle_increment_rad;
      if (bearing >= cut_from && bearing <= cut_to) {
        f.scan.ranges_m[b] = std::numeric_limits<float>::quiet_NaN();
        ++cut;
      }
    }
    const FilterResult r = filter.process(f.scan, f.pose);
    for (const TrackedObject& t : r.tracks) {
      if (t.object_class != ObjectClass::kDynamic || t.object_index < 0) continue;
      if (k <= 21) ++marked;
      if (k >= 30) ++dynamic_late;
    }
  }
  ASSERT_GT(marked, 0) << "free space did not mark the thing: the scene tests nothing";
  ASSERT_GT(cut, 0);
  EXPECT_EQ(dynamic_late, 0);
}

TEST(DynamicFilter, ATrackMarkedByFreeSpaceThatJumpsFartherThanAWalkerIsStaticAtOnce) {
  // person_following_outdoor_1 (a real robot outdoors): a track that free space had marked was
  // unseen for three scans, then took a piece nearby, and at the decision 0.4 s after the marking
  // that read as a walk, which confirmed it. Here a still scanner: a short thing in free space for
  // two scans, unseen for three, then another 0.9 m away (in 0.25 s: a walker gets 0.15 m +
  // 2.5 m/s x 0.25 s, 0.78 m; by the decision 1.15 m, so the decision alone confirmed it). Its
  // verdict is refuted in the scan the track takes it, and its velocity starts afresh.
  Scenario s;
  s.walls = room(10.0, 6.0);
  s.pieces = [](double t, const Pose2& /*sensor*/) -> std::vector<sim::Segment> {
    const auto k = static_cast<int>(std::lround(t / kPeriod));
    if (k == 20 || k == 21) return {{{0.0, 2.5}, {0.15, 2.5}}};
    if (k >= 25) return {{{0.8, 2.1}, {0.95, 2.1}}};
    return {};
  };
  DynamicFilter filter{DynamicFilterConfig{}};
  const auto st = run(s, filter, 40);
  const std::vector<int> removed = removed_per_scan(st, 0);
  std::string per_scan;
  for (int k = 18; k < 40; ++k) per_scan += std::to_string(removed[k]) + " ";
  ASSERT_GT(removed[20], 0) << "free space did not mark the thing: the scene tests nothing; "
                            << per_scan;
  for (int k = 25; k < 40; ++k) EXPECT_EQ(removed[k], 0) << "scan " << k << ": " << per_scan;
  EXPECT_GE(filter.counters().free_space_refuted, 1);
}

TEST(DynamicFilter, AThingLongerThanAWalkerFromNowhereIsKeptInItsFirstScan) {
  // person_following_outdoor_1 (a real robot outdoors): as the robot pitched, its scanner saw the
  // floor, an arc across the view where the scan before returned nothing or something far, and in
  // the next scan 0.5 m nearer or farther; free space removed it in its first scan. Here a still
  // scanner in a room, and from scan 20 on, in space seen free:
  //  - floor: a 1.5 m line 2.6 m away, 0.5 m nearer in each of the next three scans, then gone;
  //  - long: a 1.5 m line 2.0 m away that stays;
  //  - short: a 0.4 m line (a walker's size) 2.0 m away that stays.
  // A long thing from nowhere is kept in its first scan and removed from the next on; the floor,
  // a new thing or a jump in every scan, is never removed; the short thing is removed at once.
  enum class Piece { kFloor, kLong, kShort };
  for (const Piece piece : {Piece::kFloor, Piece::kLong, Piece::kShort}) {
    Scenario s;
    s.walls = room(10.0, 6.0);
    s.pieces = [piece](double t, const Pose2& /*sensor*/) -> std::vector<sim::Segment> {
      const auto k = static_cast<int>(std::lround(t / kPeriod));
      if (k < 20) return {};
      if (piece == Piece::kFloor) {
        if (k > 23) return {};
        const double y = 2.6 - 0.5 * (k - 20);
        return {{{-0.75, y}, {0.75, y}}};
      }
      const double half = piece == Piece::kLong ? 0.75 : 0.2;
      return {{{-half, 2.0}, {half, 2.0}}};
    };
    DynamicFilter filter{DynamicFilterConfig{}};
    const auto st = run(s, filter, 30);
    const std::vector<int> removed = removed_per_scan(st, 0);
    std::string per_scan;
    for (int k = 18; k < 30; ++k) per_scan += std::to_string(removed[k]) + " ";
    switch (piece) {
      case Piece::kFloor:
        for (int k = 18; k < 30; ++k)
          EXPECT_EQ(removed[k], 0) << "floor, scan " << k << ": " << per_scan;
        EXPECT_GE(filter.counters().free_space_held, 1);
        break;
      case Piece::kLong:
        EXPECT_EQ(removed[20], 0) << "long: " << per_scan;
        EXPECT_GT(removed[21], 20) << "long: free space did not mark it: " << per_scan;
        EXPECT_EQ(filter.counters().free_space_held, 1);
        break;
      case Piece::kShort:
        EXPECT_GT(removed[20], 5) << "short: " << per_scan;
        EXPECT_EQ(filter.counters().free_space_held, 0);
        break;
    }
  }
}

TEST(DynamicFilter, APlaceThatReturnedBeforeIsNotFreeSpaceEvidenceWithoutOdometry) {
  // negative_2's lasers (no odometry, no people) removed surfaces that return only now and then:
  // a pane seen square-on, a return between error codes, where the scans between saw 1-7 m
  // farther. Here a still scanner, a 0.4 m pane 3 m ahead that returns for the first 0.5 s, then
  // lets the beams through to the wall for 3 s (longer than tracks are kept), then returns again;
  // and a walker who appears at 3.5 s in floor seen empty. free_space.require_unseen: where the
  // map learnt the pane's points, its return is not evidence that something arrived there; the
  // walker's place held nothing before, and the walker is removed as before.
  Scenario s;
  s.walls = room(10.0, 6.0);
  s.pillars = {{{5.0, 3.0}, 0.3}, {{-4.0, -2.5}, 0.4}};
  s.pieces = [](double t, const Pose2& /*sensor*/) -> std::vector<sim::Segment> {
    if (t >= 0.5 && t < 3.5) return {};
    return {{{3.0, -0.2}, {3.0, 0.2}}};
  };
  s.movers = {{[](double t) {
                 return t < 3.5 ? Eigen::Vector2d(50.0, 50.0)  // Out of the room.
                                : Eigen::Vector2d(6.0, -2.0 + 1.0 * (t - 3.5));
               },
               0.2}};
  constexpr int kScans = 120;  // 6 s.
  struct Case {
    RequireUnseen require;
    bool odometry;
    bool pane_kept;
  };
  for (const Case c :
       {Case{RequireUnseen::kNever, false, false}, Case{RequireUnseen::kLaserOnly, false, true},
        Case{RequireUnseen::kLaserOnly, true, false}, Case{RequireUnseen::kAlways, true, true}}) {
    DynamicFilterConfig config;
    config.free_space.require_unseen = c.require;
    DynamicFilter filter{config};
    std::vector<ScanStats> st;
    for (int k = 0; k < kScans; ++k) {
      const Frame f = render(s, k * kPeriod);
      st.push_back(stats_of(
          f, filter.process(f.scan, c.odometry ? std::optional<Pose2>(f.pose) : std::nullopt)));
    }
    const std::string name = "require_unseen " + std::to_string(static_cast<int>(c.require)) +
                             (c.odometry ? ", odometry" : ", laser-only");
    // The pane is the only static thing that could be removed.
    if (c.pane_kept) {
      EXPECT_EQ(static_removed(st), 0) << name;
      EXPECT_GE(filter.counters().free_space_seen_before, 1) << name;
    } else {
      // Marked at its return: the scene tests something.
      EXPECT_GT(static_removed(st, 70), 0) << name;
      EXPECT_EQ(filter.counters().free_space_seen_before, 0) << name;
    }
    // The walker, new where it appears, is removed within a few scans either way.
    const int delay = scans_until_removed(st, 1);
    EXPECT_GE(delay, 0) << name;
    EXPECT_LE(delay, 10) << name;
  }
}

TEST(DynamicFilter, ALongThingDrivingAlongItselfIntoSpaceSeenEmptyStaysDynamic) {
  // The counterpart: a cart's side, 1.2 m long, driving along itself at 1 m/s from t = 1 s into
  // space the scanner saw through. Both its edges are its outline and move alike: it has moved
  // along itself, and free space's verdict is confirmed. (A piece, static in the scene's truth:
  // the only static beams removed are the cart's.)
  Scenario s;
  s.walls = room(10.0, 6.0);
  s.pillars = {{{5.0, 3.0}, 0.3}};
  s.pieces = [](double t, const Pose2& /*sensor*/) -> std::vector<sim::Segment> {
    if (t < 1.0) return {};
    const double x = -2.0 + 1.0 * (t - 1.0);
    return {{{x, 2.0}, {x + 1.2, 2.0}}};
  };
  DynamicFilter filter{DynamicFilterConfig{}};
  const auto st = run(s, filter, 60);  // 3 s: 2 s driving.
  int marked_at = -1, removed_later = 0, seen_later = 0;
  for (int k = 0; k < static_cast<int>(st.size()); ++k) {
    const auto r = st[k].removed.find(0);
    const int removed = r == st[k].removed.end() ? 0 : r->second;
    if (removed > 0 && marked_at < 0) marked_at = k;
    if (marked_at >= 0 && k > marked_at + 9) {
      ++seen_later;
      removed_later += removed > 0 ? 1 : 0;
    }
  }
  ASSERT_GE(marked_at, 0);
  EXPECT_LE(marked_at, 20 + 2);  // Marked within two scans of appearing.
  EXPECT_GT(seen_later, 20);
  EXPECT_EQ(removed_later, seen_later);  // Still removed in every scan after the decision.
}

TEST(DynamicFilter, APartOfTheRobotThatFlickersIsNeverRemovedWhileTheRobotDrives) {
  // A cable or a flap at the edge of the view 0.27 m from the scanner, in the scan two scans out
  // of three and swinging between two places 4 cm apart in the sensor frame, while the robot
  // drives and turns: it moves in the world (with the robot), it appears in space seen free, and
  // it never stands still in the sensor frame for long. The ranges its beams return again and
  // again say what it is.
  Scenario s;
  s.walls = room(10.0, 8.0);
  s.pillars = {{{4.0, 3.0}, 0.3}, {{-3.0, -4.0}, 0.4}};
  s.sensor = [](double t) { return Pose2{-5.0 + 1.0 * t, -2.0 + 0.3 * t, 0.15 * t}; };
  s.movers = {{[sensor = s.sensor](double t) {
                 const auto k = static_cast<int>(std::lround(t / kPeriod));
                 const double swing = (k / 3) % 2 == 0 ? 0.0 : 0.04;
                 return k % 3 != 2 ? sensor(t).apply(Eigen::Vector2d(-0.1 + swing, 0.25))
                                   : Eigen::Vector2d(50.0, 50.0);
               },
               0.05}};
  DynamicFilter filter{DynamicFilterConfig{}};
  const auto st = run(s, filter, 160);
  const std::vector<int> removed = removed_per_scan(st, 1);
  int seen_late = 0;
  for (int k = 20; k < static_cast<int>(st.size()); ++k) {
    if (st[k].beams.count(1) == 0) continue;
    ++seen_late;
    EXPECT_EQ(removed[k], 0) << "scan " << k;
  }
  EXPECT_GT(seen_late, 50);
  EXPECT_EQ(static_removed(st), 0);
}

TEST(DynamicFilter, WhatABeamReturnsPastTheRobotsOwnBodyIsNeverRemoved) {
  // negative_2's left laser: beams at the edge of the robot's body return it 0.73 m away in most
  // scans, and a constant 3.75 m in others (a return the scanner repeats there) while the robot
  // drives. Held still in the sensor frame, that return moves with the robot through space its
  // other beams saw free: a walker by every other evidence. Here the body (a post 0.72 m to the
  // right) is in the scan ten scans out of fifteen and the return 3.75 m beyond it in the other
  // five, while the robot drives around a circle at 1.2 m/s. The body's beams are learned over
  // the scans with measured motion (about 90 before its share reaches a half); from then on, what
  // they return beyond the body stays.
  Scenario s;
  s.walls = room(12.0, 10.0);
  s.pillars = {{{1.0, 0.5}, 0.3}, {{-9.0, -8.0}, 0.4}};
  s.sensor = [](double t) {
    const double a = 0.4 * t;  // 1.2 m/s around a circle of 3 m, the body outside.
    return Pose2{3.0 * std::cos(a), 3.0 * std::sin(a), a + kPi / 2.0};
  };
  const auto in_sensor_frame = [sensor = s.sensor](Eigen::Vector2d p, bool shown) {
    return [=](double t) {
      const auto k = static_cast<int>(std::lround(t / kPeriod));
      return (k % 15 < 10) == shown ? sensor(t).apply(p) : Eigen::Vector2d(50.0, 50.0);
    };
  };
  s.movers = {{in_sensor_frame({0.0, -0.72}, true), 0.1},
              {in_sensor_frame({0.0, -3.75}, false), 0.12}};
  DynamicFilter filter{DynamicFilterConfig{}};
  const auto st = run(s, filter, 400);
  const std::vector<int> body = removed_per_scan(st, 1);
  const std::vector<int> beyond = removed_per_scan(st, 2);
  int beyond_seen = 0, beyond_removed_early = 0;
  for (int k = 0; k < 150; ++k) beyond_removed_early += beyond[k];
  for (int k = 150; k < static_cast<int>(st.size()); ++k) {
    EXPECT_EQ(body[k], 0) << "scan " << k;
    if (st[k].beams.count(2) == 0) continue;
    ++beyond_seen;
    EXPECT_EQ(beyond[k], 0) << "scan " << k;
  }
  EXPECT_GT(beyond_seen, 60);
  EXPECT_GT(beyond_removed_early, 0);  // Before the body is known, it is a walker.
  EXPECT_EQ(static_removed(st), 0);
}

TEST(DynamicFilter, FragmentsThatStayStillInTheSensorFrameAreNotFollowedAsAWalker) {
  // negative_2's right laser: a part of the robot 0.6 m from the scanner, at the edge of its
  // view, seen once as an object in space seen free (the robot drives: whatever moves with it
  // lands where its beams passed before) and then only as a few beams, fewer than N_min. The
  // track free space made dynamic followed those beams as a walker's fragments for 50 scans. A
  // walker's fragments move in the sensor frame unless the walker keeps pace beside the robot,
  // and then within 1.5 m it is an object, not fragments. Here: the part as an object in one
  // scan, then as a few beams for 3 s, while the robot drives at 1 m/s.
  Scenario s;
  s.walls = room(10.0, 6.0);
  s.pillars = {{{4.0, 3.0}, 0.3}, {{-3.0, -4.0}, 0.4}};
  s.sensor = [](double t) { return Pose2{-5.0 + 1.0 * t, -1.0, 0.0}; };
  const auto part = [sensor = s.sensor](int from, int to) {
    return [=](double t) {
      const auto k = static_cast<int>(std::lround(t / kPeriod));
      return k >= from && k < to ? sensor(t).apply(Eigen::Vector2d(-0.4, -0.45))
                                 : Eigen::Vector2d(50.0, 50.0);
    };
  };
  s.movers = {{part(40, 41), 0.015}, {part(41, 1000), 0.005}};
  DynamicFilter filter{DynamicFilterConfig{}};
  const auto st = run(s, filter, 100);
  const std::vector<int> object = removed_per_scan(st, 1);
  const std::vector<int> fragments = removed_per_scan(st, 2);
  ASSERT_GT(object[40], 0) << "free space did not mark the part: the scene tests nothing";
  int seen_late = 0;
  for (int k = 41; k < static_cast<int>(st.size()); ++k) {
    if (st[k].beams.count(2) == 0) continue;
    EXPECT_LT(st[k].beams.at(2), 8) << "scan " << k << ": an object, not fragments";
    if (k < 41 + 25) continue;  // Still in the sensor frame for kAttachedTime_s (20 scans).
    ++seen_late;
    EXPECT_EQ(fragments[k], 0) << "scan " << k;
  }
  EXPECT_GT(seen_late, 30);
  EXPECT_EQ(static_removed(st), 0);
}

TEST(DynamicFilter, SomeoneWalkingBesideTheDrivingRobotIsStillRemoved) {
  // The rule above learns which beams the robot's body blocks from the objects judged part of the
  // robot within 1 m. Someone who walks 0.6 m beside the robot at its speed keeps to the same
  // place in the sensor frame too, but a swinging gait is never still there: never part of the
  // robot, so never the body, and the walker is removed.
  Scenario s;
  s.walls = room(10.0, 8.0);
  s.pillars = {{{4.0, 3.0}, 0.3}, {{-3.0, -4.0}, 0.4}};
  s.sensor = [](double t) { return Pose2{-5.0 + 1.2 * t, -2.0, 0.0}; };
  s.movers = {{[sensor = s.sensor](double t) {
                 return sensor(t).apply(Eigen::Vector2d(0.15 * std::sin(2.0 * kPi * t), 0.6));
               },
               0.15}};
  DynamicFilter filter{DynamicFilterConfig{}};
  const auto st = run(s, filter, 160);
  const int delay = scans_until_removed(st, 1);
  ASSERT_GE(delay, 0);
  EXPECT_LE(delay, 20);
  EXPECT_EQ(static_removed(st), 0);
}

TEST(DynamicFilter, MissedScansAndIrregularTimeStepsStillRemoveTheWalker) {
  Scenario s;
  s.walls = room(10.0, 8.0);
  s.movers = {walker({4.0, -3.5}, {0.0, 1.0})};
  DynamicFilter filter{DynamicFilterConfig{}};
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<ScanStats> st;
  std::set<std::uint64_t> ids;
  double t = 0.0;
  int processed = 0;
  while (t < 6.0) {
    t += 0.03 + 0.05 * u(rng);    // Irregular stamps.
    if (u(rng) < 0.25) continue;  // Dropped scans.
    const Frame f = render(s, t);
    const FilterResult r = filter.process(f.scan, f.pose);
    st.push_back(stats_of(f, r));
    ++processed;
    EXPECT_NE(r.event, FilterEvent::kResetTimeGap);
    if (t > 1.0 && t < 5.0) ids.insert(track_of_mover(f, r, 1));
  }
  EXPECT_EQ(static_removed(st), 0);
  const int delay = scans_until_removed(st, 1);
  ASSERT_GE(delay, 0);
  EXPECT_LE(delay, 40);
  EXPECT_EQ(ids.size(), 1u);
  EXPECT_GT(processed, 60);
}

TEST(DynamicFilter, TracksOfVanishedObjectsExpireAndTrackCountStaysBounded) {
  DynamicFilterConfig config = mechanism_config();  // Tracks kept 10 missed scans.
  DynamicFilter filter{config};
  const sim::ScanGeometry g = thesis_geometry();
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::size_t max_tracks = 0;
  for (int k = 0; k < 400; ++k) {
    // Every 20 scans, twenty pillars in new places.
    sim::World world;
    world.segments = room(12.0, 10.0);
    std::mt19937 scene_rng(static_cast<unsigned>(k / 20));
    std::uniform_real_distribution<double> v(-1.0, 1.0);
    for (int p = 0; p < 20; ++p)
      world.circles.push_back({{8.0 * v(scene_rng), 7.0 * v(scene_rng)}, 0.3});
    LaserScan scan = sim::raycast(world, Pose2{}, g);
    scan.stamp_s = k * kPeriod;
    filter.process(scan, Pose2{});
    max_tracks = std::max(max_tracks, filter.track_count());
  }
  // At most the live objects plus those still remembered (max_missed_scans after vanishing).
  EXPECT_LE(max_tracks, 80u);
  EXPECT_GT(filter.counters().tracks_dropped, 300);

  // A single object: its track is gone exactly max_missed_scans + 1 scans after it vanished.
  DynamicFilter single{config};
  sim::World world;
  world.circles = {{{2.0, 0.0}, 0.3}};
  LaserScan scan = sim::raycast(world, Pose2{}, g);
  for (int k = 0; k < 5; ++k) {
    scan.stamp_s = k * kPeriod;
    single.process(scan, Pose2{});
  }
  ASSERT_EQ(single.track_count(), 1u);
  LaserScan empty = sim::raycast(sim::World{}, Pose2{}, g);
  for (int k = 0; k <= config.tracking.max_missed_scans; ++k) {
    EXPECT_EQ(single.track_count(), 1u);
    empty.stamp_s = (5 + k) * kPeriod;
    single.process(empty, Pose2{});
  }
  EXPECT_EQ(single.track_count(), 0u);
}
}  // namespace
}  // namespace dispel
