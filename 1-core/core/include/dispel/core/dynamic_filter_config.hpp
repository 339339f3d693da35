#pragma once
/// @file
/// Configuration of the dynamic object filter, its two presets and their carry-over to another
/// scanner. `DynamicFilterConfig{}` is dispel's default; `thesis_config()` is the thesis's filter
/// (Appendix A and its rules, nothing beyond it). docs/dynamic_filter.md explains each difference.

#include "dispel/core/classification.hpp"
#include "dispel/core/free_space_map.hpp"
#include "dispel/core/scan_registration.hpp"
#include "dispel/core/segmentation.hpp"
#include "dispel/core/velocity_filter.hpp"

namespace dispel {

/// How objects of a new scan are matched to remembered tracks.
enum class Matching {
  /// The thesis's: each object takes the nearest track (by its last seen centroid) within D;
  /// pairs are taken closest first, each track once.
  kNearestNeighbour,
  /// dispel's: minimum total cost over all objects and tracks at once (Hungarian method),
  /// comparing the object's edges and centroid with the track's, predicted to the scan's time by
  /// their velocities; gated by D on the centroid. Keeps identities when people pass each other.
  kGlobal,
};

/// Parameters of the tracking. Defaults are dispel's.
struct TrackingConfig {
  /// D: an object matches a track only when their centroids are at most this far apart.
  double match_distance_m = 0.25;
  /// Global matching only: D holds for one nominal scan period (velocity.nominal_scan_period_s);
  /// for a track last seen dt ago the gate is D * dt / period, up to this many metres, for the
  /// motion its velocity estimate does not know yet (a 10 Hz scanner, missed scans, a person
  /// coming back out of a masked sector).
  double max_gate_m = 2.0;
  /// Global matching only: an object and a track whose extents (distance between the edge points)
  /// differ by more than this (metres, or half the larger extent if more) never match, so that a
  /// person's track does not take over a piece of wall or a pillar of a similar width.
  double max_extent_change_m = 0.2;
  Matching matching = Matching::kGlobal;
  /// A track not matched for more scans than this is forgotten. 40 scans (2 s at 20 Hz) keeps
  /// people who walk through a masked sector.
  int max_missed_scans = 40;
  /// An object that matches no track but lies within D of a track seen in this scan (a person
  /// whose legs split apart, a wall cut by a walker's shadow) starts its track with that track's
  /// class, weights and velocity instead of from scratch (the thesis has no such rule).
  bool inherit_on_split = true;
  /// A track seen in the same scan within this distance of a dynamic track, moving (faster than
  /// L_v) with a velocity within companion_speed_difference_mps of it, is dynamic too: the other
  /// leg of a walker. 0 turns it off (the thesis has no such rule).
  double companion_distance_m = 0.6;
  double companion_speed_difference_mps = 0.5;
  /// Beams of no object (pieces smaller than N_min: a leg half hidden behind the other, a foot at
  /// the edge of the view) within this distance of a dynamic track's outline (the segment between
  /// its edge points, predicted to the scan's time) belong to it and are removed too. 0: off (the
  /// thesis keeps every beam of no object).
  double fragment_distance_m = 0.3;
  /// A dynamic track that no object matched is followed through the beams of no object within
  /// fragment_distance_m of its predicted outline, when there are at least two and at least half
  /// of them lie in space seen free (free_space, which it needs): a walker gone too far, or too
  /// hidden, to make N_min beams stays tracked, and its beams removed, instead of coasting and
  /// being forgotten. Half in space seen free: without it a false dynamic track on a real recording
  /// walked for 2.5 s along small static things. false: off (the thesis has no such rule).
  bool follow_fragments = true;
  /// A beam of no object beside a removed beam, farther than it and nearer than the beam on its
  /// other side (each by more than a tenth of the span between them), is removed with it: the
  /// mixed pixel at a moving object's edge (a return between the object and what lies behind it),
  /// a point in mid-air that moves with the walker. A few of them kept in every scan were what a
  /// SLAM engine locked onto in a corridor. Not when the map explains it. Applied after the map
  /// has learned the scan. false: off (the thesis keeps every beam of no object).
  bool remove_edge_pixels = true;

  /// Throws std::invalid_argument naming the first bad field and its value.
  void validate() const;
};

/// Everything the filter needs. The member defaults are dispel's default configuration, the one
/// its tools use (config/default.yaml lists every key with its value).
struct DynamicFilterConfig {
  SegmentationConfig segmentation;
  TrackingConfig tracking;
  VelocityFilterConfig velocity;
  ClassificationConfig classification;
  /// Beyond the thesis: an object that appears where beams used to pass freely is dynamic at
  /// once, and beams ending where something has stood for long are kept.
  FreeSpaceConfig free_space;
  /// Beyond the thesis: each scan is registered to a local map of what has stayed static (the
  /// odometry only seeds it; without odometry a constant-velocity guess does), and an object the
  /// map explains (a surface seen in many scans over time) is not moving, however its outline
  /// slides while the robot drives past it.
  RegistrationConfig registration;
  /// A larger gap between two scans resets the tracks (they can no longer be followed).
  double max_time_gap_s = 1.0;
  /// A change of the sensor pose between two consecutive scans larger than the robot can drive in
  /// the time between them (max_speed_mps, max_turn_rate_radps) by more than max_pose_jump_m or
  /// max_pose_jump_rad is a jump of the fixed frame (odometry reset, relocalisation), not motion:
  /// the tracks are reset. (A fixed limit reset a scanner at 4 Hz on a robot at 1.3 m/s at every
  /// other scan.) The registration's constant-velocity guess is held within the same limits
  /// (SpeedLimits).
  double max_pose_jump_m = 0.5;
  double max_pose_jump_rad = 0.5;
  double max_speed_mps = 3.0;
  double max_turn_rate_radps = 3.0;

  /// Validates every component; throws std::invalid_argument naming the field.
  void validate() const;
};

/// The thesis's filter: its parameters (Appendix A: eps 0.1 m, N_min 8, D 0.25 m, L_d 18, L_s 50,
/// L_v 0.08 m/s, sigma_p^2 0.75, sigma_v^2 1.5, sigma_m^2 15, gamma 0.8) and its rules: gaps as
/// |r1 - r2|, nearest-neighbour matching, "dynamic for good", weights that only grow; every rule
/// beyond it off (split inheritance, companions, fragments, free space, registration). Where the
/// thesis gives no value (how long an unseen track is kept, the time gap and pose jump that reset
/// the tracks) the values are dispel's earlier ones: 10 missed scans, 1 s, 0.5 m and 0.5 rad.
DynamicFilterConfig thesis_config();

/// The thesis's parameters were chosen for its scanner: 0.17 degrees between beams, 20 Hz. Returns
/// @p config with the counts that depend on the scanner carried over to another one: N_min in
/// proportion to the beams an object of a given width covers (at least 3), and the weight limits
/// L_d and L_s (and still_scans_to_static) in proportion to the scans in the same time (at least
/// 1). Distances, speeds and variances are physical and stay. Throws std::invalid_argument on a
/// non-positive argument.
DynamicFilterConfig scale_to_scanner(DynamicFilterConfig config, double angle_increment_rad,
                                     double scan_period_s);

}  // namespace dispel
