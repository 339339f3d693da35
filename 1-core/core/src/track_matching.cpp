// The dynamic filter's step 4: objects of the new scan matched to remembered tracks (thesis
// section 3.2.3), and the tracks that unmatched objects split from.
#include <algorithm>
#include <cmath>
#include <numeric>

#include "dispel/core/assignment.hpp"
#include "dispel/core/dynamic_filter.hpp"

namespace dispel {
namespace {

// Find with path halving, for grouping objects and tracks that compete for each other.
std::int32_t find_root(std::vector<std::int32_t>& parent, std::int32_t i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

// A candidate pair of an object and a track, and how far apart they are.
struct Pair {
  double d;
  std::int32_t object, track;
};

// Takes the pairs nearest first, each object and each track once.
void take_nearest_first(std::vector<Pair>& pairs, std::vector<char>& track_taken,
                        std::vector<std::int32_t>& track_of_object) {
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) { return a.d < b.d; });
  for (const Pair& p : pairs) {
    if (track_of_object[p.object] >= 0 || track_taken[p.track]) continue;
    track_of_object[p.object] = p.track;
    track_taken[p.track] = 1;
  }
}

}  // namespace

void DynamicFilter::match(double stamp_s) {
  track_of_object_.assign(observations_.size(), -1);
  if (!tracks_.empty() && !observations_.empty()) {
    if (config_.tracking.matching == Matching::kNearestNeighbour) {
      associate_nearest();
    } else {
      associate_global(stamp_s);
      rescue_by_edges(stamp_s);
    }
  }
  find_split_parents(stamp_s);
}

// An object that matched no track but one of whose points lies within D of the same point of a
// track seen in this scan (a split: a person's legs parting, a wall cut by a shadow), or of a
// static track not seen lately (a surface reappearing in pieces), continues that track
// (tracking.inherit_on_split). Found before the tracks move on.
void DynamicFilter::find_split_parents(double stamp_s) {
  parent_of_object_.assign(observations_.size(), -1);
  if (!config_.tracking.inherit_on_split) return;
  std::vector<char> seen(tracks_.size(), 0);
  for (std::int32_t t : track_of_object_) {
    if (t >= 0) seen[t] = 1;
  }
  const double d_max = config_.tracking.match_distance_m;
  for (std::size_t i = 0; i < observations_.size(); ++i) {
    if (track_of_object_[i] >= 0) continue;
    double best = d_max;
    for (std::size_t t = 0; t < tracks_.size(); ++t) {
      if (!seen[t] && tracks_[t].cls.object_class != ObjectClass::kStatic) continue;
      const double dt = stamp_s - tracks_[t].last_seen_s;
      for (int k = 0; k < 3; ++k) {
        if (!observations_[i].trusted[k] && k != kCentroid) continue;
        const double d =
            (observations_[i].points[k] - tracks_[t].kf[k].predicted_position(dt)).norm();
        if (d <= best) {
          best = d;
          parent_of_object_[i] = static_cast<std::int32_t>(t);
        }
      }
    }
  }
}

// The thesis's matching: centroid to the track's last seen centroid, nearest pairs first.
void DynamicFilter::associate_nearest() {
  const double d_max = config_.tracking.match_distance_m;
  std::vector<Pair> pairs;
  for (std::size_t i = 0; i < observations_.size(); ++i) {
    for (std::size_t t = 0; t < tracks_.size(); ++t) {
      const double d =
          (observations_[i].points[kCentroid] - tracks_[t].kf[kCentroid].position()).norm();
      if (d <= d_max) {
        pairs.push_back({d, static_cast<std::int32_t>(i), static_cast<std::int32_t>(t)});
      }
    }
  }
  std::vector<char> track_taken(tracks_.size(), 0);
  take_nearest_first(pairs, track_taken, track_of_object_);
}

// Second chance for objects the global matching left alone: a surface that reappears from behind
// an occluder, or shrinks to a fragment, may have moved its centroid far while one of its edges
// stayed put. Such an object continues an unmatched track when one of its reliable edges lies
// within D of the same edge of the track (predicted), nearest pairs first.
void DynamicFilter::rescue_by_edges(double stamp_s) {
  const double d_max = config_.tracking.match_distance_m;
  std::vector<char> taken(tracks_.size(), 0);
  for (std::int32_t t : track_of_object_) {
    if (t >= 0) taken[t] = 1;
  }
  std::vector<Pair> pairs;
  for (std::size_t i = 0; i < observations_.size(); ++i) {
    if (track_of_object_[i] >= 0) continue;
    const Observation& obs = observations_[i];
    if (obs.ambiguous) continue;
    for (std::size_t t = 0; t < tracks_.size(); ++t) {
      if (taken[t]) continue;
      const Track& track = tracks_[t];
      if (!similar_extent(obs, track)) continue;
      const double dt = stamp_s - track.last_seen_s;
      double best = d_max;
      bool found = false;
      for (int k : {kFirst, kLast}) {
        if (!obs.trusted[k] || !track.trusted[k]) continue;
        const double d = (obs.points[k] - track.kf[k].predicted_position(dt)).norm();
        if (d <= best) {
          best = d;
          found = true;
        }
      }
      if (found) {
        pairs.push_back({best, static_cast<std::int32_t>(i), static_cast<std::int32_t>(t)});
      }
    }
  }
  take_nearest_first(pairs, taken, track_of_object_);
}

// Global matching: gate on the predicted centroid, cost = mean distance of the three points
// (an untrusted edge counts with the centroid's distance), solved exactly per group of objects
// and tracks that compete (most groups are one object and one track).
void DynamicFilter::associate_global(double stamp_s) {
  const double d_max = config_.tracking.match_distance_m;
  const auto n_obj = static_cast<std::int32_t>(observations_.size());
  const auto n_trk = static_cast<std::int32_t>(tracks_.size());
  struct Candidate {
    std::int32_t object, track;
    double cost;
  };
  std::vector<Candidate> pairs;
  component_.resize(n_obj + n_trk);
  std::iota(component_.begin(), component_.end(), 0);
  std::vector<std::array<Eigen::Vector2d, 3>> predicted(n_trk);
  std::vector<double> gate(n_trk);
  for (std::int32_t t = 0; t < n_trk; ++t) {
    const double dt = stamp_s - tracks_[t].last_seen_s;
    for (int k = 0; k < 3; ++k) predicted[t][k] = tracks_[t].kf[k].predicted_position(dt);
    const double scaled = d_max * dt / config_.velocity.nominal_scan_period_s;
    gate[t] = std::max(d_max, std::min(scaled, config_.tracking.max_gate_m));
  }
  for (std::int32_t i = 0; i < n_obj; ++i) {
    const Observation& obs = observations_[i];
    for (std::int32_t t = 0; t < n_trk; ++t) {
      const double dc = (obs.points[kCentroid] - predicted[t][kCentroid]).norm();
      if (dc > gate[t]) continue;
      if (!similar_extent(obs, tracks_[t])) continue;
      double cost = dc;
      for (int k : {kFirst, kLast}) {
        cost += obs.trusted[k] ? (obs.points[k] - predicted[t][k]).norm() : dc;
      }
      pairs.push_back({i, t, cost / 3.0});
      const std::int32_t a = find_root(component_, i);
      const std::int32_t b = find_root(component_, n_obj + t);
      if (a != b) component_[a] = b;
    }
  }
  if (pairs.empty()) return;
  // Group pairs by component; solve each group.
  std::sort(pairs.begin(), pairs.end(), [&](const Candidate& a, const Candidate& b) {
    return find_root(component_, a.object) < find_root(component_, b.object);
  });
  // Leaving an object unmatched costs more than any gated pair, so every object that can be matched
  // is; among the ways to do so the cheapest wins.
  const double unmatched_cost = 2.0 * *std::max_element(gate.begin(), gate.end());
  const double forbidden = 1e6;
  std::vector<std::int32_t> objs;
  std::vector<std::int32_t> trks;
  for (std::size_t begin = 0; begin < pairs.size();) {
    const std::int32_t root = find_root(component_, pairs[begin].object);
    std::size_t end = begin;
    while (end < pairs.size() && find_root(component_, pairs[end].object) == root) ++end;
    if (end - begin == 1) {  // One object, one track, no competition.
      track_of_object_[pairs[begin].object] = pairs[begin].track;
      begin = end;
      continue;
    }
    objs.clear();
    trks.clear();
    for (std::size_t p = begin; p < end; ++p) {
      objs.push_back(pairs[p].object);
      trks.push_back(pairs[p].track);
    }
    std::sort(objs.begin(), objs.end());
    objs.erase(std::unique(objs.begin(), objs.end()), objs.end());
    std::sort(trks.begin(), trks.end());
    trks.erase(std::unique(trks.begin(), trks.end()), trks.end());
    // Rows: objects; columns: tracks (a track no object takes costs nothing), then one dummy
    // column per object (object unmatched, cost unmatched_cost). Rows <= columns: the
    // assignment's cost grows with the objects squared, not with the tracks cubed (a warehouse
    // aisle kept 100 tracks in reach of 20 objects: 1.4 ms for such a scan with a square matrix).
    const auto no = static_cast<int>(objs.size());
    const auto nt = static_cast<int>(trks.size());
    const int n = no + nt;
    cost_.resize(static_cast<std::size_t>(no) * n);
    for (int r = 0; r < no; ++r) {
      for (int c = 0; c < n; ++c) cost_[r * n + c] = c < nt ? forbidden : unmatched_cost;
    }
    for (std::size_t p = begin; p < end; ++p) {
      const int r = static_cast<int>(std::lower_bound(objs.begin(), objs.end(), pairs[p].object) -
                                     objs.begin());
      const int c = static_cast<int>(std::lower_bound(trks.begin(), trks.end(), pairs[p].track) -
                                     trks.begin());
      cost_[r * n + c] = pairs[p].cost;
    }
    const std::vector<int> col = min_cost_assignment(cost_, no, n);
    for (int r = 0; r < no; ++r) {
      if (col[r] < nt && cost_[r * n + col[r]] < forbidden)
        track_of_object_[objs[r]] = trks[col[r]];
    }
    begin = end;
  }
}

bool DynamicFilter::similar_extent(const Observation& obs, const Track& track) const {
  const double change = std::abs(obs.extent_m - track.extent_m);
  return change <= std::max(config_.tracking.max_extent_change_m,
                            0.5 * std::max(obs.extent_m, track.extent_m));
}

}  // namespace dispel
