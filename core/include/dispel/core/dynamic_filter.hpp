#pragma once
/// @file
/// The dynamic object filter (thesis sections 3.2.1-3.2.4): segments each scan, follows the
/// objects from scan to scan in a fixed frame, estimates their velocity and removes the beams of
/// moving objects before SLAM sees the scan.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "dispel/core/classification.hpp"
#include "dispel/core/free_space_map.hpp"
#include "dispel/core/laser_scan.hpp"
#include "dispel/core/pose2.hpp"
#include "dispel/core/segmentation.hpp"
#include "dispel/core/velocity_filter.hpp"

namespace dispel {

/// How objects of a new scan are matched to remembered tracks.
enum class Matching {
  /// The thesis's: each object takes the nearest track (by its last seen centroid) within D;
  /// pairs are taken closest first, each track once.
  kNearestNeighbour,
  /// Minimum total cost over all objects and tracks at once (Hungarian method), comparing the
  /// object's edges and centroid with the track's, predicted to the scan's time by their
  /// velocities; gated by D on the centroid. Keeps identities when people pass each other.
  kGlobal,
};

/// Parameters of the tracking.
struct TrackingConfig {
  /// D: an object matches a track only when their centroids are at most this far apart.
  double match_distance_m = 0.25;
  /// Global matching only: D holds for one nominal scan period (velocity.nominal_scan_period_s);
  /// for a track last seen dt ago the gate is D * dt / period, up to this many metres, for the
  /// motion its velocity estimate does not know yet (a 10 Hz scanner, missed scans).
  double max_gate_m = 1.0;
  /// Global matching only: an object and a track whose extents (distance between the edge points)
  /// differ by more than this (metres, or half the larger extent if more) never match, so that a
  /// person's track does not take over a piece of wall.
  double max_extent_change_m = 0.5;
  Matching matching = Matching::kGlobal;
  /// A track not matched for more scans than this is forgotten.
  int max_missed_scans = 10;
  /// An object that matches no track but lies within D of a track seen in this scan (a person
  /// whose legs split apart, a wall cut by a walker's shadow) starts its track with that track's
  /// class, weights and velocity instead of from scratch.
  bool inherit_on_split = true;
  /// A track seen in the same scan within this distance of a dynamic track, moving (faster than
  /// L_v) with a velocity within companion_speed_difference_mps of it, is dynamic too: the other
  /// leg of a walker. 0 turns it off (the thesis has no such rule).
  double companion_distance_m = 0.0;
  double companion_speed_difference_mps = 0.5;
  /// Beams of no object (pieces smaller than N_min: a leg half hidden behind the other, a foot at
  /// the edge of the view) within this distance of a dynamic track's outline (the segment between
  /// its edge points, predicted to the scan's time) belong to it and are removed too. 0: off (the
  /// thesis keeps every beam of no object).
  double fragment_distance_m = 0.0;

  /// Throws std::invalid_argument naming the first bad field and its value.
  void validate() const;
};

/// Everything the filter needs. The member defaults are the thesis's parameters (Appendix A) with
/// everything beyond the thesis off: thesis_config(). dispel's default configuration, the one its
/// tools use, is default_config().
struct DynamicFilterConfig {
  SegmentationConfig segmentation;
  TrackingConfig tracking;
  VelocityFilterConfig velocity;
  ClassificationConfig classification;
  /// Beyond the thesis: an object that appears where beams used to pass freely is dynamic at
  /// once, and beams ending where something has stood for long are kept (off in thesis_config(),
  /// on in default_config()).
  FreeSpaceConfig free_space;
  /// A larger gap between two scans resets the tracks (they can no longer be followed).
  double max_time_gap_s = 1.0;
  /// A larger change of the sensor pose between two consecutive scans is a jump of the fixed
  /// frame (odometry reset, relocalisation), not motion: the tracks are reset.
  double max_pose_jump_m = 0.5;
  double max_pose_jump_rad = 0.5;

  /// Validates every component; throws std::invalid_argument naming the field.
  void validate() const;
};

/// The thesis's filter: its parameters (Appendix A), nothing beyond it. DynamicFilterConfig{}.
DynamicFilterConfig thesis_config();

/// dispel's default: the thesis's filter with the changes that bring its simulated hall to the
/// targets (docs/dynamic_filter.md, "The default configuration"): a velocity filter that follows a
/// walker within a few scans (sigma_m^2 0.1, sigma_p^2 0.001), L_d 8, tracks kept through masked
/// sectors (40 missed scans, gate 2 m), extent change 0.2 m, the companion rule (0.6 m), fragments
/// of dynamic tracks removed (0.3 m), and free-space evidence (neighbourhood 3 cells, memory 30 s,
/// long-occupied cells kept).
DynamicFilterConfig default_config();

/// The thesis's parameters were chosen for its scanner: 0.17 degrees between beams, 20 Hz. Returns
/// @p config with the counts that depend on the scanner carried over to another one: N_min in
/// proportion to the beams an object of a given width covers (at least 3), and the weight limits
/// L_d and L_s in proportion to the scans in the same time (at least 1). Distances, speeds and
/// variances are physical and stay. Throws std::invalid_argument on a non-positive argument.
DynamicFilterConfig scale_to_scanner(DynamicFilterConfig config, double angle_increment_rad,
                                     double scan_period_s);

/// Per-beam labels of the filtered scan (DESIGN.md, "Beam codes").
enum class BeamLabel : std::uint8_t {
  kStatic = 0,    ///< Part of a static object: kept.
  kDynamic = 1,   ///< Part of a dynamic object: removed (NaN).
  kUnknown = 2,   ///< Part of an object not yet classified (POG only): removed (NaN).
  kNoObject = 3,  ///< Valid beam in no object (noise below N_min): kept.
  kInvalid = 4,   ///< Invalid range or masked sector: untouched.
};

/// What the filter did with one scan.
enum class FilterEvent : std::uint8_t {
  kFiltered,            ///< Tracked and filtered normally.
  kFirstScan,           ///< Filtered; no earlier scan, so no velocities yet.
  kRejectedScan,        ///< The scan failed check_scan(): passed through unchanged.
  kRejectedPose,        ///< The pose has NaN or infinite values: passed through unchanged.
  kRepeatedStamp,       ///< Same stamp as the previous scan: labelled from the tracks as they
                        ///< are, without updating them.
  kResetTimeBackwards,  ///< The stamp is earlier than the previous one: tracks reset.
  kResetTimeGap,        ///< More than max_time_gap_s since the previous scan: tracks reset.
  kResetPoseJump,       ///< The sensor pose jumped: tracks reset.
};
inline constexpr std::size_t kFilterEventCount = 8;

/// Stable short name of an event, e.g. "reset_time_backwards" (for counters and JSON keys).
const char* filter_event_name(FilterEvent event);

/// Running totals since the filter was made.
struct FilterCounters {
  std::int64_t scans = 0;                                         ///< Scans given to process().
  std::array<std::int64_t, kFilterEventCount> events{};           ///< Scans per FilterEvent.
  std::array<std::int64_t, kScanIssueCount> rejected_by_issue{};  ///< kRejectedScan by reason.
  std::int64_t tracks_created = 0;
  std::int64_t tracks_dropped = 0;  ///< Forgotten after max_missed_scans, or by a reset.
  std::int64_t beams_removed_dynamic = 0;
  std::int64_t beams_removed_unknown = 0;
  /// Beams of dynamic tracks kept because they end where something has stood for a while
  /// (free_space.keep_long_occupied).
  std::int64_t beams_kept_long_occupied = 0;
  /// Beams of no object removed as fragments of a dynamic track (tracking.fragment_distance_m);
  /// included in beams_removed_dynamic.
  std::int64_t beams_removed_fragments = 0;
};

/// A tracked object as reported to the caller. Positions and velocities are in the fixed frame.
struct TrackedObject {
  std::uint64_t id = 0;  ///< Unique for the life of the filter; 1, 2, ...
  ObjectClass object_class = ObjectClass::kStatic;
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();    ///< Centroid estimate.
  Eigen::Vector2d velocity_mps = Eigen::Vector2d::Zero();  ///< Centroid velocity estimate.
  Eigen::Vector2d first_edge_m = Eigen::Vector2d::Zero();  ///< First edge point estimate.
  Eigen::Vector2d last_edge_m = Eigen::Vector2d::Zero();   ///< Last edge point estimate.
  double speed_mps = 0.0;  ///< Lowest of the three points' speeds (what is compared with L_v).
  std::int32_t dynamic_weight = 0;
  std::int32_t static_weight = 0;
  std::int32_t age_scans = 0;     ///< Scans since the track started.
  std::int32_t missed_scans = 0;  ///< Consecutive scans without a match (0 when seen now).
  /// Index into this scan's Segmentation::objects, or -1 when not seen in this scan.
  std::int32_t object_index = -1;
};

/// The result of filtering one scan.
struct FilterResult {
  FilterEvent event = FilterEvent::kFiltered;
  /// The input scan with removed beams set to NaN (REP 117); unchanged when rejected.
  LaserScan filtered;
  /// One label per beam (empty only when the scan has no beams).
  std::vector<BeamLabel> labels;
  /// Every live track after this scan.
  std::vector<TrackedObject> tracks;
  /// The segmentation of this scan (empty when rejected).
  Segmentation segmentation;
  /// Beams removed in this scan.
  std::int32_t removed_dynamic = 0;
  std::int32_t removed_unknown = 0;
};

/// The dynamic object filter. Feed it scans in time order with the pose of the sensor in a fixed
/// frame (e.g. odom) at each scan's time. Bad input never throws: it is rejected or causes a
/// reset, and FilterResult::event and counters() say which. Not thread-safe.
class DynamicFilter {
 public:
  /// @throws std::invalid_argument if config.validate() does.
  explicit DynamicFilter(DynamicFilterConfig config);

  /// Filters one scan. @p sensor_pose is the laser frame in the fixed frame at scan.stamp_s.
  void process(const LaserScan& scan, const Pose2& sensor_pose, FilterResult& out);

  FilterResult process(const LaserScan& scan, const Pose2& sensor_pose) {
    FilterResult out;
    process(scan, sensor_pose, out);
    return out;
  }

  /// Forgets every track (as after a jump in time or pose).
  void reset();

  const DynamicFilterConfig& config() const { return config_; }
  const FilterCounters& counters() const { return counters_; }
  std::size_t track_count() const { return tracks_.size(); }

 private:
  // The three tracked points of an object: first edge, last edge, centroid.
  static constexpr int kFirst = 0, kLast = 1, kCentroid = 2;

  struct Observation {  // One segmented object, in the fixed frame.
    std::array<Eigen::Vector2d, 3> points;
    std::array<bool, 3> trusted;
    bool ambiguous;  // Touches the field-of-view end or a masked sector.
    double extent_m;
    std::int32_t point_count;
  };
  struct Track {
    std::uint64_t id;
    std::array<PointVelocityFilter, 3> kf;
    std::array<bool, 3> trusted;  // Whether each point was measured reliably in the last scan.
    ClassState cls;
    double last_seen_s;
    std::int32_t age_scans;
    std::int32_t missed_scans;
    std::int32_t point_count;
    double extent_m;
    double speed_mps;
    std::int32_t object_index;
  };

  void pass_through(const LaserScan& scan, FilterEvent event, FilterResult& out);
  void associate(double stamp_s, std::vector<std::int32_t>& track_of_object);
  void associate_nearest(std::vector<std::int32_t>& track_of_object);
  void associate_global(double stamp_s, std::vector<std::int32_t>& track_of_object);
  void rescue_by_edges(double stamp_s, std::vector<std::int32_t>& track_of_object);
  bool similar_extent(const Observation& obs, const Track& track) const;
  void spread_to_companions();
  void mark_objects_in_free_space(const LaserScan& scan, const Pose2& sensor_pose,
                                  const Segmentation& segmentation);
  void update_track(Track& track, const Observation& obs, double stamp_s);
  bool near_dynamic_track(const Eigen::Vector2d& point_m, double stamp_s) const;
  Track new_track(const Observation& obs, double stamp_s, std::int32_t object_index);
  void write_output(FilterResult& out);

  DynamicFilterConfig config_;
  Segmenter segmenter_;
  FilterCounters counters_;
  std::vector<Track> tracks_;
  FreeSpaceMap free_space_;
  std::uint64_t next_id_ = 1;
  bool have_previous_ = false;
  double previous_stamp_s_ = 0.0;
  Pose2 previous_pose_;

  // Scratch reused between scans.
  std::vector<Observation> observations_;
  std::vector<std::int32_t> track_of_object_;
  std::vector<std::int32_t> object_class_label_;
  std::vector<double> cost_;
  std::vector<std::int32_t> component_;
};

}  // namespace dispel
