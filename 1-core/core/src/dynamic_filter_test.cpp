#include "dispel/core/dynamic_filter.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "dispel/core/pose2.hpp"
#include "dispel/sim/raycast.hpp"
#include "scan_csv.hpp"

namespace dispel {
namespace {

constexpr double kDeg = kPi / 180.0;
constexpr double kPeriod = 0.05;  // 20 Hz, the thesis's scanner.

sim::ScanGeometry thesis_geometry() {
  return {-137.5 * kDeg, 275.0 * kDeg / 1616.0, 1617, 0.05F, 40.0F};
}

// A scripted scene: static walls and pillars, moving circles (people), a moving sensor.
struct Mover {
  std::function<Eigen::Vector2d(double)> center;
  double radius_m;
};
struct Scenario {
  std::vector<sim::Segment> walls;
  std::vector<sim::Circle> pillars;
  std::vector<Mover> movers;
  std::function<Pose2(double)> sensor = [](double) { return Pose2{}; };
  sim::ScanGeometry geometry = thesis_geometry();
};

// Ground truth per beam: -1 no return, 0 static structure, m + 1 for mover m.
struct Frame {
  LaserScan scan;
  Pose2 pose;
  std::vector<int> truth;
};

Frame render(const Scenario& s, double t) {
  sim::World world;
  world.segments = s.walls;
  world.circles = s.pillars;
  for (const Mover& m : s.movers) world.circles.push_back({m.center(t), m.radius_m});
  Frame f;
  f.pose = s.sensor(t);
  std::vector<std::int32_t> hit;
  f.scan = sim::raycast(world, f.pose, s.geometry, &hit);
  f.scan.stamp_s = t;
  const auto first_mover = static_cast<std::int32_t>(s.walls.size() + s.pillars.size());
  f.truth.resize(hit.size());
  for (std::size_t i = 0; i < hit.size(); ++i) {
    f.truth[i] = hit[i] < 0 ? -1 : (hit[i] < first_mover ? 0 : hit[i] - first_mover + 1);
  }
  return f;
}

bool removed(BeamLabel l) { return l == BeamLabel::kDynamic || l == BeamLabel::kUnknown; }

// Per scan: how many beams of each truth class there were and how many were removed.
struct ScanStats {
  std::map<int, int> beams;
  std::map<int, int> removed;
  FilterEvent event;
};

ScanStats stats_of(const Frame& f, const FilterResult& r) {
  ScanStats st;
  st.event = r.event;
  EXPECT_EQ(r.labels.size(), f.scan.size());
  for (std::size_t i = 0; i < f.truth.size(); ++i) {
    if (f.truth[i] < 0) continue;
    ++st.beams[f.truth[i]];
    if (removed(r.labels[i])) {
      ++st.removed[f.truth[i]];
      EXPECT_TRUE(std::isnan(r.filtered.ranges_m[i]));
    } else {
      EXPECT_EQ(r.filtered.ranges_m[i], f.scan.ranges_m[i]);
    }
  }
  return st;
}

std::vector<ScanStats> run(const Scenario& s, DynamicFilter& filter, int scans) {
  std::vector<ScanStats> out;
  for (int k = 0; k < scans; ++k) {
    const Frame f = render(s, k * kPeriod);
    out.push_back(stats_of(f, filter.process(f.scan, f.pose)));
  }
  return out;
}

// Scans from the first in which mover m is seen until all but `tolerance` of its beams are
// removed in every later scan where it shows at least `min_beams` beams. -1 if never.
int scans_until_removed(const std::vector<ScanStats>& st, int m, int min_beams = 8) {
  int first_seen = -1;
  int last_bad = -1;
  for (int k = 0; k < static_cast<int>(st.size()); ++k) {
    const auto b = st[k].beams.find(m);
    if (b == st[k].beams.end() || b->second < min_beams) continue;
    if (first_seen < 0) first_seen = k;
    const auto r = st[k].removed.find(m);
    const int rem = r == st[k].removed.end() ? 0 : r->second;
    if (rem < 0.9 * b->second) last_bad = k;
  }
  if (first_seen < 0 || last_bad == static_cast<int>(st.size()) - 1) return -1;
  return std::max(0, last_bad + 1 - first_seen);
}

std::int64_t static_removed(const std::vector<ScanStats>& st, int from = 0) {
  std::int64_t n = 0;
  for (std::size_t k = from; k < st.size(); ++k) {
    const auto r = st[k].removed.find(0);
    n += r == st[k].removed.end() ? 0 : r->second;
  }
  return n;
}

std::vector<sim::Segment> room(double half_x, double half_y) {
  return {{{-half_x, -half_y}, {half_x, -half_y}},
          {{half_x, -half_y}, {half_x, half_y}},
          {{half_x, half_y}, {-half_x, half_y}},
          {{-half_x, half_y}, {-half_x, -half_y}}};
}

Mover walker(Eigen::Vector2d start, Eigen::Vector2d velocity, double radius = 0.2) {
  return {[=](double t) { return Eigen::Vector2d(start + t * velocity); }, radius};
}

// The thesis's parameters with dispel's matching and evidence rules, without free space: what
// DynamicFilterConfig{} was before the type's defaults became dispel's. The scenes that measure
// one mechanism against the thesis's L_d = 18 (a box under POG, the companion rule, free space
// against none, track expiry) use it, so that the default's other rules do not hide it.
DynamicFilterConfig mechanism_config() {
  DynamicFilterConfig c = thesis_config();
  c.segmentation.gap_metric = GapMetric::kEuclidean;
  c.tracking.matching = Matching::kGlobal;
  c.tracking.inherit_on_split = true;
  c.classification.slow_scans_reduce_dynamic_weight = true;
  c.classification.still_scans_to_static = 100;
  return c;
}

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

// Which track id covers the most beams of mover m in this scan (0 if none).
std::uint64_t track_of_mover(const Frame& f, const FilterResult& r, int m) {
  std::map<std::int32_t, int> votes;
  for (std::size_t i = 0; i < f.truth.size(); ++i) {
    if (f.truth[i] == m && r.segmentation.beam_labels[i] >= 0)
      ++votes[r.segmentation.beam_labels[i]];
  }
  std::int32_t best = -1;
  int best_votes = 0;
  for (const auto& [object, n] : votes) {
    if (n > best_votes) {
      best = object;
      best_votes = n;
    }
  }
  for (const TrackedObject& t : r.tracks) {
    if (best >= 0 && t.object_index == best) return t.id;
  }
  return 0;
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

// --- Recorded data ------------------------------------------------------------------------------

struct RecordedScore {
  double preservation;  // Background beams kept / background beams.
  double rejection;     // Foreground beams removed / foreground beams.
  std::int64_t background = 0, foreground = 0;
};

// leg_tracker: a stationary scanner (10 Hz, 512 beams, 5.6 m) in a room with people walking.
// Without labels, a beam's background range is the 90th percentile of its valid ranges over the
// 40 s: a beam within 10 cm of it sees the room; one more than 30 cm in front of it sees a person.
RecordedScore score_recorded(const DynamicFilterConfig& config) {
  const auto scans = testing::read_scan_csv(testing::data_path("leg_tracker/scans_250_to_650.csv"));
  const std::size_t n = scans.front().size();
  std::vector<float> background(n, std::numeric_limits<float>::infinity());
  for (std::size_t i = 0; i < n; ++i) {
    std::vector<float> v;
    for (const LaserScan& s : scans) {
      if (s.is_valid(i)) v.push_back(s.ranges_m[i]);
    }
    if (v.size() < scans.size() / 2) continue;
    std::nth_element(v.begin(), v.begin() + v.size() * 9 / 10, v.end());
    background[i] = v[v.size() * 9 / 10];
  }
  DynamicFilter filter{config};
  RecordedScore score{};
  std::int64_t kept = 0, removed_fg = 0;
  for (std::size_t k = 0; k < scans.size(); ++k) {
    const FilterResult r = filter.process(scans[k], Pose2{});
    EXPECT_EQ(r.event, k == 0 ? FilterEvent::kFirstScan : FilterEvent::kFiltered);
    if (k < 30) continue;  // Let the tracks settle (3 s).
    for (std::size_t i = 0; i < n; ++i) {
      if (!scans[k].is_valid(i) || !std::isfinite(background[i])) continue;
      const float d = scans[k].ranges_m[i] - background[i];
      if (std::abs(d) < 0.1F) {
        ++score.background;
        kept += removed(r.labels[i]) ? 0 : 1;
      } else if (d < -0.3F) {
        ++score.foreground;
        removed_fg += removed(r.labels[i]) ? 1 : 0;
      }
    }
  }
  score.preservation = static_cast<double>(kept) / static_cast<double>(score.background);
  score.rejection = static_cast<double>(removed_fg) / static_cast<double>(score.foreground);
  return score;
}

TEST(DynamicFilterOnRecordedScans, TheDefaultScaledToTheScannerRemovesWalkersAndKeepsTheRoom) {
  // dispel's default carried over to this scanner (0.35 deg, 10 Hz): N_min 4, L_d 4, L_s 25.
  const LaserScan first =
      testing::read_scan_csv(testing::data_path("leg_tracker/scans_250_to_650.csv")).front();
  const DynamicFilterConfig poi_config =
      scale_to_scanner(DynamicFilterConfig{}, first.angle_increment_rad, 0.1);
  ASSERT_EQ(poi_config.segmentation.min_points, 4);
  ASSERT_EQ(poi_config.classification.dynamic_weight_limit, 4);
  ASSERT_EQ(poi_config.classification.static_weight_limit, 25);
  const RecordedScore poi = score_recorded(poi_config);
  RecordProperty("poi_preservation", std::to_string(poi.preservation));
  RecordProperty("poi_rejection", std::to_string(poi.rejection));
  ASSERT_GT(poi.background, 50000);
  ASSERT_GT(poi.foreground, 4000);
  EXPECT_GE(poi.preservation, 0.99);  // Measured 1.000.
  EXPECT_GE(poi.rejection, 0.90);     // Measured 0.975.

  DynamicFilterConfig pog_config = poi_config;
  pog_config.classification.presumption = Presumption::kGuilt;
  const RecordedScore pog = score_recorded(pog_config);
  RecordProperty("pog_preservation", std::to_string(pog.preservation));
  RecordProperty("pog_rejection", std::to_string(pog.rejection));
  // Guilt removes every object until it is proven static, some of the room with it.
  EXPECT_GE(pog.rejection, 0.90);     // Measured 0.975.
  EXPECT_GE(pog.preservation, 0.95);  // Measured 0.986.
  EXPECT_LT(pog.preservation, poi.preservation);
}

TEST(DynamicFilterOnRecordedScans, UnscaledCountsOnACoarserSlowerScannerMissManyWalkers) {
  // Unscaled, N_min = 8 beams is wider than a leg beyond about 2.5 m on this scanner: the room is
  // kept but many walkers are missed. Hence scale_to_scanner().
  const RecordedScore raw = score_recorded(DynamicFilterConfig{});
  EXPECT_GE(raw.preservation, 0.99);
  EXPECT_LT(raw.rejection, 0.7);  // Measured 0.574, against 0.975 scaled.
}

TEST(DynamicFilterOnRecordedScans, TheThesisFilterKeepsTheRoomButItsMatchingLosesTheWalkers) {
  // The thesis's filter, scaled to the scanner: its nearest-neighbour matching (to where a track
  // was last seen, not where it is predicted) keeps hardly any walker long enough to collect L_d
  // scans of motion at 10 Hz; dispel's global matching alone gives the same parameters most of
  // them back.
  const LaserScan first =
      testing::read_scan_csv(testing::data_path("leg_tracker/scans_250_to_650.csv")).front();
  const DynamicFilterConfig thesis =
      scale_to_scanner(thesis_config(), first.angle_increment_rad, 0.1);
  const RecordedScore nearest = score_recorded(thesis);
  DynamicFilterConfig global = thesis;
  global.tracking.matching = Matching::kGlobal;
  const RecordedScore matched = score_recorded(global);
  RecordProperty("thesis_rejection", std::to_string(nearest.rejection));
  RecordProperty("thesis_global_rejection", std::to_string(matched.rejection));
  EXPECT_GE(nearest.preservation, 0.99);  // Measured 1.000.
  EXPECT_LT(nearest.rejection, 0.2);      // Measured 0.005.
  EXPECT_GE(matched.preservation, 0.99);  // Measured 1.000.
  EXPECT_GT(matched.rejection, 0.8);      // Measured 0.877.
}

TEST(ScaleToScanner, KeepsTheThesisScannerAndRejectsBadArguments) {
  const DynamicFilterConfig same = scale_to_scanner(thesis_config(), 275.0 / 1616.0 * kDeg, 0.05);
  EXPECT_EQ(same.segmentation.min_points, 8);
  EXPECT_EQ(same.classification.dynamic_weight_limit, 18);
  EXPECT_EQ(same.classification.static_weight_limit, 50);
  const DynamicFilterConfig fine = scale_to_scanner(thesis_config(), 0.25 * kDeg / 3.0, 0.025);
  EXPECT_EQ(fine.segmentation.min_points, 16);
  EXPECT_EQ(fine.classification.dynamic_weight_limit, 36);
  const DynamicFilterConfig dispel = scale_to_scanner(DynamicFilterConfig{}, 0.25 * kDeg / 3.0, 0.025);
  EXPECT_EQ(dispel.classification.dynamic_weight_limit, 16);
  EXPECT_EQ(dispel.classification.still_scans_to_static, 200);
  EXPECT_THROW(scale_to_scanner(DynamicFilterConfig{}, 0.0, 0.05), std::invalid_argument);
  EXPECT_THROW(scale_to_scanner(DynamicFilterConfig{}, 0.01, -1.0), std::invalid_argument);
}

// --- Bad input ----------------------------------------------------------------------------------

void expect_sane(const FilterResult& r, const LaserScan& in) {
  ASSERT_EQ(r.labels.size(), in.size());
  for (BeamLabel l : r.labels) EXPECT_LE(static_cast<int>(l), 4);
  ASSERT_EQ(r.filtered.size(), in.size());
  for (const TrackedObject& t : r.tracks) {
    EXPECT_TRUE(t.position_m.allFinite());
    EXPECT_TRUE(t.velocity_mps.allFinite());
  }
}

TEST(DynamicFilterInput, TimeGoingBackwardsResetsAndIsCounted) {
  Scenario s;
  s.walls = room(6.0, 5.0);
  s.movers = {walker({3.0, -2.0}, {0.0, 1.0})};
  DynamicFilter filter{DynamicFilterConfig{}};
  run(s, filter, 40);
  ASSERT_GT(filter.track_count(), 0u);
  Frame f = render(s, 1.0);  // Earlier than the last scan (1.95 s).
  const FilterResult r = filter.process(f.scan, f.pose);
  EXPECT_EQ(r.event, FilterEvent::kResetTimeBackwards);
  expect_sane(r, f.scan);
  EXPECT_EQ(filter.counters().events[static_cast<int>(FilterEvent::kResetTimeBackwards)], 1);
  // Tracks start again from this scan.
  for (const TrackedObject& t : r.tracks) EXPECT_EQ(t.age_scans, 1);
  f = render(s, 1.05);
  EXPECT_EQ(filter.process(f.scan, f.pose).event, FilterEvent::kFiltered);
}

TEST(DynamicFilterInput, RepeatedStampLabelsFromTheTracksWithoutChangingThem) {
  Scenario s;
  s.walls = room(6.0, 5.0);
  s.movers = {walker({3.0, -2.0}, {0.0, 1.2})};
  DynamicFilter filter{DynamicFilterConfig{}};
  run(s, filter, 60);
  const Frame f = render(s, 59 * kPeriod);  // The same stamp as the last scan.
  const std::size_t tracks = filter.track_count();
  const FilterResult r = filter.process(f.scan, f.pose);
  EXPECT_EQ(r.event, FilterEvent::kRepeatedStamp);
  expect_sane(r, f.scan);
  EXPECT_EQ(filter.track_count(), tracks);
  const ScanStats st = stats_of(f, r);
  EXPECT_GT(st.removed.at(1), st.beams.at(1) * 9 / 10);  // The walker is still removed.
  EXPECT_EQ(st.removed.count(0), 0u);
  EXPECT_EQ(filter.counters().events[static_cast<int>(FilterEvent::kRepeatedStamp)], 1);
}

TEST(DynamicFilterInput, PoseJumpResetsInsteadOfMakingTheWorldMove) {
  Scenario s;
  s.walls = room(6.0, 5.0);
  s.pillars = {{{2.0, 1.0}, 0.3}};
  DynamicFilter filter{DynamicFilterConfig{}};
  run(s, filter, 20);
  // Odometry jumps by 2 m (a reset of the fixed frame): the same scan, a different pose.
  Frame f = render(s, 20 * kPeriod);
  const FilterResult r = filter.process(f.scan, Pose2{2.0, 0.0, 0.0});
  EXPECT_EQ(r.event, FilterEvent::kResetPoseJump);
  expect_sane(r, f.scan);
  // Continuing in the new frame, nothing is ever dynamic.
  for (int k = 21; k < 80; ++k) {
    f = render(s, k * kPeriod);
    const FilterResult rk = filter.process(f.scan, Pose2{2.0, 0.0, 0.0});
    EXPECT_EQ(rk.removed_dynamic, 0);
  }
}

TEST(DynamicFilterInput, NonFinitePoseAndBadScansPassThroughUnchanged) {
  Scenario s;
  s.walls = room(6.0, 5.0);
  DynamicFilter filter{DynamicFilterConfig{}};
  run(s, filter, 10);
  Frame f = render(s, 10 * kPeriod);
  for (const Pose2& bad : {Pose2{std::nan(""), 0.0, 0.0}, Pose2{0.0, 0.0, INFINITY}}) {
    const FilterResult r = filter.process(f.scan, bad);
    EXPECT_EQ(r.event, FilterEvent::kRejectedPose);
    expect_sane(r, f.scan);
    for (std::size_t i = 0; i < f.scan.size(); ++i) {
      const float a = r.filtered.ranges_m[i];
      const float b = f.scan.ranges_m[i];
      EXPECT_TRUE(a == b || (std::isnan(a) && std::isnan(b)));
    }
  }
  LaserScan bad_scan = f.scan;
  bad_scan.angle_increment_rad = 0.0;
  bad_scan.stamp_s = 11 * kPeriod;
  const FilterResult r = filter.process(bad_scan, Pose2{});
  EXPECT_EQ(r.event, FilterEvent::kRejectedScan);
  expect_sane(r, bad_scan);
  for (BeamLabel l : r.labels) EXPECT_EQ(l, BeamLabel::kInvalid);
  LaserScan empty;
  empty.angle_increment_rad = 0.01;
  empty.range_max_m = 10.0F;
  EXPECT_EQ(filter.process(empty, Pose2{}).event, FilterEvent::kRejectedScan);
  const FilterCounters& c = filter.counters();
  EXPECT_EQ(c.events[static_cast<int>(FilterEvent::kRejectedPose)], 2);
  EXPECT_EQ(c.rejected_by_issue[static_cast<int>(ScanIssue::kNonPositiveIncrement)], 1);
  EXPECT_EQ(c.rejected_by_issue[static_cast<int>(ScanIssue::kEmpty)], 1);
  // After rejections the filter carries on as before.
  f = render(s, 12 * kPeriod);
  EXPECT_EQ(filter.process(f.scan, f.pose).event, FilterEvent::kFiltered);
}

TEST(DynamicFilterInput, NanRangesGiveValidLabels) {
  Scenario s;
  s.walls = room(6.0, 5.0);
  DynamicFilter filter{DynamicFilterConfig{}};
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < 30; ++k) {
    Frame f = render(s, k * kPeriod);
    for (float& r : f.scan.ranges_m) {
      const double p = u(rng);
      if (p < 0.2) r = std::numeric_limits<float>::quiet_NaN();
      if (p > 0.95) r = -std::numeric_limits<float>::infinity();
    }
    const FilterResult r = filter.process(f.scan, f.pose);
    expect_sane(r, f.scan);
    for (std::size_t i = 0; i < f.scan.size(); ++i) {
      if (!f.scan.is_valid(i)) {
        EXPECT_EQ(r.labels[i], BeamLabel::kInvalid);
      }
    }
  }
}

// --- dispel's default configuration: what it adds to the thesis's filter ------------------------

TEST(DynamicFilterDefaults, FragmentsBesideADynamicWalkerAreRemovedWithIt) {
  // A walker carrying a bag at arm's length: the bag covers fewer beams than N_min, so it is no
  // object at all, and the thesis keeps its beams.
  Scenario s;
  s.walls = room(10.0, 8.0);
  s.movers = {walker({4.0, -3.0}, {0.0, 1.0}),
              {[](double t) { return Eigen::Vector2d(4.0, -3.0 + t + 0.38); }, 0.03}};
  for (double fragment_distance : {0.0, 0.3}) {
    DynamicFilterConfig config = DynamicFilterConfig{};
    config.tracking.fragment_distance_m = fragment_distance;
    DynamicFilter filter{config};
    const auto st = run(s, filter, 100);
    EXPECT_EQ(static_removed(st), 0);
    const int walker_delay = scans_until_removed(st, 1);
    ASSERT_GE(walker_delay, 0);
    int bag_scans = 0, bag_removed_scans = 0;
    for (std::size_t k = 40; k < st.size(); ++k) {  // Once the walker is dynamic.
      const auto b = st[k].beams.find(2);
      if (b == st[k].beams.end()) continue;
      ASSERT_LT(b->second, config.segmentation.min_points);
      ++bag_scans;
      const auto r = st[k].removed.find(2);
      if (r != st[k].removed.end() && r->second == b->second) ++bag_removed_scans;
    }
    ASSERT_GT(bag_scans, 30);
    if (fragment_distance > 0.0) {
      EXPECT_GE(bag_removed_scans, 0.9 * bag_scans);
      EXPECT_GT(filter.counters().beams_removed_fragments, 0);
    } else {
      EXPECT_EQ(bag_removed_scans, 0);
      EXPECT_EQ(filter.counters().beams_removed_fragments, 0);
    }
  }
}

TEST(DynamicFilterDefaults, APillarAWalkerBrushesPastKeepsItsBeams) {
  // The walker touches the pillar in passing: for a few scans they are one object, which the
  // walker's dynamic track follows. The pillar has stood there all along, so its beams stay.
  Scenario s;
  s.walls = room(10.0, 8.0);
  s.pillars = {{{4.0, 0.0}, 0.3}};
  s.movers = {walker({3.5, -3.0}, {0.0, 1.0})};
  DynamicFilter filter{DynamicFilterConfig{}};
  const auto st = run(s, filter, 120);
  EXPECT_EQ(static_removed(st), 0);
  const int delay = scans_until_removed(st, 1);
  ASSERT_GE(delay, 0);
  EXPECT_LE(delay, 20);
}

TEST(DynamicFilterDefaults, SomeoneWalkingOutOfTheDarkIntoSpaceSeenEmptyIsRemovedAtOnce) {
  // In a hall whose walls are out of range (the thesis's 5.5 m cut) most beams return nothing;
  // they still show the floor to be empty, so a person who walks into view from beyond the range
  // stands in space seen free and is dynamic at once.
  Scenario s;
  s.geometry.range_max_m = 5.5F;
  s.walls = room(20.0, 15.0);  // Out of range: every beam without a return is +inf.
  s.movers = {walker({3.0, -7.0}, {0.0, 1.0})};
  DynamicFilterConfig with = DynamicFilterConfig{};
  DynamicFilterConfig without = with;
  without.free_space.no_return_is_free = false;
  DynamicFilter a{with}, b{without};
  const auto st_with = run(s, a, 160);
  const auto st_without = run(s, b, 160);
  EXPECT_EQ(static_removed(st_with), 0);
  const int fast = scans_until_removed(st_with, 1);
  const int slow = scans_until_removed(st_without, 1);
  ASSERT_GE(fast, 0);
  ASSERT_GE(slow, 0);
  // It must first walk 0.3 m into the range (6 scans): until then the cells behind it, which every
  // point needs around it, have not been seen.
  EXPECT_LE(fast, 10);
  EXPECT_GE(slow, fast + 6);
}

}  // namespace
}  // namespace dispel
