#pragma once
// Test support for the dynamic filter's tests (never installed): scripted scenes ray-cast at the
// thesis's 20 Hz, the per-scan statistics against the scene's truth, and the filter
// configuration the scenes that measure one mechanism use.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <vector>

#include "dispel/core/dynamic_filter.hpp"
#include "dispel/core/pose2.hpp"
#include "dispel/sim/raycast.hpp"

namespace dispel::scenes {

inline constexpr double kDeg = kPi / 180.0;
inline constexpr double kPeriod = 0.05;  // 20 Hz, the thesis's scanner.

inline sim::ScanGeometry thesis_geometry() {
  return {-137.5 * kDeg, 275.0 * kDeg / 1616.0, 1617, 0.05F, 40.0F};
}

// A scripted scene: static walls and pillars, moving circles (people), a moving sensor; and
// static things the scan plane reaches only at times (pieces: given the time and the sensor's
// pose, the segments seen then, static in the truth).
struct Mover {
  std::function<Eigen::Vector2d(double)> center;
  double radius_m;
};
struct Scenario {
  std::vector<sim::Segment> walls;
  std::function<std::vector<sim::Segment>(double, const Pose2&)> pieces;
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

inline Frame render(const Scenario& s, double t) {
  sim::World world;
  world.segments = s.walls;
  if (s.pieces) {
    for (const sim::Segment& piece : s.pieces(t, s.sensor(t))) world.segments.push_back(piece);
  }
  world.circles = s.pillars;
  for (const Mover& m : s.movers) world.circles.push_back({m.center(t), m.radius_m});
  Frame f;
  f.pose = s.sensor(t);
  std::vector<std::int32_t> hit;
  f.scan = sim::raycast(world, f.pose, s.geometry, &hit);
  f.scan.stamp_s = t;
  const auto first_mover = static_cast<std::int32_t>(world.segments.size() + s.pillars.size());
  f.truth.resize(hit.size());
  for (std::size_t i = 0; i < hit.size(); ++i) {
    f.truth[i] = hit[i] < 0 ? -1 : (hit[i] < first_mover ? 0 : hit[i] - first_mover + 1);
  }
  return f;
}

inline bool removed(BeamLabel l) { return l == BeamLabel::kDynamic || l == BeamLabel::kUnknown; }

// Per scan: how many beams of each truth class there were and how many were removed.
struct ScanStats {
  std::map<int, int> beams;
  std::map<int, int> removed;
  FilterEvent event;
};

inline ScanStats stats_of(const Frame& f, const FilterResult& r) {
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

inline std::vector<ScanStats> run(const Scenario& s, DynamicFilter& filter, int scans) {
  std::vector<ScanStats> out;
  for (int k = 0; k < scans; ++k) {
    const Frame f = render(s, k * kPeriod);
    out.push_back(stats_of(f, filter.process(f.scan, f.pose)));
  }
  return out;
}

// Scans from the first in which mover m is seen until all but `tolerance` of its beams are
// removed in every later scan where it shows at least `min_beams` beams. -1 if never.
inline int scans_until_removed(const std::vector<ScanStats>& st, int m, int min_beams = 8) {
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

inline std::int64_t static_removed(const std::vector<ScanStats>& st, int from = 0) {
  std::int64_t n = 0;
  for (std::size_t k = from; k < st.size(); ++k) {
    const auto r = st[k].removed.find(0);
    n += r == st[k].removed.end() ? 0 : r->second;
  }
  return n;
}

inline std::vector<sim::Segment> room(double half_x, double half_y) {
  return {{{-half_x, -half_y}, {half_x, -half_y}},
          {{half_x, -half_y}, {half_x, half_y}},
          {{half_x, half_y}, {-half_x, half_y}},
          {{-half_x, half_y}, {-half_x, -half_y}}};
}

inline Mover walker(Eigen::Vector2d start, Eigen::Vector2d velocity, double radius = 0.2) {
  return {[=](double t) { return Eigen::Vector2d(start + t * velocity); }, radius};
}

// The thesis's parameters with dispel's matching and evidence rules, without free space: what
// DynamicFilterConfig{} was before the type's defaults became dispel's. The scenes that measure
// one mechanism against the thesis's L_d = 18 (a box under POG, the companion rule, free space
// against none, track expiry) use it, so that the default's other rules do not hide it.
inline DynamicFilterConfig mechanism_config() {
  DynamicFilterConfig c = thesis_config();
  c.segmentation.gap_metric = GapMetric::kEuclidean;
  c.tracking.matching = Matching::kGlobal;
  c.tracking.inherit_on_split = true;
  c.classification.slow_scans_reduce_dynamic_weight = true;
  c.classification.still_scans_to_static = 100;
  return c;
}

// Which track id covers the most beams of mover m in this scan (0 if none).
inline std::uint64_t track_of_mover(const Frame& f, const FilterResult& r, int m) {
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

}  // namespace dispel::scenes
