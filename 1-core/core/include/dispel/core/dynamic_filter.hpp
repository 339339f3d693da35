#pragma once
/// @file
/// The dynamic object filter (thesis sections 3.2.1-3.2.4): segments each scan, follows the
/// objects from scan to scan in a fixed frame, estimates their velocity and removes the beams of
/// moving objects before SLAM sees the scan.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "dispel/core/classification.hpp"
#include "dispel/core/dynamic_filter_config.hpp"
#include "dispel/core/free_space_map.hpp"
#include "dispel/core/laser_scan.hpp"
#include "dispel/core/pose2.hpp"
#include "dispel/core/scan_registration.hpp"
#include "dispel/core/segmentation.hpp"
#include "dispel/core/velocity_filter.hpp"

namespace dispel {

/// Per-beam labels of the filtered scan, what <scan>_labels carries in its intensities
/// (docs/dynamic_filter.md, "Beam labels").
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
  kNoPose,              ///< No sensor pose was given (none known at the scan's time) and the
                        ///< registration is off: passed through unchanged.
};
inline constexpr std::size_t kFilterEventCount = 9;

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
  /// Tracks made dynamic by free space that had not moved like a walker 0.4 s later (static
  /// again; docs/dynamic_filter.md, "Per scan", free space).
  std::int64_t free_space_refuted = 0;
  /// Objects longer than a walker that free space marked when they appeared from nowhere, kept
  /// in that first scan (docs/dynamic_filter.md, "A long thing from nowhere waits a scan").
  std::int64_t free_space_held = 0;
  /// Objects free space would have marked but for points the map had seen there before
  /// (free_space.require_unseen).
  std::int64_t free_space_seen_before = 0;
  /// Dynamic tracks static again after standing still alone for
  /// classification.still_alone_to_static_s.
  std::int64_t still_alone_to_static = 0;
  /// Beams of no object removed as fragments of a dynamic track (tracking.fragment_distance_m);
  /// included in beams_removed_dynamic.
  std::int64_t beams_removed_fragments = 0;
  /// Beams of no object removed as the mixed pixels at a removed object's edge
  /// (tracking.remove_edge_pixels); included in beams_removed_dynamic.
  std::int64_t beams_removed_edge_pixels = 0;
  /// Scans in which a dynamic track was followed through fragments (tracking.follow_fragments),
  /// summed over the tracks.
  std::int64_t fragment_follows = 0;
  /// Dynamic tracks that let their fragments go: near the sensor, their beams returned the ranges
  /// of the scan before for kAttachedTime_s (a part of the robot, not a walker).
  std::int64_t fragments_let_go = 0;
  /// Beams of moving or unknown objects kept because the registered map explains them
  /// (registration.explained_*).
  std::int64_t beams_kept_explained = 0;
  /// Registration (when on): scans aligned with the map, scans that fell back to their seed
  /// (odometry or constant velocity), registered scans with an unconstrained direction, and
  /// scans registered without odometry, and scans registered from the constant-velocity guess
  /// because the odometry slipped (RegistrationReport::odometry_overruled), and scans de-skewed
  /// by their registered turn and aligned again (RegistrationReport::realignments), and scans
  /// after which the constant-velocity guess was held at the robot's limits
  /// (RegistrationReport::guess_limited), and laser-only scans whose sideways motion was held
  /// (RegistrationReport::held_sideways).
  std::int64_t scans_registered = 0;
  std::int64_t registration_fallbacks = 0;
  std::int64_t registration_degenerate = 0;
  std::int64_t scans_without_odometry = 0;
  std::int64_t odometry_overruled = 0;
  std::int64_t scans_realigned = 0;
  std::int64_t registration_guess_limited = 0;
  std::int64_t registration_held_sideways = 0;
  /// Voxels of the registered map started afresh: hit again after a time unseen where the
  /// scanner had long seen through (ScanRegistration::add()).
  std::int64_t map_voxels_restarted = 0;
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
/// What the filter did for one scan: the sizes its cost grows with (to tell a slow scan's cause).
struct ScanWork {
  std::int32_t beams = 0;
  std::int32_t objects = 0;  ///< Segmented objects.
  std::int32_t tracks = 0;   ///< Live tracks after the scan.
  std::int32_t registration_points = 0;
  std::int32_t registration_iterations = 0;  ///< Of the alignment kept.
  std::int32_t registration_alignments = 0;  ///< Alignments tried (RegistrationReport).
  std::int32_t registration_total_iterations = 0;
  /// Wall time of the scan's registration and of adding it to the free-space map (steady clock;
  /// 0 when off): where a slow scan's time went.
  double registration_us = 0.0;
  double free_space_us = 0.0;
  std::int64_t map_voxels = 0;                ///< The registration's local map after the scan.
  std::int64_t free_space_tiles_started = 0;  ///< Free-space tiles emptied for this scan.
};

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
  /// The sensor pose the scan was filtered with (registered when the registration is on), in the
  /// filter's fixed frame; unset when the scan was passed through.
  std::optional<Pose2> sensor_pose;
  /// How the scan registered (all zero when the registration is off).
  RegistrationReport registration;
  ScanWork work;
};

/// The dynamic object filter. Feed it scans in time order with the pose of the sensor in a fixed
/// frame (e.g. odom) at each scan's time. Bad input never throws: it is rejected or causes a
/// reset, and FilterResult::event and counters() say which. Not thread-safe.
class DynamicFilter {
 public:
  /// @throws std::invalid_argument if config.validate() does.
  explicit DynamicFilter(DynamicFilterConfig config);
  /// The same, taking the free-space window of @p free_space, made earlier with the same
  /// free-space settings (FreeSpaceMap's constructor from an earlier map).
  DynamicFilter(DynamicFilterConfig config, FreeSpaceMap&& free_space);

  /// Filters one scan (thesis Figure 3.3). @p sensor_pose is the laser frame in the fixed frame
  /// (odometry) at scan.stamp_s, or std::nullopt when none is known. With the registration on,
  /// the scan is registered to the local map, seeded by the pose (or, without one, by constant
  /// velocity: laser-only recordings). With it off, a scan without a pose is passed through
  /// unchanged (FilterEvent::kNoPose) and the tracks wait for the next scan with a pose.
  void process(const LaserScan& scan, const std::optional<Pose2>& sensor_pose, FilterResult& out);

  FilterResult process(const LaserScan& scan, const std::optional<Pose2>& sensor_pose) {
    FilterResult out;
    process(scan, sensor_pose, out);
    return out;
  }

  /// What process() gives for a scan it passes through unchanged with @p event (a rejection, no
  /// pose): the scan as it is, every valid beam "no object" (every beam "invalid" when the scan
  /// fails check_scan()), no tracks. For a caller that passes a scan through without a filter.
  static void pass_through_unfiltered(const LaserScan& scan, FilterEvent event, FilterResult& out);

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
    double explained_share;          // Of its beams, the share the registered map explains.
    Eigen::Vector2d local_centroid;  // In the sensor frame.
    double recurring_share;          // Of its beams, the share that moves with the robot: ending
                                     // where they often end, or beyond the robot's own body.
  };
  // Where a point has stayed, within a tolerance the caller keeps, and since when.
  struct StillSince {
    Eigen::Vector2d at;
    double since_s;
    bool left(const Eigen::Vector2d& p, double tolerance_m) const {
      return (p - at).norm() > tolerance_m;
    }
    void restart(const Eigen::Vector2d& p, double stamp_s) {
      at = p;
      since_s = stamp_s;
    }
  };
  struct Track {
    std::uint64_t id;
    std::array<PointVelocityFilter, 3> kf;
    std::array<bool, 3> trusted;  // Whether each point was measured reliably in the last scan.
    ClassState cls;
    double last_seen_s;
    double born_s;  // When it (or the track it split from) was first seen.
    std::int32_t age_scans;
    std::int32_t missed_scans;
    std::int32_t point_count;
    double extent_m;
    double speed_mps;
    std::int32_t object_index;
    // Where the object stands in the sensor frame, and since when it has stood there: a part of
    // the robot (or something it carries) moves with the sensor.
    StillSince local_still;
    // Where a dynamic track's centroid has stayed (within kStillRadius_m) since when, and whether
    // it was first seen there after scans unseen (classification.still_alone_to_static_s).
    StillSince still;
    bool still_since_unseen = false;
    // Dynamic because it appeared in space seen free, not yet confirmed by its own motion: where
    // and when it was. Something that then stays put was there all along, below or above the
    // scan plane where the beams passed (a chair seat, a shelf's edge: a tilted plane sees it
    // only within some range); it is static again and free space never marks it again.
    bool free_space_pending = false;
    bool free_space_refuted = false;
    // Marked when older than free space asks about, because it stood beside a dynamic track (a
    // walker's other leg): confirmed only by its own motion, not by standing beside one.
    bool marked_beside = false;
    Eigen::Vector2d marked_at = Eigen::Vector2d::Zero();
    // Its edges then, and whether both were its outline (see kElongated_m).
    Eigen::Vector2d marked_first = Eigen::Vector2d::Zero();
    Eigen::Vector2d marked_last = Eigen::Vector2d::Zero();
    bool marked_edges_trusted = false;
    double marked_s = 0.0;
    // Marked in its first scan as a thing longer than a walker where nothing was near in the scan
    // before: kept in that scan (see kNowhereMargin_m).
    bool held = false;
    bool attached = false;  // Judged part of the robot in the last scan it was seen.
    // Since when the fragments it follows have returned the ranges of the scan before (-1: not
    // following such fragments).
    double fragments_still_since_s = -1.0;
  };

  // What the first step decides about a scan.
  struct ScanCheck {
    FilterEvent event = FilterEvent::kFiltered;
    bool rejected = false;  // Passed through unchanged.
    bool learn = true;      // Tracks are updated (false for a repeated stamp).
  };

  // The steps of process(), in order (thesis Figure 3.3).
  ScanCheck check(const LaserScan& scan, const std::optional<Pose2>& sensor_pose);
  void place_beams(const LaserScan& scan, const Pose2& sensor_pose, bool registered);
  void observe(const Segmentation& segmentation, const Pose2& sensor_pose, float range_max_m);
  void explain(const LaserScan& scan, const Segmentation& segmentation);
  static double moved_since_marked(const Track& track, const Observation& obs);
  bool appeared_from_nowhere(const LaserScan& scan, const Segmentation& segmentation,
                             std::int32_t object) const;
  static bool held_now(const Track& track, double stamp_s);
  bool beside_moving_track(const Track& self, const Eigen::Vector2d& point_m) const;
  bool slides_unlike_the_sensor(const Track& track, const Observation& obs) const;
  void recur(const LaserScan& scan, const Segmentation& segmentation, const Pose2& sensor_pose,
             bool learn);
  void match(double stamp_s);
  void update_velocities(double stamp_s);
  void classify(const LaserScan& scan, const Pose2& sensor_pose, const Segmentation& segmentation);
  void label(const LaserScan& scan, const ScanCheck& check, FilterResult& out);
  void learn_body(const LaserScan& scan, const Segmentation& segmentation);

  // Step 1.
  void pass_through(const LaserScan& scan, FilterEvent event, FilterResult& out);
  /// Fills out.work (the sizes of what this scan cost).
  void record_work(const LaserScan& scan, FilterResult& out);
  // Step 4 (track_matching.cpp).
  void find_split_parents(double stamp_s);
  void associate_nearest();
  void associate_global(double stamp_s);
  void rescue_by_edges(double stamp_s);
  bool similar_extent(const Observation& obs, const Track& track) const;
  // Steps 5 and 6.
  void update_class(Track& track, const Observation& obs, double stamp_s);
  void start_tracks(double stamp_s);
  void mark_objects_in_free_space(const LaserScan& scan, const Segmentation& segmentation);
  void spread_to_companions();
  void forget_lost_tracks();
  Track new_track(const Observation& obs, double stamp_s, std::int32_t object_index);
  // Step 7.
  BeamLabel beam_label(std::size_t b, std::int32_t segment_label, bool learned);
  /// The outlines (edge to edge) of the tracks moving now, predicted to @p stamp_s, into
  /// moving_outlines_: once per scan for the registration, once for the labels.
  void predict_moving_outlines(double stamp_s);
  /// Whether a point lies within fragment_distance_m of one of moving_outlines_.
  bool near_dynamic_track(const Eigen::Vector2d& point_m) const;
  void follow_fragments(const LaserScan& scan, const Segmentation& segmentation,
                        const Pose2& sensor_pose);
  void remove_edge_pixels(const LaserScan& scan, FilterResult& out);
  void write_tracks(FilterResult& out) const;

  DynamicFilterConfig config_;
  Segmenter segmenter_;
  FilterCounters counters_;
  std::vector<Track> tracks_;
  FreeSpaceMap free_space_;
  double registration_us_ = 0.0;  // This scan's stage times (ScanWork).
  double free_space_us_ = 0.0;
  ScanRegistration registration_;
  std::vector<char> explained_;                // Per beam of this scan (registration on).
  BeamDirections directions_;                  // The scanner's beam directions.
  std::vector<Eigen::Vector2d> beam_points_;   // Per beam of this scan, fixed frame (NaN: invalid).
  std::vector<std::int32_t> explained_count_;  // Scratch: per object.
  // Ranges each beam has often returned: per beam, kRecurringSlots ranges, each with the share of
  // recent scans that returned it (an exponential average, decayed lazily: its value and the scan
  // it was last brought up to date). Whatever moves with the sensor (a part of the robot, even
  // one that flickers in and out of the scan; a return the scanner repeats) is at the same
  // ranges of the same beams scan after scan; the world, seen from a moving robot, is not.
  struct RecurringRange {
    float range_m = 0.0F;
    float share = 0.0F;
    std::uint32_t scan = 0;
  };
  static constexpr std::size_t kRecurringSlots = 2;
  std::vector<RecurringRange> recurring_;  // kRecurringSlots per beam.
  std::uint32_t recurring_scans_ = 0;      // Scans counted (see recur()).
  std::optional<Pose2> recurring_pose_;    // The sensor's pose at the last scan counted.
  bool recurring_counted_ = false;         // Whether this scan is counted.
  // Per beam, the range at which it returns the robot's own body (an object judged part of the
  // robot), with the share of the scans counted that returned it there (decayed lazily, as
  // RecurringRange). What such a beam returns well beyond that range moves with the robot.
  std::vector<RecurringRange> body_;
  std::vector<float> previous_ranges_;  // The last learned scan's ranges.
  std::vector<char> attached_;  // Scratch: per object of this scan, judged part of the robot.
  std::vector<double> spacing_limit_;             // Scratch: per object, for free-space evidence,
  std::vector<double> points_needed_;             // the points in free space that would mark it,
  std::vector<std::int32_t> points_in_free_;      // and those found,
  std::vector<std::int32_t> points_seen_before_;  // and those the map saw there before.
  bool laser_only_ = false;  // The scan being processed has no odometry (registered alone).
  std::vector<char> keep_;   // Scratch: beams the map learns.
  std::vector<std::size_t> edge_pixels_;  // Scratch: remove_edge_pixels().
  struct PredictedOutline {  // A track's outline (edge to edge), predicted dt after it was seen.
    PredictedOutline(const PointVelocityFilter& first, const PointVelocityFilter& last, double dt);
    double distance(const Eigen::Vector2d& p) const;
    Eigen::Vector2d a, ab;  // The segment from a to a + ab.
    double len2;
  };
  std::vector<PredictedOutline> moving_outlines_;  // predict_moving_outlines().
  std::optional<Pose2> previous_input_pose_;       // The pose given with the previous scan.
  std::uint64_t next_id_ = 1;
  bool have_previous_ = false;
  double previous_stamp_s_ = 0.0;
  Eigen::Vector2d previous_position_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d sensor_velocity_ = Eigen::Vector2d::Zero();
  // For segmentation.min_width_m: the last scans' beam end points (fixed frame, NaN: invalid),
  // poses and geometry, the latest first; whether a small thing was there in each (seen_before()).
  struct EarlierScan {
    std::vector<Eigen::Vector2d> points;
    Pose2 sensor_pose;
    double angle_min_rad = 0.0;
    double increment_rad = 0.0;
    bool full_circle = false;  // As its segmentation found it.
    bool has_return_near(const Eigen::Vector2d& point_m, double radius_m) const;
  };
  std::array<EarlierScan, 2> earlier_scans_;
  std::size_t earlier_count_ = 0;  // Of earlier_scans_ held since the last reset.
  bool seen_before(const Eigen::Vector2d& point_m) const;

  // Per scan, reused between scans: one entry per object of the segmentation.
  std::vector<Observation> observations_;
  std::vector<std::int32_t> track_of_object_;   // Step 4: the matched track, or -1.
  std::vector<std::int32_t> parent_of_object_;  // Step 4: the track an unmatched object split from.
  struct ObjectVerdict {  // Step 6: the class and speed of each object's track.
    ObjectClass object_class;
    double speed_mps;
  };
  std::vector<ObjectVerdict> verdicts_;
  // Scratch of the global matching.
  std::vector<double> cost_;
  std::vector<std::int32_t> component_;
};

}  // namespace dispel
