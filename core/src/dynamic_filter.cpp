#include "dispel/core/dynamic_filter.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "dispel/core/assignment.hpp"
#include "dispel/core/invalid_field.hpp"

namespace dispel {
namespace {

constexpr auto reject = reject_field;

bool finite_pose(const Pose2& p) {
  return std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.yaw_rad);
}

// Whether an edge is the object's own outline (thesis section 3.2.2 and Figure 3.6).
bool edge_trusted(EdgeNeighbour n) {
  return n == EdgeNeighbour::kFarther || n == EdgeNeighbour::kInvalid;
}

bool edge_at_view_limit(EdgeNeighbour n) {
  return n == EdgeNeighbour::kFieldOfViewEnd || n == EdgeNeighbour::kMaskedSector;
}

// Find with path halving, for grouping objects and tracks that compete for each other.
std::int32_t find_root(std::vector<std::int32_t>& parent, std::int32_t i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

}  // namespace

const char* filter_event_name(FilterEvent event) {
  switch (event) {
    case FilterEvent::kFiltered:
      return "filtered";
    case FilterEvent::kFirstScan:
      return "first_scan";
    case FilterEvent::kRejectedScan:
      return "rejected_scan";
    case FilterEvent::kRejectedPose:
      return "rejected_pose";
    case FilterEvent::kRepeatedStamp:
      return "repeated_stamp";
    case FilterEvent::kResetTimeBackwards:
      return "reset_time_backwards";
    case FilterEvent::kResetTimeGap:
      return "reset_time_gap";
    case FilterEvent::kResetPoseJump:
      return "reset_pose_jump";
  }
  return "unknown";
}

void TrackingConfig::validate() const {
  if (!std::isfinite(match_distance_m) || !(match_distance_m > 0.0)) {
    reject("tracking.match_distance_m", match_distance_m, "a finite number > 0");
  }
  if (matching != Matching::kGlobal && matching != Matching::kNearestNeighbour) {
    reject("tracking.matching", static_cast<int>(matching), "global or nearest_neighbour");
  }
  if (max_missed_scans < 0) reject("tracking.max_missed_scans", max_missed_scans, ">= 0");
  if (!std::isfinite(companion_distance_m) || companion_distance_m < 0.0) {
    reject("tracking.companion_distance_m", companion_distance_m, "a finite number >= 0");
  }
  if (!std::isfinite(companion_speed_difference_mps) || companion_speed_difference_mps < 0.0) {
    reject("tracking.companion_speed_difference_mps", companion_speed_difference_mps,
           "a finite number >= 0");
  }
  if (!std::isfinite(fragment_distance_m) || fragment_distance_m < 0.0) {
    reject("tracking.fragment_distance_m", fragment_distance_m, "a finite number >= 0");
  }
  if (!std::isfinite(max_gate_m) || max_gate_m < match_distance_m) {
    reject("tracking.max_gate_m", max_gate_m, "finite and >= match_distance_m");
  }
  if (!(max_extent_change_m > 0.0)) {
    reject("tracking.max_extent_change_m", max_extent_change_m, "> 0");
  }
}

void DynamicFilterConfig::validate() const {
  segmentation.validate();
  tracking.validate();
  velocity.validate();
  classification.validate();
  free_space.validate();
  if (!(max_time_gap_s > 0.0)) reject("max_time_gap_s", max_time_gap_s, "> 0");
  if (!(max_pose_jump_m > 0.0)) reject("max_pose_jump_m", max_pose_jump_m, "> 0");
  if (!(max_pose_jump_rad > 0.0)) reject("max_pose_jump_rad", max_pose_jump_rad, "> 0");
}

DynamicFilterConfig thesis_config() { return DynamicFilterConfig{}; }

DynamicFilterConfig default_config() {
  DynamicFilterConfig c;
  c.velocity.measurement_variance_m2 = 0.1;
  c.velocity.position_variance_m2 = 0.001;
  c.classification.dynamic_weight_limit = 8;
  c.tracking.max_extent_change_m = 0.2;
  c.tracking.max_missed_scans = 40;
  c.tracking.max_gate_m = 2.0;
  c.tracking.companion_distance_m = 0.6;
  c.tracking.fragment_distance_m = 0.3;
  c.free_space.enabled = true;
  c.free_space.neighbourhood_cells = 3;
  c.free_space.memory_s = 30.0;
  return c;
}

DynamicFilterConfig scale_to_scanner(DynamicFilterConfig config, double angle_increment_rad,
                                     double scan_period_s) {
  if (!std::isfinite(angle_increment_rad) || !(angle_increment_rad > 0.0)) {
    reject("angle_increment_rad", angle_increment_rad, "a finite number > 0");
  }
  if (!std::isfinite(scan_period_s) || !(scan_period_s > 0.0)) {
    reject("scan_period_s", scan_period_s, "a finite number > 0");
  }
  constexpr double kThesisIncrementRad = 275.0 / 1616.0 * kPi / 180.0;
  constexpr double kThesisPeriodS = 0.05;
  const double beams = kThesisIncrementRad / angle_increment_rad;
  const double scans = kThesisPeriodS / scan_period_s;
  ClassificationConfig& c = config.classification;
  config.segmentation.min_points =
      std::max(3, static_cast<int>(std::lround(config.segmentation.min_points * beams)));
  c.dynamic_weight_limit =
      std::max(1, static_cast<int>(std::lround(c.dynamic_weight_limit * scans)));
  c.static_weight_limit = std::max(1, static_cast<int>(std::lround(c.static_weight_limit * scans)));
  if (c.still_scans_to_static > 0) {
    c.still_scans_to_static =
        std::max(1, static_cast<int>(std::lround(c.still_scans_to_static * scans)));
  }
  return config;
}

DynamicFilter::DynamicFilter(DynamicFilterConfig config)
    : config_((config.validate(), std::move(config))),
      segmenter_(config_.segmentation),
      free_space_(config_.free_space) {}

void DynamicFilter::reset() {
  counters_.tracks_dropped += static_cast<std::int64_t>(tracks_.size());
  tracks_.clear();
  free_space_.clear();
  have_previous_ = false;
}

void DynamicFilter::pass_through(const LaserScan& scan, FilterEvent event, FilterResult& out) {
  out.event = event;
  out.filtered = scan;
  out.segmentation = Segmentation{};
  out.segmentation.issue = check_scan(scan);
  const bool usable_limits = out.segmentation.issue == ScanIssue::kNone;
  out.labels.resize(scan.size());
  for (std::size_t i = 0; i < scan.size(); ++i) {
    out.labels[i] = usable_limits && scan.is_valid(i) ? BeamLabel::kNoObject : BeamLabel::kInvalid;
  }
  for (Track& t : tracks_) t.object_index = -1;
  object_class_label_.clear();
  write_output(out);
  ++counters_.events[static_cast<std::size_t>(event)];
}

void DynamicFilter::process(const LaserScan& scan, const Pose2& sensor_pose, FilterResult& out) {
  ++counters_.scans;
  out.removed_dynamic = out.removed_unknown = 0;
  const ScanIssue issue = check_scan(scan);
  if (issue != ScanIssue::kNone) {
    ++counters_.rejected_by_issue[static_cast<std::size_t>(issue)];
    pass_through(scan, FilterEvent::kRejectedScan, out);
    return;
  }
  if (!finite_pose(sensor_pose)) {
    pass_through(scan, FilterEvent::kRejectedPose, out);
    return;
  }

  FilterEvent event = FilterEvent::kFiltered;
  bool update = true;
  if (!have_previous_) {
    event = FilterEvent::kFirstScan;
  } else {
    const double dt = scan.stamp_s - previous_stamp_s_;
    const double moved = (sensor_pose.translation() - previous_pose_.translation()).norm();
    const double turned = std::abs(wrap_angle(sensor_pose.yaw_rad - previous_pose_.yaw_rad));
    if (dt < 0.0) {
      reset();
      event = FilterEvent::kResetTimeBackwards;
    } else if (dt == 0.0) {
      event = FilterEvent::kRepeatedStamp;
      update = false;
    } else if (dt > config_.max_time_gap_s) {
      reset();
      event = FilterEvent::kResetTimeGap;
    } else if (moved > config_.max_pose_jump_m || turned > config_.max_pose_jump_rad) {
      reset();
      event = FilterEvent::kResetPoseJump;
    }
  }

  // Segment, and move each object's three points into the fixed frame.
  segmenter_.segment(scan, out.segmentation);
  const std::vector<ScanObject>& objects = out.segmentation.objects;
  observations_.resize(objects.size());
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const ScanObject& o = objects[i];
    Observation& obs = observations_[i];
    obs.points[kFirst] = sensor_pose.apply(o.first_point_m);
    obs.points[kLast] = sensor_pose.apply(o.last_point_m);
    obs.points[kCentroid] = sensor_pose.apply(o.centroid_m);
    // An edge beside a beam with no return, at the end of the scanner's range, may continue
    // beyond it: as the robot moves, it slides along the object like a view limit.
    const double range_edge =
        static_cast<double>(scan.range_max_m) - 2.0 * config_.segmentation.cluster_gap_m;
    const auto at_range_limit = [&](EdgeNeighbour n, const Eigen::Vector2d& p) {
      return n == EdgeNeighbour::kInvalid && p.norm() > range_edge;
    };
    obs.trusted[kFirst] =
        edge_trusted(o.before_first) && !at_range_limit(o.before_first, o.first_point_m);
    obs.trusted[kLast] =
        edge_trusted(o.after_last) && !at_range_limit(o.after_last, o.last_point_m);
    // A hidden part of the outline shifts the centroid as well.
    obs.trusted[kCentroid] = obs.trusted[kFirst] && obs.trusted[kLast];
    obs.ambiguous = edge_at_view_limit(o.before_first) || edge_at_view_limit(o.after_last);
    obs.extent_m = (o.last_point_m - o.first_point_m).norm();
    obs.point_count = o.point_count;
  }

  associate(scan.stamp_s, track_of_object_);

  // The class each object is labelled with.
  object_class_label_.resize(objects.size());
  const ClassState fresh = initial_class_state(config_.classification);
  if (update) {
    // Find the parents of split objects before the tracks move on.
    std::vector<std::int32_t> parent(objects.size(), -1);
    if (config_.tracking.inherit_on_split) {
      std::vector<char> seen(tracks_.size(), 0);
      for (std::int32_t t : track_of_object_) {
        if (t >= 0) seen[t] = 1;
      }
      const double d_max = config_.tracking.match_distance_m;
      for (std::size_t i = 0; i < objects.size(); ++i) {
        if (track_of_object_[i] >= 0) continue;
        double best = d_max;
        for (std::size_t t = 0; t < tracks_.size(); ++t) {
          // A track seen in this scan may have split; one unseen for a while may be a static
          // surface that reappears in pieces.
          if (!seen[t] && tracks_[t].cls.object_class != ObjectClass::kStatic) continue;
          const double dt = scan.stamp_s - tracks_[t].last_seen_s;
          for (int k = 0; k < 3; ++k) {
            if (!observations_[i].trusted[k] && k != kCentroid) continue;
            const double d =
                (observations_[i].points[k] - tracks_[t].kf[k].predicted_position(dt)).norm();
            if (d <= best) {
              best = d;
              parent[i] = static_cast<std::int32_t>(t);
            }
          }
        }
      }
    }
    for (Track& t : tracks_) t.object_index = -1;
    for (std::size_t i = 0; i < objects.size(); ++i) {
      const std::int32_t t = track_of_object_[i];
      if (t < 0) continue;
      update_track(tracks_[t], observations_[i], scan.stamp_s);
      tracks_[t].object_index = static_cast<std::int32_t>(i);
    }
    for (Track& t : tracks_) {
      if (t.object_index < 0) {
        ++t.missed_scans;
        ++t.age_scans;
      }
    }
    for (std::size_t i = 0; i < objects.size(); ++i) {
      if (track_of_object_[i] >= 0) continue;
      Track track = new_track(observations_[i], scan.stamp_s, static_cast<std::int32_t>(i));
      if (parent[i] >= 0) {
        const Track& from = tracks_[parent[i]];
        track.cls = from.cls;
        track.age_scans = from.age_scans;  // A continuation: as old as what it came from.
        for (PointVelocityFilter& kf : track.kf) kf.set_velocity(from.kf[kCentroid].velocity());
        track.speed_mps = from.speed_mps;
      }
      track_of_object_[i] = static_cast<std::int32_t>(tracks_.size());
      tracks_.push_back(std::move(track));
    }
    if (config_.free_space.enabled) {
      mark_objects_in_free_space(scan, sensor_pose, out.segmentation);
      free_space_.add_scan(scan, sensor_pose);
    }
    spread_to_companions();
    for (std::size_t i = 0; i < objects.size(); ++i) {
      object_class_label_[i] =
          static_cast<std::int32_t>(tracks_[track_of_object_[i]].cls.object_class);
    }
    // Forget tracks unseen for too long (after labelling: indices above stay valid until now).
    const auto expired = [&](const Track& t) {
      return t.missed_scans > config_.tracking.max_missed_scans;
    };
    const auto before = tracks_.size();
    tracks_.erase(std::remove_if(tracks_.begin(), tracks_.end(), expired), tracks_.end());
    counters_.tracks_dropped += static_cast<std::int64_t>(before - tracks_.size());
    previous_stamp_s_ = scan.stamp_s;
    previous_pose_ = sensor_pose;
    have_previous_ = true;
  } else {
    // Repeated stamp: no time has passed, so nothing can be learned; label from the tracks.
    for (Track& t : tracks_) t.object_index = -1;
    for (std::size_t i = 0; i < objects.size(); ++i) {
      const std::int32_t t = track_of_object_[i];
      object_class_label_[i] =
          static_cast<std::int32_t>(t >= 0 ? tracks_[t].cls.object_class : fresh.object_class);
      if (t >= 0) tracks_[t].object_index = static_cast<std::int32_t>(i);
    }
  }

  out.event = event;
  out.filtered = scan;
  out.labels.resize(scan.size());
  const std::vector<std::int32_t>& seg_labels = out.segmentation.beam_labels;
  const bool check_occupied = config_.free_space.enabled && config_.free_space.keep_long_occupied;
  const bool absorb_fragments = update && config_.tracking.fragment_distance_m > 0.0;
  const double slow_mps = 2.0 * config_.classification.speed_limit_mps;
  for (std::size_t b = 0; b < scan.size(); ++b) {
    const std::int32_t l = seg_labels[b];
    BeamLabel label = BeamLabel::kInvalid;
    if (l >= 0) {
      switch (static_cast<ObjectClass>(object_class_label_[l])) {
        case ObjectClass::kStatic:
          label = BeamLabel::kStatic;
          break;
        case ObjectClass::kDynamic:
          label = BeamLabel::kDynamic;
          break;
        case ObjectClass::kUnknown:
          label = BeamLabel::kUnknown;
          break;
      }
    } else if (l == kLabelNoise) {
      label = BeamLabel::kNoObject;
    }
    if (label == BeamLabel::kStatic || label == BeamLabel::kInvalid) {
      out.labels[b] = label;
      continue;
    }
    const double r = scan.ranges_m[b];
    const double bearing = scan.bearing_rad(b);
    const Eigen::Vector2d point =
        sensor_pose.apply(Eigen::Vector2d(r * std::cos(bearing), r * std::sin(bearing)));
    if (label == BeamLabel::kNoObject) {
      if (absorb_fragments && near_dynamic_track(point, scan.stamp_s) &&
          !(check_occupied &&
            free_space_.hit_balance(point) >= config_.free_space.max_recent_hits)) {
        label = BeamLabel::kDynamic;
        ++counters_.beams_removed_fragments;
      }
    } else if (check_occupied && update &&
               (tracks_[track_of_object_[l]].speed_mps <= slow_mps
                    ? free_space_.hit_balance(point) >= config_.free_space.max_recent_hits
                    : free_space_.occupied_scans(point) >=
                          config_.free_space.long_occupied_scans)) {
      label = BeamLabel::kStatic;
      ++counters_.beams_kept_long_occupied;
    }
    if (label == BeamLabel::kDynamic) {
      ++out.removed_dynamic;
      out.filtered.ranges_m[b] = std::numeric_limits<float>::quiet_NaN();
    } else if (label == BeamLabel::kUnknown) {
      ++out.removed_unknown;
      out.filtered.ranges_m[b] = std::numeric_limits<float>::quiet_NaN();
    }
    out.labels[b] = label;
  }
  counters_.beams_removed_dynamic += out.removed_dynamic;
  counters_.beams_removed_unknown += out.removed_unknown;
  write_output(out);
  ++counters_.events[static_cast<std::size_t>(event)];
}

// Whether a point lies within fragment_distance_m of the outline (edge to edge, predicted to now)
// of a dynamic track seen in this scan or missed for a few scans at most.
bool DynamicFilter::near_dynamic_track(const Eigen::Vector2d& point_m, double stamp_s) const {
  constexpr std::int32_t kMaxMissed = 2;
  const double limit = config_.tracking.fragment_distance_m;
  for (const Track& t : tracks_) {
    if (t.cls.object_class != ObjectClass::kDynamic || t.missed_scans > kMaxMissed) continue;
    const double dt = stamp_s - t.last_seen_s;
    const Eigen::Vector2d a = t.kf[kFirst].predicted_position(dt);
    const Eigen::Vector2d ab = t.kf[kLast].predicted_position(dt) - a;
    const double len2 = ab.squaredNorm();
    const double u = len2 > 0.0 ? std::clamp((point_m - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    if ((point_m - (a + u * ab)).norm() <= limit) return true;
  }
  return false;
}

bool DynamicFilter::similar_extent(const Observation& obs, const Track& track) const {
  const double change = std::abs(obs.extent_m - track.extent_m);
  return change <= std::max(config_.tracking.max_extent_change_m,
                            0.5 * std::max(obs.extent_m, track.extent_m));
}

constexpr std::int32_t kFreeSpaceMaxAge = 10;

// An object most of whose points stand where beams passed freely before (and not as far as the
// map knows, hit since) has moved there: it is dynamic at once, unless it is too large to be.
void DynamicFilter::mark_objects_in_free_space(const LaserScan& scan, const Pose2& sensor_pose,
                                               const Segmentation& segmentation) {
  std::vector<std::int32_t> in_free(segmentation.objects.size(), 0);
  for (std::size_t b = 0; b < scan.size(); ++b) {
    const std::int32_t o = segmentation.beam_labels[b];
    if (o < 0) continue;
    const double r = scan.ranges_m[b];
    const double bearing = scan.bearing_rad(b);
    if (free_space_.known_free(sensor_pose.apply({r * std::cos(bearing), r * std::sin(bearing)}))) {
      ++in_free[static_cast<std::size_t>(o)];
    }
  }
  for (std::size_t i = 0; i < segmentation.objects.size(); ++i) {
    const ScanObject& o = segmentation.objects[i];
    if (static_cast<double>(in_free[i]) < config_.free_space.min_object_share * o.point_count)
      continue;
    if ((o.last_point_m - o.first_point_m).norm() > config_.classification.max_dynamic_extent_m) {
      continue;
    }
    Track& t = tracks_[static_cast<std::size_t>(track_of_object_[i])];
    // A track followed for a while without any sign of motion is known structure seen from a new
    // side (or merged with someone next to it), not something that just appeared.
    if (t.age_scans > kFreeSpaceMaxAge) continue;
    if (t.cls.object_class != ObjectClass::kDynamic) {
      t.cls.object_class = ObjectClass::kDynamic;
      t.cls.dynamic_weight =
          std::max(t.cls.dynamic_weight, config_.classification.dynamic_weight_limit);
      t.cls.still_scans = 0;
    }
  }
}

// Two tracks seen in this scan that are close together and move alike are parts of one thing
// (the two legs of a walker, tracked apart when one is behind the other): once one is dynamic,
// so is the other, instead of it collecting L_d scans of its own.
void DynamicFilter::spread_to_companions() {
  const TrackingConfig& tc = config_.tracking;
  if (!(tc.companion_distance_m > 0.0)) return;
  const double limit = config_.classification.speed_limit_mps;
  for (const Track& a : tracks_) {
    if (a.object_index < 0 || a.cls.object_class != ObjectClass::kDynamic) continue;
    const Eigen::Vector2d pa = a.kf[kCentroid].position();
    const Eigen::Vector2d va = a.kf[kCentroid].velocity();
    for (Track& b : tracks_) {
      if (b.object_index < 0 || b.cls.object_class == ObjectClass::kDynamic) continue;
      const Eigen::Vector2d vb = b.kf[kCentroid].velocity();
      if (b.speed_mps > 3.0 * limit && b.cls.dynamic_weight > 0 &&
          (b.kf[kCentroid].position() - pa).norm() <= tc.companion_distance_m &&
          (vb - va).norm() <= tc.companion_speed_difference_mps) {
        b.cls.object_class = ObjectClass::kDynamic;
        b.cls.dynamic_weight = std::max(b.cls.dynamic_weight, a.cls.dynamic_weight);
        b.cls.still_scans = 0;
      }
    }
  }
}

void DynamicFilter::associate(double stamp_s, std::vector<std::int32_t>& track_of_object) {
  track_of_object.assign(observations_.size(), -1);
  if (tracks_.empty() || observations_.empty()) return;
  if (config_.tracking.matching == Matching::kNearestNeighbour) {
    associate_nearest(track_of_object);
  } else {
    associate_global(stamp_s, track_of_object);
    rescue_by_edges(stamp_s, track_of_object);
  }
}

// Second chance for objects the global matching left alone: a surface that reappears from behind
// an occluder, or shrinks to a fragment, may have moved its centroid far while one of its edges
// stayed put. Such an object continues an unmatched track when one of its reliable edges lies
// within D of the same edge of the track (predicted), nearest pairs first.
void DynamicFilter::rescue_by_edges(double stamp_s, std::vector<std::int32_t>& track_of_object) {
  const double d_max = config_.tracking.match_distance_m;
  std::vector<char> taken(tracks_.size(), 0);
  for (std::int32_t t : track_of_object) {
    if (t >= 0) taken[t] = 1;
  }
  struct Pair {
    double d;
    std::int32_t object, track;
  };
  std::vector<Pair> pairs;
  for (std::size_t i = 0; i < observations_.size(); ++i) {
    if (track_of_object[i] >= 0) continue;
    const Observation& obs = observations_[i];
    for (std::size_t t = 0; t < tracks_.size(); ++t) {
      if (taken[t]) continue;
      const Track& track = tracks_[t];
      if (!similar_extent(obs, track)) continue;
      const double dt = stamp_s - track.last_seen_s;
      double best = d_max;
      bool found = false;
      for (int k : {kFirst, kLast}) {
        if (!obs.trusted[k] || !track.trusted[k] || obs.ambiguous) continue;
        const double d = (obs.points[k] - track.kf[k].predicted_position(dt)).norm();
        if (d <= best) {
          best = d;
          found = true;
        }
      }
      if (found)
        pairs.push_back({best, static_cast<std::int32_t>(i), static_cast<std::int32_t>(t)});
    }
  }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) { return a.d < b.d; });
  for (const Pair& p : pairs) {
    if (track_of_object[p.object] >= 0 || taken[p.track]) continue;
    track_of_object[p.object] = p.track;
    taken[p.track] = 1;
  }
}

// The thesis's matching: centroid to the track's last seen centroid, nearest pairs first.
void DynamicFilter::associate_nearest(std::vector<std::int32_t>& track_of_object) {
  const double d_max = config_.tracking.match_distance_m;
  struct Pair {
    double d;
    std::int32_t object, track;
  };
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
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) { return a.d < b.d; });
  std::vector<char> track_taken(tracks_.size(), 0);
  for (const Pair& p : pairs) {
    if (track_of_object[p.object] >= 0 || track_taken[p.track]) continue;
    track_of_object[p.object] = p.track;
    track_taken[p.track] = 1;
  }
}

// Global matching: gate on the predicted centroid, cost = mean distance of the three points
// (an untrusted edge counts with the centroid's distance), solved exactly per group of objects
// and tracks that compete (most groups are one object and one track).
void DynamicFilter::associate_global(double stamp_s, std::vector<std::int32_t>& track_of_object) {
  const double d_max = config_.tracking.match_distance_m;
  const auto n_obj = static_cast<std::int32_t>(observations_.size());
  const auto n_trk = static_cast<std::int32_t>(tracks_.size());
  struct Pair {
    std::int32_t object, track;
    double cost;
  };
  std::vector<Pair> pairs;
  component_.resize(n_obj + n_trk);
  std::iota(component_.begin(), component_.end(), 0);
  std::vector<std::array<Eigen::Vector2d, 3>> predicted(n_trk);
  for (std::int32_t t = 0; t < n_trk; ++t) {
    const double dt = stamp_s - tracks_[t].last_seen_s;
    for (int k = 0; k < 3; ++k) predicted[t][k] = tracks_[t].kf[k].predicted_position(dt);
  }
  std::vector<double> gate(n_trk);
  for (std::int32_t t = 0; t < n_trk; ++t) {
    const double dt = stamp_s - tracks_[t].last_seen_s;
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
  std::sort(pairs.begin(), pairs.end(), [&](const Pair& a, const Pair& b) {
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
      track_of_object[pairs[begin].object] = pairs[begin].track;
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
    // Rows: objects then one dummy row per track (track unmatched, cost 0); columns: tracks then
    // one dummy column per object (object unmatched, cost unmatched_cost).
    const auto no = static_cast<int>(objs.size());
    const auto nt = static_cast<int>(trks.size());
    const int n = no + nt;
    cost_.assign(static_cast<std::size_t>(n) * n, 0.0);
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
    const std::vector<int> col = min_cost_assignment(cost_, n);
    for (int r = 0; r < no; ++r) {
      if (col[r] < nt && cost_[r * n + col[r]] < forbidden) track_of_object[objs[r]] = trks[col[r]];
    }
    begin = end;
  }
}

void DynamicFilter::update_track(Track& track, const Observation& obs, double stamp_s) {
  const double dt = stamp_s - track.last_seen_s;
  // At the field-of-view end or a masked sector the whole object is ambiguous: its apparent motion
  // may be it entering or leaving the view, so its velocity decays (thesis 3.2.2). An edge hidden
  // behind something nearer (and the centroid with it) holds its velocity instead, and its position
  // follows the measurement: the occluder's motion is not learned, a walker passing behind another
  // keeps its motion, and a wall whose visible part changes stays where it is seen. The first scan
  // in which such a point is trusted again re-anchors it the same way, so that the jump back to
  // the true outline is not taken for motion either.
  for (int k = 0; k < 3; ++k) {
    PointVelocityFilter& kf = track.kf[k];
    if (obs.ambiguous) {
      kf.predict_and_decay(obs.points[k], dt, config_.velocity);
    } else if (!obs.trusted[k] || !track.trusted[k]) {
      kf.predict_and_hold(obs.points[k], dt, config_.velocity);
    } else {
      kf.predict_and_update(obs.points[k], dt, config_.velocity);
    }
    track.trusted[k] = obs.trusted[k] && !obs.ambiguous;
  }
  // Speed is the lowest of the three points' speeds (thesis 3.2.4).
  std::array<Eigen::Vector2d, 3> v;
  double speed = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    v[k] = track.kf[k].velocity();
    speed = std::min(speed, v[k].norm());
  }
  const ClassificationConfig& cc = config_.classification;
  const double ratio =
      static_cast<double>(std::max(obs.point_count, track.point_count)) /
      static_cast<double>(std::max(1, std::min(obs.point_count, track.point_count)));
  MotionEvidence evidence = MotionEvidence::kFast;
  if (speed <= cc.speed_limit_mps) {
    evidence = MotionEvidence::kSlow;
  } else if (ratio > cc.max_point_count_ratio) {
    evidence = MotionEvidence::kNone;  // Size jump (merge, split, occlusion): motion unreliable.
  } else if (obs.ambiguous || obs.extent_m > cc.max_dynamic_extent_m) {
    evidence = MotionEvidence::kNone;
  } else {
    const double cos_limit = std::cos(cc.max_direction_difference_rad);
    for (int a = 0; a < 3 && evidence == MotionEvidence::kFast; ++a) {
      for (int b = a + 1; b < 3; ++b) {
        if (v[a].dot(v[b]) < cos_limit * v[a].norm() * v[b].norm()) {
          evidence = MotionEvidence::kNone;  // The points disagree: not a rigid motion.
          break;
        }
      }
    }
  }
  track.cls = update_class_state(track.cls, evidence, cc);
  track.speed_mps = speed;
  track.point_count = obs.point_count;
  // A dynamic object keeps the extent it had when it became dynamic: people and vehicles do not
  // grow, so its track cannot creep onto a wall the person stood next to.
  if (track.cls.object_class != ObjectClass::kDynamic) track.extent_m = obs.extent_m;
  track.last_seen_s = stamp_s;
  track.missed_scans = 0;
  ++track.age_scans;
}

DynamicFilter::Track DynamicFilter::new_track(const Observation& obs, double stamp_s,
                                              std::int32_t object_index) {
  Track t;
  t.id = next_id_++;
  for (int k = 0; k < 3; ++k) {
    t.kf[k] = PointVelocityFilter(obs.points[k], config_.velocity);
    t.trusted[k] = obs.trusted[k] && !obs.ambiguous;
  }
  t.cls = initial_class_state(config_.classification);
  t.last_seen_s = stamp_s;
  t.age_scans = 1;
  t.missed_scans = 0;
  t.point_count = obs.point_count;
  t.extent_m = obs.extent_m;
  t.speed_mps = 0.0;
  t.object_index = object_index;
  ++counters_.tracks_created;
  return t;
}

void DynamicFilter::write_output(FilterResult& out) {
  out.tracks.resize(tracks_.size());
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    const Track& t = tracks_[i];
    TrackedObject& o = out.tracks[i];
    o.id = t.id;
    o.object_class = t.cls.object_class;
    o.position_m = t.kf[kCentroid].position();
    o.velocity_mps = t.kf[kCentroid].velocity();
    o.first_edge_m = t.kf[kFirst].position();
    o.last_edge_m = t.kf[kLast].position();
    o.speed_mps = t.speed_mps;
    o.dynamic_weight = t.cls.dynamic_weight;
    o.static_weight = t.cls.static_weight;
    o.age_scans = t.age_scans;
    o.missed_scans = t.missed_scans;
    o.object_index = t.object_index;
  }
}

}  // namespace dispel
