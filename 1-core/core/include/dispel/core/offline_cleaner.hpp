#pragma once
/// @file
/// The offline cleaner (`dispel clean`): a second look at a whole recording that the online filter
/// has already been through. An online filter sees only the past: someone who stands still until
/// after the recording's last scan of them is kept, and an object is removed only from the scan in
/// which it is found moving. With every scan at hand the cleaner also removes
/// - the beams of an object (a track of the online filter) that was found moving at some time,
///   from the first scan in which it was seen until it last moved (retroactive removal; where it
///   was not found moving, only once the scanner saw through its place after it moved on), and
/// - optionally (CleanConfig::through_min_scans), a small thing whose place the scanner saw
///   through later or earlier (what stood there left, or was not there yet),
/// - legs at range, too few beams for an object of the online filter's: runs of beams in no object
///   that it links from scan to scan itself, when they walked (CleanConfig::leg_walk_m),
/// and keeps what the online filter took for moving only for a moment and never again (a wall
/// piece whose outline slid for a scan or two). Both directions in time: what an object did later
/// decides about its earlier beams, and what the scanner saw at other times decides about a place.
///
/// Beams are placed where they were measured: the sensor moves during a sweep (time_increment),
/// at the pace it moved since the scan before.
///
/// Memory: per scan, its stamp, pose, motion and geometry (about 100 bytes), five bytes per beam
/// (the online label, the online object, the range in cm) and 13 per object (its track, the
/// track's position, its width); per track a summary (about 100 bytes) and 12 bytes per scan in
/// which it was dynamic; per run of beams in no object 24 bytes, and 4 in its chain.

#include <cmath>
#include <cstdint>
#include <optional>
#include <unordered_map>
#include <vector>

#include "dispel/core/dynamic_filter.hpp"
#include "dispel/core/laser_scan.hpp"
#include "dispel/core/pose2.hpp"

namespace dispel {

/// Parameters of the offline cleaner. Defaults are dispel's.
struct CleanConfig {
  /// A track counts as moving when the online filter labelled it dynamic in at least this many
  /// scans (a wall piece whose outline slid is dynamic for a scan or two).
  int moving_min_scans = 3;
  /// ... and, in those scans, its centroid moved at least this far (m) from where it was first
  /// dynamic. Not from where it was first seen: on a real robot's laser-only poses a wall piece's
  /// centroid drifts metres over the seconds it is tracked as static.
  double moving_min_travel_m = 0.5;
  /// A moving track's object in a scan in which it was not found moving is removed only within
  /// this distance (m) of where the track was found moving nearest in time: a track that took
  /// over a piece of wall for a while does not take the wall with it.
  double moved_from_m = 1.0;
  /// The cleaner removes (beyond what the online filter removed) only objects at most this wide
  /// (m), and beams in no object: a person, two legs, a cart. A track that ended on a walker
  /// passing a wall took the wall piece with it.
  double max_width_m = 1.5;
  /// Such a beam is removed when this many scans saw through its place, from through_gap_s to
  /// through_horizon_s after it (or before it), before one hit it again: what stood there left
  /// (or was not there yet); decided per object (or run of beams in no object) by the majority
  /// of its beams. 0: off, the default: on the real negative_2 (no people) it removed 0.7-2.1 %
  /// of the beams (docs/clean.md).
  int through_min_scans = 0;
  double through_gap_s = 1.0;
  double through_horizon_s = 20.0;
  /// The poses are exact (a sensor that does not move: `--static-sensor`). Then the rule above
  /// looks past scans that hit the place: N scans in a row anywhere within the horizon that saw
  /// through it, with no hit among them, are enough (what is there came and stood a while, or
  /// stood a while and left). On a moving robot's poses a few centimetres of error grow over
  /// seconds, and a wall looked at long enough is seen through at last: there the first hit ends
  /// the look (on the real negative_2, looking past hits removed 24-30 % of the beams).
  bool poses_exact = false;
  /// Seeing through a place: the beam toward it and both beside it returned from at least this
  /// far (m) beyond it (range noise, a wall seen at a slant), or nothing returned.
  double free_margin_m = 0.3;
  /// Places farther than this (m) from the scanner are not asked about.
  double max_range_m = 20.0;
  /// Legs at range: runs of beams in no object (too few for N_min), narrow, in front of what is
  /// beside them, are linked from scan to scan into chains. The runs of a chain that went at least
  /// this far (m) from where it began are removed while it moved, and before that where the
  /// scanner saw through the place after it left (label kWalkedLeg). 0: off.
  double leg_walk_m = 1.0;
  /// A chain links runs at most this far apart in time (s). A far leg is missed in a scan now
  /// and then; a sporadic return (speckle) is there in one scan and not in the next ones.
  double leg_max_gap_s = 0.3;

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

/// What the cleaner says of a beam (`<scan>_clean_labels`).
enum class CleanLabel : std::uint8_t {
  kStatic = 0,      ///< Kept: part of a static object.
  kDynamic = 1,     ///< Removed: the online filter found it moving, and the cleaner agrees.
  kUnknown = 2,     ///< Removed: the online filter's unknown (POG).
  kNoObject = 3,    ///< Kept: in no object.
  kInvalid = 4,     ///< No usable range: untouched.
  kMovedLater = 5,  ///< Removed: its object moved at another time (or stood where one set off).
  kVacated = 6,   ///< Removed: the scanner saw through its place later or earlier (it left, came).
  kRestored = 7,  ///< Kept: the online filter removed it, but its object never moved.
  /// Removed: in no object (a leg at range, too few beams for one) on a chain of such runs of
  /// beams that walked (CleanConfig::leg_walk_m).
  kWalkedLeg = 8,
};

/// True for the labels whose beams are removed (NaN in `<scan>_clean`).
inline bool removed(CleanLabel label) {
  return label == CleanLabel::kDynamic || label == CleanLabel::kUnknown ||
         label == CleanLabel::kMovedLater || label == CleanLabel::kVacated ||
         label == CleanLabel::kWalkedLeg;
}

/// The label a labels topic's intensity holds (`<scan>_clean_labels`, or `<scan>_labels`, whose
/// BeamLabel values 0-4 mean the same); nothing for a value that is no label (negative, above 8,
/// fractional, NaN).
inline std::optional<CleanLabel> clean_label(float value) {
  if (!(value >= 0.0F && value <= 8.0F) || value != std::floor(value)) return std::nullopt;
  return static_cast<CleanLabel>(static_cast<std::uint8_t>(value));
}

/// One object (an online track) over the recording: when it was seen, moving, and removed.
struct CleanedObject {
  std::uint64_t track_id = 0;
  double first_seen_s = 0.0, last_seen_s = 0.0;
  std::int32_t scans = 0;          ///< Scans in which it was seen.
  std::int32_t dynamic_scans = 0;  ///< Of them, labelled dynamic by the online filter.
  double first_dynamic_s = 0.0, last_dynamic_s = 0.0;  ///< When it was (0 when never).
  double travel_m = 0.0;  ///< Largest distance of its centroid from where it was first seen.
  /// Largest distance of its centroid, in the scans in which it was dynamic, from where it was
  /// first dynamic: what decides `moving` (a static thing's centroid can slide while it is taken
  /// for static, as a wall piece does on a moving robot's drifting poses).
  double dynamic_travel_m = 0.0;
  bool moving = false;  ///< Counted as moving (CleanConfig): every beam of it removed.
  /// Of a track that moved, the scans in which the online filter did not find it moving but it
  /// was walking into or out of a stretch in which it did (at least 0.4 m/s over every 0.5 s).
  std::int32_t walking_scans = 0;
  std::int64_t beams = 0, beams_removed = 0;
};

/// Counts of the cleaner's labels over the recording.
struct CleanCounts {
  std::int64_t scans = 0, scans_with_pose = 0;
  std::int64_t valid_beams = 0;
  std::int64_t removed_online = 0;  ///< kDynamic + kUnknown.
  std::int64_t moved_later = 0, vacated = 0, restored = 0;
  std::int64_t walked_legs = 0;  ///< kWalkedLeg.
  /// Every beam removed, whatever the reason.
  std::int64_t removed() const { return removed_online + moved_later + vacated + walked_legs; }
};

/// Two passes over a recording: add() each scan with what the online filter made of it, in time
/// order; then finish(); then label() each scan again, by its index in the order added.
class OfflineCleaner {
 public:
  explicit OfflineCleaner(CleanConfig config);

  /// Pass 1. @p result is the online filter's for @p scan (its sensor pose, labels, segmentation
  /// and tracks); a scan passed through (no pose) is remembered with its labels only.
  void add(const LaserScan& scan, const FilterResult& result);

  /// After the last add(): decides which tracks moved.
  void finish();

  /// Pass 2: the labels of scan @p index (0-based, in the order added), given the same scan.
  /// @throws std::out_of_range for an index never added, std::invalid_argument for a scan of
  /// another size.
  void label(std::size_t index, const LaserScan& scan, std::vector<CleanLabel>& out);

  /// The objects, in the order they were first seen, with the beams removed by label() so far.
  std::vector<CleanedObject> objects() const;
  const CleanCounts& counts() const { return counts_; }
  std::size_t scans() const { return scans_.size(); }
  const CleanConfig& config() const { return config_; }

 private:
  struct ScanRecord {
    double stamp_s = 0.0;
    std::optional<Pose2> pose;
    Pose2 motion_per_s;  // The sensor's since the scan before (its frame): for the de-skew.
    double time_increment_s = 0.0;             // 0: the beams are not de-skewed.
    std::vector<std::uint8_t> labels;          // BeamLabel per beam.
    std::vector<std::uint16_t> object;         // Per beam: object index, kNone.
    std::vector<std::uint32_t> track_of;       // Per object: index into tracks_, kNone32.
    std::vector<Eigen::Vector2f> position_of;  // Per object: its track's position then.
    std::vector<std::uint8_t> width_of;        // Per object: its width, in 2 cm (255: wider).
    std::vector<std::uint16_t> range_cm;       // Per beam, cm; kNoReturn, kUnusable.
    double angle_min_rad = 0.0, angle_increment_rad = 0.0;
    float range_max_m = 0.0F;
  };
  struct Track {
    CleanedObject object;
    Eigen::Vector2d first_position = Eigen::Vector2d::Zero();
    // Where it was when the online filter found it moving, in time order.
    std::vector<std::pair<double, Eigen::Vector2f>> moving_at;
    // Every sighting, in time order; finish() marks those in which it was walking into or out of
    // a stretch the online filter found it moving (walking()).
    struct Sighting {
      double stamp_s = 0.0;
      Eigen::Vector2f position = Eigen::Vector2f::Zero();
      bool dynamic = false;
      bool walking = false;
    };
    std::vector<Sighting> seen;
  };
  static constexpr std::uint16_t kNone = 0xFFFF;
  static constexpr std::uint16_t kNoReturn = 0xFFFF, kUnusable = 0xFFFE;  // In range_cm.
  static constexpr std::uint32_t kNone32 = 0xFFFFFFFFU;

  // The sensor's pose when beam @p b of @p record's scan was measured.
  static Pose2 beam_pose(const ScanRecord& record, std::size_t b);
  // What scan k's beam toward a place in the fixed frame says of it.
  enum class Look : std::uint8_t { kThrough, kHit, kNeither };
  // How a walk over the scans looks at a place. Where a track moved (LookMode{}), a beam that
  // returned nothing sees through anything in range, and a hit ends the walk. For the
  // seen-through rule on its own: a beam that returned nothing sees through only places
  // no_return_margin_m (free_margin_m) nearer than its range_max, and with exact poses
  // (CleanConfig::poses_exact) a hit starts the count again.
  struct LookMode {
    double no_return_margin_m = 0.0;
    bool hit_restarts = false;
  };
  Look look(std::size_t k, const Eigen::Vector2d& p, double no_return_margin_m) const;
  static double beam_toward(const ScanRecord& r, const Eigen::Vector2d& p, Eigen::Vector2d& q);
  bool attached(std::size_t k, std::size_t b) const;
  // Walks the scans from @p first by @p step; @p window(stamp) says whether a scan is skipped
  // (-1), looked at (0) or ends the walk (1). True when @p needed of them saw through @p p before
  // one hit it (@p mode), or, when a hit restarts the count, @p needed in a row with no hit among
  // them.
  template <typename Window>
  bool through_before_hit(const Eigen::Vector2d& p, std::ptrdiff_t first, int step, int needed,
                          Window window, LookMode mode) const;
  // Whether the scans from through_gap_s after @p from_s on saw through @p p before one hit it.
  bool left_after(const Eigen::Vector2d& p, double from_s) const;
  bool seen_through(std::size_t k, const Eigen::Vector2d& p, int step) const;
  // @p track's first sighting while moving at or after @p stamp_s (end() if none).
  static std::vector<std::pair<double, Eigen::Vector2f>>::const_iterator moving_from(
      const Track& track, double stamp_s);
  static double next_moving_s(const Track& track, double stamp_s);
  bool near_where_it_moved(const Track& track, double stamp_s,
                           const Eigen::Vector2f& position) const;
  // Where and when a moving track set off: its first sighting of each stretch in which it was
  // found moving or walking, in time order (finish()).
  std::vector<std::pair<double, Eigen::Vector2f>> set_off_;
  // Whether a thing at @p p in scan @p k stood where a track set off later: within kSetOff_m of
  // where one set off within through_horizon_s, the place left after (left_after()), and hit in
  // kStoodShare of the scans that looked at it from scan @p k until then.
  bool stood_where_one_set_off(std::size_t k, std::size_t b, const Eigen::Vector2d& p) const;
  // finish(): marks @p track's sightings next to a dynamic one from which it walked on without
  // a pause (walking()).
  static void mark_walking(Track& track);
  // Whether @p track was walking into or out of a stretch in which it was found moving at
  // @p stamp_s (mark_walking()).
  static bool walking(const Track& track, double stamp_s);

  // A run of beams in no object (too few for N_min), narrow, in front of what is beside it: a leg
  // at range (with the other leg beside it, merged), a small static thing, or speckle.
  struct Run {
    std::uint32_t scan = 0;
    std::uint16_t first = 0, last = 0;
    std::uint16_t first2 = kNone, last2 = 0;  // The other leg's beams, when merged into it.
    std::uint16_t beams = 0;
    bool removed = false;
    Eigen::Vector2f at = Eigen::Vector2f::Zero();  // Its centre in the fixed frame.
  };
  // Runs linked from scan to scan: each to the nearest run to where the chain was heading.
  struct Chain {
    std::vector<std::uint32_t> runs;  // Into runs_, in time order.
    Eigen::Vector2f velocity = Eigen::Vector2f::Zero();
    double last_s = 0.0;
  };
  // Pass 1: scan @p k's runs, linked to the open chains.
  // @p unit: the scan's beam directions (directions_).
  void add_runs(std::size_t k, const std::vector<Eigen::Vector2d>& unit);
  // finish(): which runs of which chains are removed.
  void decide_runs();

  CleanConfig config_;
  std::vector<ScanRecord> scans_;
  std::vector<Run> runs_;
  std::vector<std::uint32_t> runs_begin_;  // Per scan: the index of its first run in runs_.
  std::vector<Chain> chains_;
  std::vector<std::uint32_t> open_chains_;  // Chains a run of the next scan may extend.
  // add_runs()'s working space, kept from scan to scan: candidate (distance, chain, run) links,
  // the chains left open, whether each new run was linked.
  std::vector<std::tuple<float, std::uint32_t, std::uint32_t>> link_pairs_;
  std::vector<std::uint32_t> next_open_chains_;
  std::vector<char> linked_;
  std::vector<std::uint8_t> in_walked_leg_;  // label(): per beam, in a removed run.
  std::vector<Track> tracks_;
  std::unordered_map<std::uint64_t, std::uint32_t> track_index_;
  BeamDirections directions_;
  // label(): each beam's thing (object or run of beams in no object; -1: none asked about), and
  // per thing its beams, those asked about so far, and those seen through elsewhen. The majority
  // decides (vacated()); once it is settled the thing's other beams are not asked.
  struct Vote {
    std::int32_t beams = 0, asked = 0, through = 0;
    bool vacated() const { return through > 0 && 2 * through >= beams; }
    bool settled() const {
      const std::int32_t most = through + beams - asked;
      return vacated() || most == 0 || 2 * most < beams;
    }
  };
  std::vector<std::int32_t> group_;
  std::vector<Vote> votes_;
  std::vector<std::uint8_t> left_;   // label(): per object, see left_after().
  std::vector<Vote> set_off_votes_;  // label(): per thing, stood_where_one_set_off().
  std::vector<std::pair<std::int32_t, std::int32_t>> left_votes_;
  std::vector<Eigen::Vector2d>
      points_;  // label(): each beam's end in the fixed frame, NaN: not yet.
  CleanCounts counts_;
  bool finished_ = false;
  // A still sensor (CleanConfig::poses_exact, every scan with the same pose, geometry and no
  // motion, stamps in order): a place is on the same beam in every scan. finish() then keeps, per
  // block of kReachBlock scans and beam, the farthest place any of its scans could see through
  // on that beam (reach_cm_), so that a walk skips the blocks that cannot see through a place.
  static constexpr std::size_t kReachBlock = 32;
  bool still_ = false;
  std::vector<std::uint16_t> reach_cm_;  // [block * beams + beam], rounded up, +1 cm.
  void find_reach();
};

}  // namespace dispel
