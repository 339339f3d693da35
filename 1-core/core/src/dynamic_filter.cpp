// The dynamic filter's per-scan steps (thesis Figure 3.3): check, segment, observe, match, update
// velocities, classify, label. Matching is in track_matching.cpp, the configuration in
// dynamic_filter_config.cpp.
#include "dispel/core/dynamic_filter.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <utility>

namespace dispel {
namespace {

double microseconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start)
      .count();
}

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

// A track followed for longer than this without any sign of motion is known structure seen from
// a new side (or merged with someone next to it), not something that just appeared in free space;
// unless it is beside a dynamic track (free_space.mark_beside_dynamic): a walker's other leg.
constexpr std::int32_t kFreeSpaceMaxAge = 10;
// An object made dynamic by free space is judged kFreeSpaceDecision_s later: confirmed if its
// centroid has moved more than kFreeSpaceConfirm_m from where it appeared (or it is beside a
// track that has moved: a walker's planted foot), else it was there all along (out of the scan
// plane where the earlier beams passed) and is static again. A walker at 0.4 m/s leaves the
// 0.15 m in 0.4 s; a static surface's centroid moves a few centimetres as the view of it changes.
// Judged after one scan, a planted foot would be refuted and a surface whose visible part grows
// confirmed.
constexpr double kFreeSpaceConfirm_m = 0.15;
constexpr double kFreeSpaceDecision_s = 0.4;
// An object at least kElongated_m long (a wall's piece, a cart's side; longer than a walker's
// stride) shows its motion only across itself: the part of a surface a scanner sees changes as
// the robot drives (a dropout, an occluder's edge) and its centroid slides along it. Along itself
// only the motion of both its edges counts, when both are its outline then and now and they
// moved alike (within kEdgesAgree_m).
constexpr double kElongated_m = 0.8;
constexpr double kEdgesAgree_m = 0.15;
// A thing longer than a walker (kElongated_m) that free space marks in a scan where at least
// kNowhereShare of its beams returned nothing, or something more than kNowhereMargin_m farther, in
// the scan before appeared from nowhere: the floor, seen as the scanner pitches, is such an arc
// across the view, new in every scan and 0.5 m nearer or farther in the next
// (person_following_outdoor_1). It is kept in that scan and removed from the next on, unless the
// track jumps (below). A vehicle that a track loses and takes up again, or that comes out from
// behind something, was near in the scan before and is removed at once; the walkers of the real
// recording were never longer than 0.6 m.
constexpr double kNowhereMargin_m = 0.3;
constexpr double kNowhereShare = 0.9;
// Faster than this from where it appeared, the track has jumped to another object (a chair leg
// next to it), which is no evidence of motion: refuted too.
constexpr double kMaxWalkerSpeed_mps = 2.5;

// A dynamic track whose centroid stays within this of one place is still
// (classification.still_alone_to_static_s): a walker leaves it within a stride.
constexpr double kStillRadius_m = 0.15;

// An object whose beams the registered map explains by at least this share is a surface that has
// stood there: whatever its outline does, it is not moving.
constexpr double kExplainedShare = 0.5;
// The sensor's velocity (registration.slide_tolerance_mps) is smoothed over this time constant.
constexpr double kSensorVelocityTime_s = 0.3;
// An explained object shorter than this has no direction along itself to slide in.
constexpr double kSlideMinExtent_m = 0.5;

// An object that has stood still in the sensor frame (within kAttachedTolerance_m) for
// kAttachedTime_s, within kAttachedRange_m of the sensor, is part of the robot or carried by it (a
// bumper, a mast, another scanner): it moves with the sensor and is not a moving object.
constexpr double kAttachedTolerance_m = 0.03;
constexpr double kAttachedTime_s = 1.0;
constexpr double kAttachedRange_m = 1.5;
// An object most of whose beams return ranges their beams returned in at least kRecurringShare of
// the recent scans (within kRecurringTolerance_m plus kRecurringRelativeTolerance of the range; an
// exponential average, each scan weighing kRecurringWeight: five scans in a row from nothing),
// within kRecurringRange_m of the sensor, is part of the robot too, even when it flickers in and
// out of the scan (a flap, a cable, a bumper at a grazing angle). Nothing else stands that close
// to the scanner while the robot drives. Farther out the same evidence would keep someone who
// walks beside the robot at its speed, whom SLAM takes for part of the robot and must not see.
constexpr float kRecurringRange_m = 0.35F;
constexpr float kRecurringTolerance_m = 0.03F;
constexpr float kRecurringRelativeTolerance = 0.01F;
constexpr float kRecurringWeight = 1.0F / 16.0F;
constexpr float kRecurringShare = 0.25F;
// segmentation.min_width_m: an object below min_points is one only where each of the last two
// scans had a return within kSeenBefore_m: a far walker's legs are there scan after scan (a leg
// moves 0.2 m a scan at 1.5 m/s and 7.5 Hz, and the other one stands); a sporadic return
// outdoors (the ground near the range limit, docs/dynamic_filter.md) has nothing around it in
// the scans before. (The number of scans is the size of DynamicFilter::earlier_scans_.)
constexpr double kSeenBefore_m = 0.3;
// A scan counts only when the sensor has moved this far or turned this much since the last one
// counted.
constexpr double kRecurringMove_m = 0.05;
constexpr double kRecurringTurn_rad = 0.035;
constexpr double kRecurringObjectShare = 0.5;
// A beam that has returned a part of the robot (an object judged part of it, as above) at one
// range within kBodyRange_m in at least kBodyShare of the scans counted (an exponential average,
// kBodyWeight per scan, over scans whose motion was measured) is blocked by the robot's body or
// grazes its edge; what it returns more than kBodyMargin_m beyond that range is no evidence of
// motion: the world seen past the robot's edge in some scans only, or a return the scanner repeats
// there (on negative_2's left laser, beams that return the robot at 0.73 m in most scans and a
// constant 3.75 m or 6.77 m in others while the robot drives 2 m). Someone walking beside or ahead
// of the robot is never judged part of it (a walker's legs never stand still in the sensor frame),
// so the beams that hit them are not the body's.
constexpr float kBodyMargin_m = 0.1F;
constexpr float kBodyRange_m = 1.0F;
constexpr float kBodyWeight = 1.0F / 64.0F;
constexpr float kBodyShare = 0.5F;

// A range's share as of counted scan @p now: the share it had at its own scan, decayed by @p keep
// for each counted scan since (pow(keep, 0) is exactly 1).
float share_at(float share, std::uint32_t since, std::uint32_t now, float keep) {
  return since < now ? share * std::pow(keep, static_cast<float>(now - since)) : share;
}

// Fragments are absorbed by dynamic tracks seen in this scan or missed for a few scans at most.
constexpr std::int32_t kFragmentMaxMissed = 2;

// A dynamic track seen in this scan or missed for kFragmentMaxMissed scans at most: what moves
// now, for the fragments beside it, the companions and the registration's left-out points.
template <typename Track>
bool moving_now(const Track& t) {
  return t.cls.object_class == ObjectClass::kDynamic && t.missed_scans <= kFragmentMaxMissed;
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
    case FilterEvent::kNoPose:
      return "no_pose";
  }
  return "unknown";
}

DynamicFilter::DynamicFilter(DynamicFilterConfig config)
    : config_((config.validate(), std::move(config))),
      segmenter_(config_.segmentation),
      free_space_(config_.free_space),
      registration_(config_.registration,
                    SpeedLimits{config_.max_speed_mps, config_.max_turn_rate_radps}) {}

DynamicFilter::DynamicFilter(DynamicFilterConfig config, FreeSpaceMap&& free_space)
    : config_((config.validate(), std::move(config))),
      segmenter_(config_.segmentation),
      free_space_(config_.free_space, std::move(free_space)),
      registration_(config_.registration,
                    SpeedLimits{config_.max_speed_mps, config_.max_turn_rate_radps}) {}

void DynamicFilter::reset() {
  counters_.tracks_dropped += static_cast<std::int64_t>(tracks_.size());
  tracks_.clear();
  free_space_.clear();
  registration_.reset();
  have_previous_ = false;  // recurring_ is kept: the robot's parts are where they were.
  earlier_count_ = 0;
  previous_ranges_.clear();
}

void DynamicFilter::process(const LaserScan& scan, const std::optional<Pose2>& sensor_pose,
                            FilterResult& out) {
  ++counters_.scans;
  const ScanCheck checked = check(scan, sensor_pose);
  if (checked.rejected) {
    pass_through(scan, checked.event, out);
    record_work(scan, out);
    return;
  }
  const bool registering = config_.registration.enabled;
  laser_only_ = registering && !sensor_pose;
  out.registration = RegistrationReport{};
  const auto registration_start = std::chrono::steady_clock::now();
  // What moves, for a laser-only registration (registration.leave_out_moving): the points near a
  // dynamic track's outline, predicted to the scan's time.
  // Asked per sample point: only when there is such a track (most scans of a recording without
  // people have none).
  predict_moving_outlines(scan.stamp_s);
  std::function<bool(const Eigen::Vector2d&)> moving;
  if (!moving_outlines_.empty()) {
    moving = [this](const Eigen::Vector2d& p) { return near_dynamic_track(p); };
  }
  const Pose2 pose = registering
                         ? registration_.register_scan(scan, sensor_pose, out.registration, moving)
                         : *sensor_pose;
  registration_us_ = registering ? microseconds_since(registration_start) : 0.0;
  if (registering) {
    counters_.scans_registered += out.registration.registered ? 1 : 0;
    counters_.registration_fallbacks += out.registration.fallback ? 1 : 0;
    counters_.registration_degenerate += out.registration.degenerate ? 1 : 0;
    counters_.scans_without_odometry += sensor_pose ? 0 : 1;
    counters_.odometry_overruled += out.registration.odometry_overruled ? 1 : 0;
    counters_.scans_realigned += out.registration.realignments > 0 ? 1 : 0;
    counters_.registration_guess_limited += out.registration.guess_limited ? 1 : 0;
    counters_.registration_held_sideways += out.registration.held_sideways ? 1 : 0;
  }
  out.sensor_pose = pose;
  previous_input_pose_ = sensor_pose;
  place_beams(scan, pose, registering);
  if (config_.segmentation.min_width_m > 0.0) {
    const PoseTransform to_fixed(pose);
    segmenter_.segment(scan, out.segmentation,
                       [&](const Eigen::Vector2d& p) { return seen_before(to_fixed(p)); });
  } else {
    segmenter_.segment(scan, out.segmentation);
  }
  observe(out.segmentation, pose, scan.range_max_m);
  if (registering) {
    explain(scan, out.segmentation);
    recur(scan, out.segmentation, pose, checked.learn);
  }
  match(scan.stamp_s);
  if (checked.learn) {
    update_velocities(scan.stamp_s);
    classify(scan, pose, out.segmentation);
    follow_fragments(scan, out.segmentation, pose);
    previous_ranges_ = scan.ranges_m;
    // The body is learned only when the sensor's motion was measured (by odometry, or by a
    // registration that holds in every direction): a guessed motion while the robot stands would
    // count someone standing in front of it as moving with it.
    if (registering &&
        (sensor_pose || (out.registration.registered && !out.registration.degenerate))) {
      learn_body(scan, out.segmentation);
    }
    if (have_previous_ && scan.stamp_s > previous_stamp_s_) {
      const double dt = scan.stamp_s - previous_stamp_s_;
      const Eigen::Vector2d v = (pose.translation() - previous_position_) / dt;
      const double a = dt / (kSensorVelocityTime_s + dt);
      sensor_velocity_ += a * (v - sensor_velocity_);
    } else {
      sensor_velocity_.setZero();
    }
    previous_position_ = pose.translation();
    previous_stamp_s_ = scan.stamp_s;
    have_previous_ = true;
    if (config_.segmentation.min_width_m > 0.0) {
      std::rotate(earlier_scans_.rbegin(), earlier_scans_.rbegin() + 1, earlier_scans_.rend());
      EarlierScan& latest = earlier_scans_.front();
      latest.points = beam_points_;
      latest.sensor_pose = pose;
      latest.angle_min_rad = scan.angle_min_rad;
      latest.increment_rad = scan.angle_increment_rad;
      latest.full_circle = out.segmentation.full_circle;
      earlier_count_ = std::min(earlier_count_ + 1, earlier_scans_.size());
    }
  } else {
    // A repeated stamp: no time has passed, so nothing can be learned; label from the tracks.
    for (Track& t : tracks_) t.object_index = -1;
    const ObjectClass fresh = initial_class_state(config_.classification).object_class;
    verdicts_.resize(observations_.size());
    for (std::size_t i = 0; i < observations_.size(); ++i) {
      const std::int32_t t = track_of_object_[i];
      verdicts_[i] = t >= 0 ? ObjectVerdict{tracks_[t].cls.object_class, tracks_[t].speed_mps}
                            : ObjectVerdict{fresh, 0.0};
      if (t >= 0) tracks_[t].object_index = static_cast<std::int32_t>(i);
    }
  }
  label(scan, checked, out);
  if (registering && checked.learn) {
    // The map learns what stays in the scan: static objects and beams of no object.
    keep_.resize(out.labels.size());
    for (std::size_t b = 0; b < out.labels.size(); ++b) {
      keep_[b] = out.labels[b] == BeamLabel::kStatic || out.labels[b] == BeamLabel::kNoObject;
    }
    const std::int64_t restarted = registration_.voxels_restarted();
    if (config_.free_space.enabled) {
      registration_.add(
          keep_, [this](const Eigen::Vector2d& p) { return free_space_.known_free(p); },
          [this](const Eigen::Vector2d& p) { return free_space_.long_free(p); });
    } else {
      registration_.add(keep_, {});
    }
    counters_.map_voxels_restarted += registration_.voxels_restarted() - restarted;
  }
  if (checked.learn && config_.tracking.remove_edge_pixels) remove_edge_pixels(scan, out);
  ++counters_.events[static_cast<std::size_t>(checked.event)];
  record_work(scan, out);
}

void DynamicFilter::record_work(const LaserScan& scan, FilterResult& out) {
  ScanWork& w = out.work;
  w.beams = static_cast<std::int32_t>(scan.size());
  w.objects = static_cast<std::int32_t>(out.segmentation.objects.size());
  w.tracks = static_cast<std::int32_t>(tracks_.size());
  w.registration_points = out.registration.points;
  w.registration_iterations = out.registration.iterations;
  w.registration_alignments = out.registration.alignments;
  w.registration_total_iterations = out.registration.total_iterations;
  w.registration_us = registration_us_;
  w.free_space_us = free_space_us_;
  registration_us_ = free_space_us_ = 0.0;
  w.map_voxels = static_cast<std::int64_t>(registration_.voxel_count());
  w.free_space_tiles_started = free_space_.take_tiles_started();
}

// Step 1: a scan or pose that cannot be used is passed through; a jump in time or pose resets the
// tracks; a repeated stamp is labelled without learning.
DynamicFilter::ScanCheck DynamicFilter::check(const LaserScan& scan,
                                              const std::optional<Pose2>& sensor_pose) {
  ScanCheck c;
  const ScanIssue issue = check_scan(scan);
  if (issue != ScanIssue::kNone) {
    ++counters_.rejected_by_issue[static_cast<std::size_t>(issue)];
    c.event = FilterEvent::kRejectedScan;
  } else if (!sensor_pose && !config_.registration.enabled) {
    c.event = FilterEvent::kNoPose;
  } else if (sensor_pose && !finite_pose(*sensor_pose)) {
    c.event = FilterEvent::kRejectedPose;
  }
  if (c.event != FilterEvent::kFiltered) {
    c.rejected = true;
    return c;
  }
  if (!have_previous_) {
    c.event = FilterEvent::kFirstScan;
    return c;
  }
  const double dt = scan.stamp_s - previous_stamp_s_;
  // A jump of the given poses (the odometry's frame), when there are two to compare.
  double moved = 0.0, turned = 0.0;
  if (sensor_pose && previous_input_pose_) {
    moved = (sensor_pose->translation() - previous_input_pose_->translation()).norm();
    turned = std::abs(wrap_angle(sensor_pose->yaw_rad - previous_input_pose_->yaw_rad));
  }
  if (dt < 0.0) {
    reset();
    c.event = FilterEvent::kResetTimeBackwards;
  } else if (dt == 0.0) {
    c.event = FilterEvent::kRepeatedStamp;
    c.learn = false;
  } else if (dt > config_.max_time_gap_s) {
    reset();
    c.event = FilterEvent::kResetTimeGap;
  } else if (moved > config_.max_pose_jump_m + config_.max_speed_mps * dt ||
             turned > config_.max_pose_jump_rad + config_.max_turn_rate_radps * dt) {
    reset();
    c.event = FilterEvent::kResetPoseJump;
  }
  return c;
}

void DynamicFilter::pass_through_unfiltered(const LaserScan& scan, FilterEvent event,
                                            FilterResult& out) {
  out.event = event;
  out.filtered = scan;
  out.segmentation = Segmentation{};
  out.segmentation.issue = check_scan(scan);
  out.removed_dynamic = out.removed_unknown = 0;
  const bool usable_limits = out.segmentation.issue == ScanIssue::kNone;
  out.labels.resize(scan.size());
  for (std::size_t i = 0; i < scan.size(); ++i) {
    out.labels[i] = usable_limits && scan.is_valid(i) ? BeamLabel::kNoObject : BeamLabel::kInvalid;
  }
  out.tracks.clear();
  out.work = ScanWork{};
  out.work.beams = static_cast<std::int32_t>(scan.size());
}

void DynamicFilter::pass_through(const LaserScan& scan, FilterEvent event, FilterResult& out) {
  pass_through_unfiltered(scan, event, out);
  out.sensor_pose.reset();
  out.registration = RegistrationReport{};
  for (Track& t : tracks_) t.object_index = -1;
  write_tracks(out);
  ++counters_.events[static_cast<std::size_t>(event)];
}

// Whether each of the scans held in earlier_scans_ (the last two) had a return within
// kSeenBefore_m of @p point_m (fixed frame).
bool DynamicFilter::seen_before(const Eigen::Vector2d& point_m) const {
  if (earlier_count_ < earlier_scans_.size()) return false;
  return std::all_of(earlier_scans_.begin(), earlier_scans_.end(), [&](const EarlierScan& e) {
    return e.has_return_near(point_m, kSeenBefore_m);
  });
}

// The beams around the point's bearing from where the scan was taken, as far as @p radius_m
// reaches at its range.
bool DynamicFilter::EarlierScan::has_return_near(const Eigen::Vector2d& point_m,
                                                 double radius_m) const {
  const Eigen::Vector2d q = sensor_pose.inverse().apply(point_m);
  const double range = q.norm();
  const double increment = std::abs(increment_rad);
  if (!(range > 0.0) || !(increment > 0.0) || points.empty()) return false;
  const auto n = static_cast<std::int64_t>(points.size());
  const auto centre = static_cast<std::int64_t>(
      std::lround((std::atan2(q.y(), q.x()) - angle_min_rad) / increment_rad));
  const auto reach = static_cast<std::int64_t>(std::ceil(std::atan2(radius_m, range) / increment));
  for (std::int64_t j = centre - reach; j <= centre + reach; ++j) {
    const std::int64_t k = full_circle ? ((j % n) + n) % n : j;
    if (k < 0 || k >= n) continue;
    // False for an invalid beam's NaN.
    if ((points[static_cast<std::size_t>(k)] - point_m).squaredNorm() <= radius_m * radius_m) {
      return true;
    }
  }
  return false;
}

// Each valid beam's end point in the fixed frame (NaN for the others), for the rules that ask
// where a beam ends.
void DynamicFilter::place_beams(const LaserScan& scan, const Pose2& sensor_pose, bool registered) {
  beam_points_.resize(scan.size());
  if (registered) {
    // The registration's points: each beam where the sensor was when it measured it (de-skewed),
    // as the objects' edges are (observe()). Placed from the scan's stamp instead, a beam near
    // the end of a sweep taken while turning lay up to 0.05 rad x its range off its object's edge
    // (0.5 rad/s over the 0.1 s sweep of the simulated 768-beam scanner), and free space traced
    // along it cut through the walls seen in the next scans.
    const std::vector<Eigen::Vector2d>& deskewed = registration_.points();
    for (std::size_t b = 0; b < scan.size(); ++b) {
      beam_points_[b] = scan.is_valid(b) && b < deskewed.size()
                            ? deskewed[b]
                            : Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
    }
    return;
  }
  const std::vector<Eigen::Vector2d>& unit = directions_.of(scan);
  const PoseTransform to_fixed(sensor_pose);
  for (std::size_t b = 0; b < scan.size(); ++b) {
    beam_points_[b] = scan.is_valid(b)
                          ? to_fixed(static_cast<double>(scan.ranges_m[b]) * unit[b])
                          : Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  }
}

// Step 3: each object's first edge, last edge and centroid in the fixed frame, and whether each
// is the object's true outline (trusted) or may be cut off.
void DynamicFilter::observe(const Segmentation& segmentation, const Pose2& sensor_pose,
                            float range_max_m) {
  const std::vector<ScanObject>& objects = segmentation.objects;
  observations_.resize(objects.size());
  // An edge beside a beam with no return, at the end of the scanner's range, may continue beyond
  // it: as the robot moves, it slides along the object like a view limit.
  const double range_edge =
      static_cast<double>(range_max_m) - 2.0 * config_.segmentation.cluster_gap_m;
  const auto at_range_limit = [&](EdgeNeighbour n, const Eigen::Vector2d& p) {
    return n == EdgeNeighbour::kInvalid && p.norm() > range_edge;
  };
  // With the registration, the edges are its de-skewed points (each beam where the sensor was
  // when it measured it), and the centroid moves with them.
  const std::vector<Eigen::Vector2d>* deskewed =
      config_.registration.enabled ? &registration_.points() : nullptr;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const ScanObject& o = objects[i];
    Observation& obs = observations_[i];
    obs.points[kFirst] = sensor_pose.apply(o.first_point_m);
    obs.points[kLast] = sensor_pose.apply(o.last_point_m);
    obs.points[kCentroid] = sensor_pose.apply(o.centroid_m);
    if (deskewed != nullptr) {
      const Eigen::Vector2d first = (*deskewed)[static_cast<std::size_t>(o.first_beam)];
      const Eigen::Vector2d last = (*deskewed)[static_cast<std::size_t>(o.last_beam)];
      obs.points[kCentroid] += 0.5 * ((first - obs.points[kFirst]) + (last - obs.points[kLast]));
      obs.points[kFirst] = first;
      obs.points[kLast] = last;
    }
    obs.explained_share = 0.0;
    obs.local_centroid = o.centroid_m;
    obs.recurring_share = 0.0;
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
}

// Each object's share of beams that return a range their beam has often returned (see
// RecurringRange), then this scan's ranges counted.
void DynamicFilter::recur(const LaserScan& scan, const Segmentation& segmentation,
                          const Pose2& sensor_pose, bool learn) {
  if (recurring_.size() != kRecurringSlots * scan.size()) {
    recurring_.assign(kRecurringSlots * scan.size(), RecurringRange{});
    recurring_scans_ = 0;
    recurring_pose_.reset();
  }
  // Only a scan taken after the sensor has moved tells what moves with it: while it stands, the
  // world (a walker's foot planted for a step) is still in its frame too.
  if (learn) {
    const bool moved =
        !recurring_pose_ ||
        (sensor_pose.translation() - recurring_pose_->translation()).norm() >= kRecurringMove_m ||
        std::abs(wrap_angle(sensor_pose.yaw_rad - recurring_pose_->yaw_rad)) >= kRecurringTurn_rad;
    learn = moved;
  }
  if (learn) {
    ++recurring_scans_;
    recurring_pose_ = sensor_pose;
  }
  recurring_counted_ = learn;
  if (body_.size() != scan.size()) body_.assign(scan.size(), RecurringRange{});
  const float keep = 1.0F - kRecurringWeight;
  // A slot's share as of the last scan counted before this one (each counted scan that did not
  // return its range decays it).
  const std::uint32_t previous = learn ? recurring_scans_ - 1 : recurring_scans_;
  explained_count_.assign(segmentation.objects.size(), 0);
  for (std::size_t b = 0; b < scan.size(); ++b) {
    if (!scan.is_valid(b)) continue;
    const std::int32_t object = segmentation.beam_labels[b];
    const RecurringRange& body = body_[b];
    // (body.share >= kBodyShare first: most beams have never returned the body, and a share only
    // decays.)
    if (object >= 0 && body.share >= kBodyShare &&
        scan.ranges_m[b] > body.range_m + kBodyMargin_m &&
        share_at(body.share, body.scan, previous, 1.0F - kBodyWeight) >= kBodyShare) {
      ++explained_count_[static_cast<std::size_t>(object)];
      continue;
    }
    if (scan.ranges_m[b] > kRecurringRange_m) continue;
    const float r = scan.ranges_m[b];
    const float tolerance = kRecurringTolerance_m + kRecurringRelativeTolerance * r;
    RecurringRange* slots = &recurring_[kRecurringSlots * b];
    RecurringRange* match = nullptr;
    RecurringRange* weakest = slots;
    for (std::size_t k = 0; k < kRecurringSlots; ++k) {
      RecurringRange& slot = slots[k];
      if (slot.scan < previous) {
        slot.share = share_at(slot.share, slot.scan, previous, keep);
        slot.scan = previous;
      }
      if (std::abs(slot.range_m - r) <= tolerance &&
          (match == nullptr || slot.share > match->share)) {
        match = &slot;
      }
      if (slot.share < weakest->share) weakest = &slot;
    }
    const std::int32_t o = segmentation.beam_labels[b];
    if (o >= 0 && match != nullptr && match->share >= kRecurringShare) {
      ++explained_count_[static_cast<std::size_t>(o)];
    }
    if (!learn) continue;
    // This scan counts: the range it returned goes up (a new range takes the weakest slot); the
    // other slot decays when it is next brought up to date.
    if (match == nullptr) {
      match = weakest;
      match->range_m = r;
      match->share = 0.0F;
    }
    match->share = match->share * keep + kRecurringWeight;
    match->scan = recurring_scans_;
  }
  for (std::size_t i = 0; i < segmentation.objects.size(); ++i) {
    observations_[i].recurring_share =
        static_cast<double>(explained_count_[i]) / std::max(1, segmentation.objects[i].point_count);
  }
}

// Where each beam returns the robot's own body: the beams of objects judged part of the robot in
// this scan, when it is counted (see recur()).
void DynamicFilter::learn_body(const LaserScan& scan, const Segmentation& segmentation) {
  if (!recurring_counted_) return;
  const float keep = 1.0F - kBodyWeight;
  for (std::size_t b = 0; b < scan.size(); ++b) {
    const std::int32_t o = segmentation.beam_labels[b];
    if (o < 0 || !scan.is_valid(b) || scan.ranges_m[b] > kBodyRange_m ||
        attached_[static_cast<std::size_t>(o)] == 0) {
      continue;
    }
    RecurringRange& body = body_[b];
    const float r = scan.ranges_m[b];
    body.share = share_at(body.share, body.scan, recurring_scans_ - 1, keep);
    if (std::abs(body.range_m - r) > kRecurringTolerance_m + kRecurringRelativeTolerance * r) {
      if (body.share >= kBodyShare) {
        body.scan = recurring_scans_ - 1;  // Brought up to date; another range does not count.
        continue;
      }
      body.range_m = r;
      body.share = 0.0F;
    }
    body.share = body.share * keep + kBodyWeight;
    body.scan = recurring_scans_;
  }
}

// Which beams the registered map explains, and each object's share of them.
void DynamicFilter::explain(const LaserScan& scan, const Segmentation& segmentation) {
  explained_.assign(scan.size(), 0);
  std::vector<std::int32_t>& count = explained_count_;
  count.assign(segmentation.objects.size(), 0);
  for (std::size_t b = 0; b < scan.size(); ++b) {
    const std::int32_t o = segmentation.beam_labels[b];
    if (o < 0 && o != kLabelNoise) continue;
    if (!registration_.explained(b)) continue;
    explained_[b] = 1;
    if (o >= 0) ++count[static_cast<std::size_t>(o)];
  }
  for (std::size_t i = 0; i < segmentation.objects.size(); ++i) {
    observations_[i].explained_share =
        static_cast<double>(count[i]) /
        static_cast<double>(std::max(1, segmentation.objects[i].point_count));
  }
}

// Step 5: the point velocity filters of every matched track (thesis Eq. 3.4-3.5); tracks not seen
// grow older.
void DynamicFilter::update_velocities(double stamp_s) {
  for (Track& t : tracks_) t.object_index = -1;
  for (std::size_t i = 0; i < observations_.size(); ++i) {
    const std::int32_t index = track_of_object_[i];
    if (index < 0) continue;
    Track& track = tracks_[index];
    const Observation& obs = observations_[i];
    const double dt = stamp_s - track.last_seen_s;
    // At the field-of-view end or a masked sector the whole object is ambiguous: its apparent
    // motion may be it entering or leaving the view, so its velocity decays (thesis 3.2.2). An
    // edge hidden behind something nearer (and the centroid with it) holds its velocity instead,
    // and its position follows the measurement: the occluder's motion is not learned, a walker
    // passing behind another keeps its motion, and a wall whose visible part changes stays where
    // it is seen. The first scan in which such a point is trusted again re-anchors it the same
    // way, so that the jump back to the true outline is not taken for motion either.
    double speed = std::numeric_limits<double>::infinity();
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
      // Speed is the lowest of the three points' speeds (thesis 3.2.4).
      speed = std::min(speed, kf.velocity().norm());
    }
    track.speed_mps = speed;
    track.object_index = static_cast<std::int32_t>(i);
  }
  for (Track& t : tracks_) {
    if (t.object_index < 0) {
      ++t.missed_scans;
      ++t.age_scans;
    }
  }
}

// Step 6: each matched track's motion evidence and class (thesis 3.2.4); new tracks for the other
// objects; beyond the thesis, objects in space seen free and the companions of dynamic tracks;
// then every object's verdict, and tracks unseen for too long are forgotten.
void DynamicFilter::classify(const LaserScan& scan, const Pose2& sensor_pose,
                             const Segmentation& segmentation) {
  for (std::size_t i = 0; i < observations_.size(); ++i) {
    if (track_of_object_[i] >= 0) {
      update_class(tracks_[track_of_object_[i]], observations_[i], scan.stamp_s);
    }
  }
  start_tracks(scan.stamp_s);
  if (config_.free_space.enabled) {
    mark_objects_in_free_space(scan, segmentation);
    const auto free_space_start = std::chrono::steady_clock::now();
    // Traced along the beams as the registration de-skewed them (turned by the sensor's turn
    // while it swept), where the objects' points are.
    free_space_.add_scan(
        scan, sensor_pose,
        config_.registration.enabled ? registration_.deskew_turn_per_beam_rad() : 0.0);
    free_space_us_ = microseconds_since(free_space_start);
  }
  spread_to_companions();
  verdicts_.resize(observations_.size());
  attached_.resize(observations_.size());
  for (std::size_t i = 0; i < observations_.size(); ++i) {
    const Track& t = tracks_[track_of_object_[i]];
    verdicts_[i] = {held_now(t, scan.stamp_s) ? ObjectClass::kStatic : t.cls.object_class,
                    t.speed_mps};
    attached_[i] = t.attached ? 1 : 0;
  }
  forget_lost_tracks();  // Tracks move: track_of_object_ is stale from here on.
}

void DynamicFilter::update_class(Track& track, const Observation& obs, double stamp_s) {
  const ClassificationConfig& cc = config_.classification;
  const double ratio =
      static_cast<double>(std::max(obs.point_count, track.point_count)) /
      static_cast<double>(std::max(1, std::min(obs.point_count, track.point_count)));
  MotionEvidence evidence = MotionEvidence::kFast;
  if (obs.explained_share >= kExplainedShare && !slides_unlike_the_sensor(track, obs)) {
    evidence = MotionEvidence::kSlow;  // A surface that has stood there: its outline slides.
  } else if (track.speed_mps <= cc.speed_limit_mps) {
    evidence = MotionEvidence::kSlow;
  } else if (ratio > cc.max_point_count_ratio) {
    evidence = MotionEvidence::kNone;  // Size jump (merge, split, occlusion): motion unreliable.
  } else if (obs.ambiguous || obs.extent_m > cc.max_dynamic_extent_m) {
    evidence = MotionEvidence::kNone;
  } else {
    const double cos_limit = std::cos(cc.max_direction_difference_rad);
    for (int a = 0; a < 3 && evidence == MotionEvidence::kFast; ++a) {
      for (int b = a + 1; b < 3; ++b) {
        const Eigen::Vector2d va = track.kf[a].velocity(), vb = track.kf[b].velocity();
        if (va.dot(vb) < cos_limit * va.norm() * vb.norm()) {
          evidence = MotionEvidence::kNone;  // The points disagree: not a rigid motion.
          break;
        }
      }
    }
  }
  // An object made dynamic by free space is judged kFreeSpaceDecision_s later (see there): refuted
  // when the map explains it now (a surface that has stood there, which the track took after it
  // lost what free space marked, or grew onto as more of it came into view); else confirmed when
  // it has moved as a walker can, or it is beside a track that has (unless that is what marked
  // it: a low thing first hit up close beside a walker, office_revisits' walls); else refuted.
  // Farther from where it appeared than a walker gets by then, it is refuted as soon as that is
  // seen, in any scan before the decision: the track went on to another thing (a piece nearby
  // that it took after it was unseen for a few scans). At the decision that jump could pass for a
  // walk, and the velocity it gave the track for motion.
  if (track.free_space_pending) {
    const double elapsed = stamp_s - track.marked_s;
    const double moved = moved_since_marked(track, obs);
    const bool decided = elapsed >= kFreeSpaceDecision_s;
    const bool jumped = moved > kFreeSpaceConfirm_m + kMaxWalkerSpeed_mps * elapsed;
    const bool moved_plausibly = moved > kFreeSpaceConfirm_m && !jumped;
    const bool explained =
        decided && obs.explained_share >= kExplainedShare && !slides_unlike_the_sensor(track, obs);
    if ((decided || jumped) &&
        (explained || (!moved_plausibly && (track.marked_beside ||
                                            !beside_moving_track(track, obs.points[kCentroid]))))) {
      track.free_space_pending = false;
      track.free_space_refuted = true;
      track.cls = initial_class_state(cc);
      ++counters_.free_space_refuted;
      if (jumped) {
        // What it jumped from was another thing: its motion starts afresh here.
        for (int k = 0; k < 3; ++k)
          track.kf[k] = PointVelocityFilter(obs.points[k], config_.velocity);
        track.speed_mps = 0.0;
        evidence = MotionEvidence::kNone;
      }
    } else if (decided) {
      track.free_space_pending = false;
    }
  }
  // Part of the robot: still in the sensor frame for long, near it.
  if (track.local_still.left(obs.local_centroid, kAttachedTolerance_m)) {
    track.local_still.restart(obs.local_centroid, stamp_s);
  }
  const bool attached =
      config_.registration.enabled && ((stamp_s - track.local_still.since_s >= kAttachedTime_s &&
                                        obs.local_centroid.norm() <= kAttachedRange_m) ||
                                       obs.recurring_share >= kRecurringObjectShare);
  track.attached = attached;
  if (attached) evidence = MotionEvidence::kSlow;
  track.cls = update_class_state(track.cls, evidence, cc);
  if (attached && track.cls.object_class != ObjectClass::kStatic) {
    track.cls.object_class = ObjectClass::kStatic;
    track.cls.dynamic_weight = 0;
  }
  // Dynamic, still for still_alone_to_static_s, and alone: static again.
  if (track.cls.object_class != ObjectClass::kDynamic ||
      track.still.left(obs.points[kCentroid], kStillRadius_m)) {
    track.still.restart(obs.points[kCentroid], stamp_s);
    track.still_since_unseen = track.missed_scans > 0;
  } else if (cc.still_alone_to_static_s > 0.0 && track.still_since_unseen &&
             stamp_s - track.still.since_s >= cc.still_alone_to_static_s &&
             !beside_moving_track(track, obs.points[kCentroid])) {
    track.cls = initial_class_state(cc);
    track.free_space_pending = false;
    ++counters_.still_alone_to_static;
  }
  track.point_count = obs.point_count;
  // A dynamic object keeps the extent it had when it became dynamic: people and vehicles do not
  // grow, so its track cannot creep onto a wall the person stood next to.
  if (track.cls.object_class != ObjectClass::kDynamic) track.extent_m = obs.extent_m;
  track.last_seen_s = stamp_s;
  track.missed_scans = 0;
  track.fragments_still_since_s = -1.0;
  ++track.age_scans;
}

// A track for every object that matched none; one that split from a track (see
// find_split_parents) continues it: its class, weights, age and velocity.
void DynamicFilter::start_tracks(double stamp_s) {
  for (std::size_t i = 0; i < observations_.size(); ++i) {
    if (track_of_object_[i] >= 0) continue;
    Track track = new_track(observations_[i], stamp_s, static_cast<std::int32_t>(i));
    if (parent_of_object_[i] >= 0) {
      const Track& from = tracks_[parent_of_object_[i]];
      track.cls = from.cls;
      track.free_space_pending = from.free_space_pending;
      track.free_space_refuted = from.free_space_refuted;
      track.marked_beside = from.marked_beside;
      track.marked_at = from.marked_at;
      track.marked_first = from.marked_first;
      track.marked_last = from.marked_last;
      track.marked_edges_trusted = from.marked_edges_trusted;
      track.marked_s = from.marked_s;
      track.age_scans = from.age_scans;
      track.born_s = from.born_s;
      for (PointVelocityFilter& kf : track.kf) kf.set_velocity(from.kf[kCentroid].velocity());
      track.speed_mps = from.speed_mps;
    }
    track_of_object_[i] = static_cast<std::int32_t>(tracks_.size());
    tracks_.push_back(std::move(track));
  }
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
  t.born_s = stamp_s;
  t.age_scans = 1;
  t.missed_scans = 0;
  t.point_count = obs.point_count;
  t.extent_m = obs.extent_m;
  t.speed_mps = 0.0;
  t.object_index = object_index;
  t.local_still.restart(obs.local_centroid, stamp_s);
  t.still.restart(obs.points[kCentroid], stamp_s);
  ++counters_.tracks_created;
  return t;
}

// An object most of whose points stand where beams passed freely before (and not as far as the
// map knows, hit since) has moved there: it is dynamic at once, unless it is too large to be.
// With free_space.require_unseen (laser-only by default), a point counts only where the map saw
// nothing before the object's track began: a place that returned before returns now and then.
void DynamicFilter::mark_objects_in_free_space(const LaserScan& scan,
                                               const Segmentation& segmentation) {
  const std::size_t n = segmentation.objects.size();
  // Which objects the free space could mark (the rest are not asked about: most of a scan is
  // surfaces the map explains or tracks too old for it), and the points in free space each of
  // them needs. An older track is asked when it is beside a dynamic one: a walker who walks
  // beside the robot hides one leg behind the other for seconds, and the leg's own track, static
  // since it last stood, steps out into space seen free beside the leg tracked as dynamic (on the
  // simulated office at 1 m/s it kept 3 scans of that leg at every step; docs/dynamic_filter.md).
  const auto could_mark = [&](std::size_t i) {
    const ScanObject& o = segmentation.objects[i];
    const Track& t = tracks_[static_cast<std::size_t>(track_of_object_[i])];
    return (o.last_point_m - o.first_point_m).norm() <=
               config_.classification.max_dynamic_extent_m &&
           observations_[i].explained_share < kExplainedShare &&
           observations_[i].recurring_share < kRecurringObjectShare && !t.free_space_refuted &&
           t.cls.object_class != ObjectClass::kDynamic &&
           (t.age_scans <= kFreeSpaceMaxAge ||
            (config_.free_space.mark_beside_dynamic &&
             beside_moving_track(t, observations_[i].points[kCentroid])));
  };
  // The space must have been seen through by beams dense enough to hit the object: at most half
  // its width apart (a chair leg seen close was missed, not absent, by beams 3 cm apart at 5 m).
  spacing_limit_.resize(n);
  points_needed_.resize(n);
  points_in_free_.assign(n, 0);
  points_seen_before_.assign(n, 0);
  // free_space.require_unseen: a point the map saw there before its track began does not count.
  const RequireUnseen unseen = config_.free_space.require_unseen;
  const bool require_unseen =
      config_.registration.enabled &&
      (unseen == RequireUnseen::kAlways || (unseen == RequireUnseen::kLaserOnly && laser_only_));
  for (std::size_t i = 0; i < n; ++i) {
    const ScanObject& o = segmentation.objects[i];
    spacing_limit_[i] = 0.5 * (o.last_point_m - o.first_point_m).norm();
    points_needed_[i] = could_mark(i) ? config_.free_space.min_object_share * o.point_count
                                      : std::numeric_limits<double>::infinity();
  }
  for (std::size_t b = 0; b < scan.size(); ++b) {
    const std::int32_t o = segmentation.beam_labels[b];
    if (o < 0) continue;
    const auto i = static_cast<std::size_t>(o);
    // Counted until it has enough.
    if (std::isinf(points_needed_[i]) ||
        static_cast<double>(points_in_free_[i]) >= points_needed_[i]) {
      continue;
    }
    if (!free_space_.known_free(beam_points_[b], spacing_limit_[i])) continue;
    if (require_unseen && registration_.seen_before(
                              b, tracks_[static_cast<std::size_t>(track_of_object_[i])].born_s)) {
      ++points_seen_before_[i];
    } else {
      ++points_in_free_[i];
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!(static_cast<double>(points_in_free_[i]) >= points_needed_[i])) {
      if (static_cast<double>(points_in_free_[i] + points_seen_before_[i]) >= points_needed_[i]) {
        ++counters_.free_space_seen_before;
      }
      continue;
    }
    Track& t = tracks_[static_cast<std::size_t>(track_of_object_[i])];
    t.free_space_pending = true;
    t.marked_beside = t.age_scans > kFreeSpaceMaxAge;
    t.marked_at = observations_[i].points[kCentroid];
    t.marked_first = observations_[i].points[kFirst];
    t.marked_last = observations_[i].points[kLast];
    t.marked_edges_trusted = observations_[i].trusted[kFirst] && observations_[i].trusted[kLast];
    t.marked_s = scan.stamp_s;
    t.held = observations_[i].extent_m > kElongated_m &&
             appeared_from_nowhere(scan, segmentation, static_cast<std::int32_t>(i));
    counters_.free_space_held += t.held ? 1 : 0;
    t.cls.object_class = ObjectClass::kDynamic;
    t.cls.dynamic_weight =
        std::max(t.cls.dynamic_weight, config_.classification.dynamic_weight_limit);
    t.cls.still_scans = 0;
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

void DynamicFilter::forget_lost_tracks() {
  const auto lost = [&](const Track& t) {
    return t.missed_scans > config_.tracking.max_missed_scans;
  };
  const auto before = tracks_.size();
  tracks_.erase(std::remove_if(tracks_.begin(), tracks_.end(), lost), tracks_.end());
  counters_.tracks_dropped += static_cast<std::int64_t>(before - tracks_.size());
}

// Step 7: one label per beam from its object's verdict; the beams of dynamic and unknown objects
// become NaN.
void DynamicFilter::label(const LaserScan& scan, const ScanCheck& check, FilterResult& out) {
  out.event = check.event;
  out.filtered = scan;
  out.labels.resize(scan.size());
  out.removed_dynamic = out.removed_unknown = 0;
  const std::vector<std::int32_t>& segment_labels = out.segmentation.beam_labels;
  predict_moving_outlines(scan.stamp_s);
  for (std::size_t b = 0; b < scan.size(); ++b) {
    const std::int32_t l = segment_labels[b];
    BeamLabel label = BeamLabel::kInvalid;
    if (l >= 0 || l == kLabelNoise) label = beam_label(b, l, check.learn);
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
  write_tracks(out);
}

// The label of valid beam @p b of object @p segment_label (or of no object: kLabelNoise). Beyond
// the thesis: a beam of no object beside a dynamic track is one of its fragments; a beam of a
// moving object that ends where something has stood for a while is kept. The beam's point comes
// from place_beams(), once per scan.
BeamLabel DynamicFilter::beam_label(std::size_t b, std::int32_t segment_label, bool learned) {
  const FreeSpaceConfig& fs = config_.free_space;
  const bool check_occupied = learned && fs.enabled && fs.keep_long_occupied;
  const bool explained = !explained_.empty() && explained_[b] != 0;
  if (segment_label == kLabelNoise) {
    if (!learned || !(config_.tracking.fragment_distance_m > 0.0) || explained)
      return BeamLabel::kNoObject;
    const Eigen::Vector2d point = beam_points_[b];
    if (near_dynamic_track(point) &&
        !(check_occupied && free_space_.hit_balance(point) >= fs.max_recent_hits)) {
      ++counters_.beams_removed_fragments;
      return BeamLabel::kDynamic;
    }
    return BeamLabel::kNoObject;
  }
  const ObjectVerdict& v = verdicts_[static_cast<std::size_t>(segment_label)];
  if (v.object_class == ObjectClass::kStatic) return BeamLabel::kStatic;
  if (explained) {
    ++counters_.beams_kept_explained;
    return BeamLabel::kStatic;
  }
  if (check_occupied) {
    const Eigen::Vector2d point = beam_points_[b];
    const bool slow = v.speed_mps <= 2.0 * config_.classification.speed_limit_mps;
    if (slow ? free_space_.hit_balance(point) >= fs.max_recent_hits
             : free_space_.occupied_scans(point) >= fs.long_occupied_scans) {
      ++counters_.beams_kept_long_occupied;
      return BeamLabel::kStatic;
    }
  }
  return v.object_class == ObjectClass::kDynamic ? BeamLabel::kDynamic : BeamLabel::kUnknown;
}

// Whether at least kNowhereShare of object @p object's beams returned nothing in the last learned
// scan, or something more than kNowhereMargin_m farther (see there).
bool DynamicFilter::appeared_from_nowhere(const LaserScan& scan, const Segmentation& segmentation,
                                          std::int32_t object) const {
  const std::size_t n = scan.size();
  if (previous_ranges_.size() != n) return false;
  // Its beams lie from first_beam to last_beam, across the seam of a full circle if need be.
  const ScanObject& o = segmentation.objects[static_cast<std::size_t>(object)];
  const auto first = static_cast<std::size_t>(o.first_beam);
  const std::size_t span = (static_cast<std::size_t>(o.last_beam) + n - first) % n + 1;
  std::int32_t beams = 0, from_nowhere = 0;
  for (std::size_t k = 0; k < span; ++k) {
    const std::size_t b = (first + k) % n;
    if (segmentation.beam_labels[b] != object) continue;
    ++beams;
    const float was = previous_ranges_[b];
    const bool returned = was >= scan.range_min_m && was <= scan.range_max_m;
    if (!returned || was > scan.ranges_m[b] + kNowhereMargin_m) ++from_nowhere;
  }
  return beams > 0 && static_cast<double>(from_nowhere) >= kNowhereShare * beams;
}

// Whether @p track is kept in the scan of @p stamp_s as held (see kNowhereMargin_m).
bool DynamicFilter::held_now(const Track& track, double stamp_s) {
  return track.held && track.free_space_pending && track.marked_s == stamp_s;
}

// How far a track marked by free space has moved since: its centroid's distance from where it
// was, or for an elongated object its motion across itself and, when its edges show it, along.
double DynamicFilter::moved_since_marked(const Track& track, const Observation& obs) {
  const Eigen::Vector2d moved = obs.points[kCentroid] - track.marked_at;
  const Eigen::Vector2d axis = obs.points[kLast] - obs.points[kFirst];
  if (obs.extent_m < kElongated_m || !(axis.norm() > 0.0)) return moved.norm();
  const Eigen::Vector2d along = axis.normalized();
  const double across = moved.dot(Eigen::Vector2d(-along.y(), along.x()));
  double lengthwise = 0.0;
  if (track.marked_edges_trusted && obs.trusted[kFirst] && obs.trusted[kLast]) {
    const double first = (obs.points[kFirst] - track.marked_first).dot(along);
    const double last = (obs.points[kLast] - track.marked_last).dot(along);
    if (std::abs(first - last) <= kEdgesAgree_m) lengthwise = 0.5 * (first + last);
  }
  return std::hypot(across, lengthwise);
}

// Whether an object the map explains moves along itself unlike a static surface's outline, which
// slides only with the sensor (registration.slide_tolerance_mps): both ends its true outline (so
// the centroid is too), and its velocity along itself away from the sensor's along it by more
// than the tolerance.
bool DynamicFilter::slides_unlike_the_sensor(const Track& track, const Observation& obs) const {
  const double tolerance = config_.registration.slide_tolerance_mps;
  if (tolerance <= 0.0 || obs.ambiguous || obs.extent_m < kSlideMinExtent_m ||
      !obs.trusted[kCentroid]) {
    return false;
  }
  const Eigen::Vector2d along = (obs.points[kLast] - obs.points[kFirst]).normalized();
  return std::abs((track.kf[kCentroid].velocity() - sensor_velocity_).dot(along)) > tolerance;
}

// Whether a dynamic track other than @p self, confirmed by its motion (not only by free space) and
// seen in the last few scans, is within companion_distance_m of @p point_m: the other leg of a
// walker whose planted foot has not moved while its free-space evidence was weighed.
bool DynamicFilter::beside_moving_track(const Track& self, const Eigen::Vector2d& point_m) const {
  const double limit = config_.tracking.companion_distance_m;
  if (!(limit > 0.0)) return false;
  for (const Track& t : tracks_) {
    if (&t == &self || !moving_now(t) || t.free_space_pending) continue;
    if ((t.kf[kCentroid].position() - point_m).norm() <= limit) return true;
  }
  return false;
}

DynamicFilter::PredictedOutline::PredictedOutline(const PointVelocityFilter& first,
                                                  const PointVelocityFilter& last, double dt)
    : a(first.predicted_position(dt)),
      ab(last.predicted_position(dt) - a),
      len2(ab.squaredNorm()) {}

double DynamicFilter::PredictedOutline::distance(const Eigen::Vector2d& p) const {
  const double u = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + u * ab)).norm();
}

// The outlines of the dynamic tracks seen in this scan or missed for a few scans at most, each
// predicted to @p stamp_s.
void DynamicFilter::predict_moving_outlines(double stamp_s) {
  moving_outlines_.clear();
  for (const Track& t : tracks_) {
    if (moving_now(t) && !held_now(t, stamp_s))
      moving_outlines_.emplace_back(t.kf[kFirst], t.kf[kLast], stamp_s - t.last_seen_s);
  }
}

bool DynamicFilter::near_dynamic_track(const Eigen::Vector2d& point_m) const {
  const double limit = config_.tracking.fragment_distance_m;
  return std::any_of(moving_outlines_.begin(), moving_outlines_.end(),
                     [&](const PredictedOutline& o) { return o.distance(point_m) <= limit; });
}

// Beyond the thesis (tracking.remove_edge_pixels): a scanner's beam that grazes an object's edge
// returns a range between the object and what lies behind it (a mixed pixel), a point in mid-air
// that is in no object. Beside a removed beam, farther than it and nearer than the beam on its
// other side, each by more than a tenth of the span between those two, it is removed too, unless
// the map explains it. This runs after the map has learned the scan, so the registration sees
// what it saw before the rule: removing the pixels from what the map learns as well moved
// person_following_outdoor_1 (laser-only) from 0.963 to 0.951 of its background kept.
void DynamicFilter::remove_edge_pixels(const LaserScan& scan, FilterResult& out) {
  const std::vector<std::int32_t>& segment_labels = out.segmentation.beam_labels;
  const auto removed = [&out](std::size_t j) {
    return out.labels[j] == BeamLabel::kDynamic || out.labels[j] == BeamLabel::kUnknown;
  };
  edge_pixels_.clear();
  for (std::size_t b = 0; b < scan.size(); ++b) {
    if (out.labels[b] != BeamLabel::kNoObject || segment_labels[b] != kLabelNoise) continue;
    if (!explained_.empty() && explained_[b] != 0) continue;
    const float r = scan.ranges_m[b];
    for (const std::size_t side : {b - 1, b + 1}) {  // b - 1 wraps for b = 0: out of range.
      const std::size_t other = side < b ? b + 1 : b - 1;
      if (side >= scan.size() || other >= scan.size() || !removed(side) || !scan.is_valid(other))
        continue;
      // Clear of both: a beam within a tenth of the span of either side lies on that surface (a
      // wall seen at a slant, in pieces under N_min, goes on smoothly past an occluder's edge).
      const float margin = 0.1F * (scan.ranges_m[other] - scan.ranges_m[side]);
      if (r > scan.ranges_m[side] + margin && r < scan.ranges_m[other] - margin) {
        edge_pixels_.push_back(b);
        break;
      }
    }
  }
  // Decided on the labels before any pixel was removed: a pixel never makes another.
  for (const std::size_t b : edge_pixels_) {
    out.labels[b] = BeamLabel::kDynamic;
    out.filtered.ranges_m[b] = std::numeric_limits<float>::quiet_NaN();
    ++out.removed_dynamic;
    ++counters_.beams_removed_dynamic;
    ++counters_.beams_removed_edge_pixels;
  }
}

// Beyond the thesis (tracking.follow_fragments): a dynamic track that no object matched in this
// scan follows the beams of no object beside its predicted outline (the fragments that
// beam_label() removes with it), when at least two of them, and half of them, lie in space seen
// free. Its centroid is updated with theirs; its edges are re-anchored on the outermost of them
// with their velocity held (a fragment's ends are not the walker's). A walker who walks on until
// each leg is fewer beams than N_min stays followed and removed. Fragments that hold still near
// the sensor (a part of the robot, in space seen free because the robot drives) are let go.
void DynamicFilter::follow_fragments(const LaserScan& scan, const Segmentation& segmentation,
                                     const Pose2& sensor_pose) {
  const double limit = config_.tracking.fragment_distance_m;
  if (!config_.tracking.follow_fragments || !(limit > 0.0) || !config_.free_space.enabled) return;
  const std::vector<std::int32_t>& labels = segmentation.beam_labels;
  const bool have_previous = previous_ranges_.size() == scan.size();
  for (Track& t : tracks_) {
    if (!moving_now(t) || t.object_index >= 0) continue;
    const double dt = scan.stamp_s - t.last_seen_s;
    if (!(dt > 0.0)) continue;
    const PredictedOutline outline(t.kf[kFirst], t.kf[kLast], dt);
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    std::int32_t count = 0, in_free = 0, same_range = 0;
    std::size_t first = 0, last = 0;
    for (std::size_t b = 0; b < scan.size(); ++b) {
      if (labels[b] != kLabelNoise || !scan.is_valid(b)) continue;
      if (!explained_.empty() && explained_[b] != 0) continue;
      const Eigen::Vector2d& p = beam_points_[b];
      if (outline.distance(p) > limit) continue;
      if (count == 0) first = b;
      last = b;
      sum += p;
      ++count;
      if (free_space_.known_free(p)) ++in_free;
      const float r = scan.ranges_m[b];
      if (have_previous && std::abs(previous_ranges_[b] - r) <=
                               kRecurringTolerance_m + kRecurringRelativeTolerance * r) {
        ++same_range;
      }
    }
    if (count < 2 || 2 * in_free < count) {
      t.fragments_still_since_s = -1.0;
      continue;
    }
    const Eigen::Vector2d centroid = sum / static_cast<double>(count);
    // Fragments whose beams return the ranges they returned the scan before, near the sensor,
    // for kAttachedTime_s: a part of the robot, not a walker (whose legs never hold still in the
    // sensor frame); the track lets them go and is static again.
    if (2 * same_range < count || t.fragments_still_since_s < 0.0) {
      t.fragments_still_since_s = scan.stamp_s;
    }
    if (scan.stamp_s - t.fragments_still_since_s >= kAttachedTime_s &&
        (centroid - sensor_pose.translation()).norm() <= kAttachedRange_m) {
      t.cls = initial_class_state(config_.classification);
      t.free_space_pending = false;
      t.fragments_still_since_s = -1.0;
      ++counters_.fragments_let_go;
      continue;
    }
    double speed = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
      PointVelocityFilter& kf = t.kf[k];
      if (k == kCentroid) {
        kf.predict_and_update(centroid, dt, config_.velocity);
      } else {
        kf.predict_and_hold(beam_points_[k == kFirst ? first : last], dt, config_.velocity);
      }
      speed = std::min(speed, kf.velocity().norm());
    }
    t.speed_mps = speed;
    t.last_seen_s = scan.stamp_s;
    t.missed_scans = 0;
    ++counters_.fragment_follows;
  }
}

void DynamicFilter::write_tracks(FilterResult& out) const {
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
