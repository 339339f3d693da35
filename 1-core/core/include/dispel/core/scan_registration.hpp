#pragma once
/// @file
/// Scan-to-map registration: each scan is aligned with a local map of what has been static
/// (point-to-line ICP with a robust kernel and an adaptive threshold over a voxel-hashed map, the
/// design of KISS-ICP in the plane), seeded by the odometry when there is one and by a
/// constant-velocity guess when there is none. The same map says which points it explains: a
/// surface seen in many scans spread over time.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <utility>
#include <vector>

#include "dispel/core/integer_key_map.hpp"
#include "dispel/core/laser_scan.hpp"
#include "dispel/core/pose2.hpp"

namespace dispel {

/// Parameters of the registration and its local map. Defaults are dispel's.
struct RegistrationConfig {
  /// false: the sensor pose is the one given (odometry), as in the thesis.
  bool enabled = true;
  /// false: each scan is placed at the pose given and not aligned, for a sensor known not to
  /// move (`--static-sensor`: the identity is exact, and an alignment can only add error:
  /// people walking past turned the leg_tracker demo's scanner by 0.7 degrees). The map is
  /// still built, for what it explains.
  bool align = true;
  double voxel_size_m = 0.25;        ///< Side of a map voxel.
  int max_points_per_voxel = 4;      ///< Points kept per voxel (later ones only count the scan).
  double scan_spacing_m = 0.05;      ///< The scan is thinned to points at least this far apart.
  double max_range_m = 30.0;         ///< Returns farther than this are not registered.
  double local_map_radius_m = 30.0;  ///< Voxels farther from the sensor are forgotten.
  int max_iterations = 20;
  /// The correspondence threshold adapts to how far the registration moved the seed (KISS-ICP):
  /// three standard deviations of that, between these limits; initial_threshold_m until known.
  double initial_threshold_m = 0.5;
  double min_threshold_m = 0.1;
  double max_threshold_m = 1.0;
  /// A scan registers when at least this share of its points found a correspondence and the
  /// correction of the seed stays within max_correction_m / max_correction_rad; otherwise the
  /// seed is used (counted as a fallback).
  double min_inlier_share = 0.2;
  int min_points = 20;
  /// Seeded by odometry, a scan registers only with this many points matched to structure (a hall
  /// whose walls are out of range, with people standing about, falls back to the odometry).
  int min_points_with_odometry = 60;
  double max_correction_m = 0.5;
  double max_correction_rad = 0.35;
  /// The noise of a return (m) and of the seed's motion per scan: the odometry's (these plus 5 %
  /// of the motion and 0.01 rad per metre), and a constant-velocity guess's (no odometry). The
  /// seed counts against the points with these.
  double range_noise_m = 0.03;
  double odometry_noise_m = 0.005;
  double odometry_noise_rad = 0.002;
  double constant_velocity_noise_m = 0.2;
  double constant_velocity_noise_rad = 0.1;
  /// The constant-velocity guess's velocity: each scan's registered motion counts this much
  /// against the estimate so far (1: the last scan's motion alone, which oscillated and diverged
  /// along a corridor at 1 m/s).
  double velocity_smoothing = 0.5;
  /// A scan is degenerate (a corridor with nothing ahead) when the weakest direction of its
  /// translation information is below this share of the strongest; along that direction the seed
  /// holds (the seed's noise keeps it).
  double degeneracy_ratio = 0.02;
  /// Structure, the part of the map scans register to (every voxel while there is too little of it:
  /// a young map): voxels hit in at least
  /// explained_min_scans scans spread over at least explained_min_span_s. A point is explained
  /// when it lies within explained_distance_m of a point of structure that was added at least
  /// explained_min_span_s before (so that a walker's own trail, always younger than the time
  /// the walker takes to pass, never explains the walker).
  int explained_min_scans = 4;
  double explained_min_span_s = 0.6;
  double explained_min_span_in_free_s = 5.0;
  double explained_distance_m = 0.12;
  /// Structure explains only while seen: hit within this long before the scan.
  double explained_max_age_s = 0.5;
  /// An object the map explains gives no motion evidence: a static surface whose outline slides
  /// as the sensor moves. Unless its outline is its own at both ends and moves along itself unlike
  /// the sensor: a static surface's outline slides along it only as the sensor moves along it (an
  /// end where the incidence grows too steep, or the surface's returns thin out, moves with the
  /// sensor). An explained object of at least 0.5 m whose ends are both trusted and whose velocity
  /// along itself differs from the sensor's along it by more than this (m/s) gives motion
  /// evidence as any object does: a cart driving to and fro along one line, explained by its own
  /// earlier passes. 0: off (the map's explanation always wins).
  double slide_tolerance_mps = 0.5;
  /// Beams are de-skewed by their time_increment with the odometry's motion since the previous
  /// scan (never by a constant-velocity guess's translation: its error fed back into the
  /// registration).
  bool deskew = true;
  /// Laser-only (no odometry; with deskew): beams are de-skewed by the constant-velocity guess's
  /// turn, then aligned again de-skewed by the registered turn while that bends the sweep by more
  /// than 1 cm at 10 m against the turn used, up to 3 times. On the simulated office loop
  /// (768 beams, 7.5 Hz, 1 m/s) it takes the error over 1 s from 0.60 to 0.10 degrees and 6.9 to
  /// 4.5 cm (seeds 1-20); on the real negative_2 it lowers the residuals, but one laser then
  /// removes 0.38 % of its beams instead of 0.08 % (docs/results.md, "De-skewing laser-only
  /// scans by their turn"). Off by default.
  bool deskew_laser_only_turn = false;
  /// Laser-only (no odometry): a wheeled robot drives along one direction of the sensor frame and
  /// does not slide sideways; a turn moves a sensor mounted off the axle sideways by an amount in
  /// proportion to the turn. Both are learnt from the scans that register (the direction along
  /// which they moved while driving straight, the sideways motion per turn), starting from the
  /// sensor's x axis. Each alignment then holds the sideways motion beyond the turn's share to
  /// this noise (m/s), and the constant-velocity guess keeps none. With little structure (a
  /// narrow view outdoors, a person walking ahead) the scans registered 1 m/s sideways and turning
  /// 14-20 degrees/s within 2 s of a straight drive. 0: off (any motion in the plane).
  double lateral_noise_mps = 0.1;
  /// Laser-only: on a scan that does not register (a fallback), the guess's turn decays with this
  /// time constant (s): without evidence a turn does not go on, and a guessed turn carried
  /// through a run of fallbacks spun the registered pose a full circle. 0: off (carried on).
  double fallback_turn_decay_s = 0.25;
  /// Laser-only: the points of what the filter tracks as moving (register_scan()'s @p moving)
  /// are left out of the alignments. A person walked 1.7 m ahead of a robot following them, half
  /// of what the scanner saw: registered to, they held the robot back (the registered pace 0.8-1.1
  /// m/s against their 1.4-1.5). false: every point counts.
  bool leave_out_moving = true;

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

/// How one scan registered.
struct RegistrationReport {
  bool registered = false;  ///< Aligned with the map (false: first scan, fallback, disabled).
  bool fallback = false;    ///< Could not register: the seed was used.
  bool degenerate = false;  ///< Registered, with a direction the scan does not constrain.
  bool seeded_by_odometry = false;
  /// The odometry's motion and the constant-velocity guess parted (a wheel slipped), and the
  /// guess matched clearly more of the scan: registered from the guess.
  bool odometry_overruled = false;
  /// The constant-velocity guess, brought up to date with this scan's motion, was faster than the
  /// robot can drive (SpeedLimits) and was held at the limit.
  bool guess_limited = false;
  /// Laser-only: the alignment held the sensor's sideways motion (RegistrationConfig::
  /// lateral_noise_mps) along the direction learnt so far.
  bool held_sideways = false;
  /// Times the scan was de-skewed by its registered turn and aligned again: the turn it was first
  /// de-skewed by (the odometry's, or the guess's) bent it (a slip starts or ends within a scan).
  std::int32_t realignments = 0;
  std::int32_t points = 0;      ///< Points of the thinned scan.
  std::int32_t left_out = 0;    ///< Of them, left out as moving (leave_out_moving).
  std::int32_t iterations = 0;  ///< Of the alignment kept.
  /// Alignments tried for the scan (the odometry's seed, the guess's after a slip, realignments)
  /// and their iterations together: the registration's work.
  std::int32_t alignments = 0;
  std::int32_t total_iterations = 0;
  double inlier_share = 0.0;  ///< Share of the points with a correspondence.
  double residual_m = 0.0;    ///< RMS point-to-line distance of the inliers.
  double degeneracy = 0.0;    ///< Weakest / strongest translation information (0..1).
  double threshold_m = 0.0;   ///< The correspondence threshold used.
  Pose2 correction;           ///< Registered pose relative to the seed.
};

/// What the robot can do (DynamicFilterConfig::max_speed_mps, max_turn_rate_radps): the
/// constant-velocity guess is held within them. With little structure (a narrow view outdoors, a
/// person walking ahead) the registered motion is poor, and the guess, which every fallback
/// carries on unchanged, ran away: up to 34 m/s on a real robot following a walker at about
/// 1.5 m/s (person_following_outdoor_1, docs/results.md).
struct SpeedLimits {
  double speed_mps = 3.0;
  double turn_rate_radps = 3.0;
};

/// Registers scans to a local map and says which points it explains. Feed scans in time order;
/// after labelling, add() the beams that stay static. Not thread-safe.
class ScanRegistration {
 public:
  explicit ScanRegistration(RegistrationConfig config, SpeedLimits limits = {});

  /// Registers @p scan. @p odometry_pose is the sensor in the odometry frame at the scan's stamp
  /// (std::nullopt: none; the motion is guessed: the registered motion per second, smoothed,
  /// within SpeedLimits). Returns the sensor's pose in the registration's fixed frame (the
  /// odometry frame at the first scan, or the first scan's sensor frame when there is no
  /// odometry). Fills the scan's points in that
  /// frame (points(): one per beam, de-skewed; NaN for invalid beams). Laser-only, with
  /// leave_out_moving, a point for which @p moving (in the fixed frame, where the seed puts it)
  /// is true is left out of the alignments (empty: none).
  Pose2 register_scan(const LaserScan& scan, const std::optional<Pose2>& odometry_pose,
                      RegistrationReport& report,
                      const std::function<bool(const Eigen::Vector2d&)>& moving = {});

  /// The last registered scan's beams in the fixed frame (NaN where invalid).
  const std::vector<Eigen::Vector2d>& points() const { return world_points_; }
  /// The turn of the sensor from one beam of the last registered scan to the next that its
  /// points were de-skewed by (0: not de-skewed, or not turned).
  double deskew_turn_per_beam_rad() const { return deskew_turn_per_beam_rad_; }

  /// Whether the map explains beam @p b of the last registered scan (see RegistrationConfig).
  /// Valid after register_scan() and before add().
  bool explained(std::size_t b) const;
  /// Whether the map holds a point within explained_distance_m of beam @p b of the last
  /// registered scan that it learnt before @p before_s (structure or not, seen lately or not:
  /// FreeSpaceConfig::require_unseen). Valid after register_scan() and before add().
  bool seen_before(std::size_t b, double before_s) const;

  /// Adds the beams of the last registered scan for which @p keep is true to the map, and forgets
  /// voxels beyond local_map_radius_m. @p in_free_space (may be empty: never) says whether a
  /// point ends where the scanner saw through before; it is asked only for a point that creates a
  /// voxel. A voxel first hit by such a point (a cart driving along itself, a walker's trail) is
  /// not structure until it has been hit for explained_min_span_in_free_s. @p long_free (may be
  /// empty: never) says whether the scanner has seen through a point's place in many more scans
  /// than anything was there; it is asked only for a point that hits a voxel unseen for longer
  /// than explained_max_age_s. Such a voxel is started afresh: what stood there left, and a
  /// thing that comes back along the same line (a cart driving to and fro, its side sliding along
  /// itself) is not explained by its own earlier passes.
  void add(const std::vector<char>& keep,
           const std::function<bool(const Eigen::Vector2d&)>& in_free_space,
           const std::function<bool(const Eigen::Vector2d&)>& long_free = {});

  /// Forgets the map and the motion (after a jump in time or of the fixed frame).
  void reset();

  std::size_t voxel_count() const { return map_.size(); }
  /// Voxels started afresh by add() since the start (see its long_free).
  std::int64_t voxels_restarted() const { return voxels_restarted_; }
  /// Laser-only: the direction the sensor moves along (radians in the sensor frame, either way
  /// along it), as learnt so far (0 before any scan registered: the x axis).
  double learnt_heading_rad() const;
  const RegistrationConfig& config() const { return config_; }
  /// For tests: each sample point's nearest map point found by walking all its candidates at
  /// every iteration, without the shortcuts that must not change it (the nearby lists, the
  /// bound that passes over points too far from every candidate). Slow.
  void search_exhaustively(bool on) { exhaustive_ = on; }

 private:
  static inline const Eigen::Vector2f kZero = Eigen::Vector2f::Zero();
  struct Voxel {
    // Zeroed (Eigen leaves its own uninitialised): voxels are copied when the map grows.
    std::array<Eigen::Vector2f, 4> points{kZero, kZero, kZero, kZero};
    std::array<Eigen::Vector2f, 4> normals{kZero, kZero, kZero, kZero};
    std::array<double, 4> stamps_s{};  // When each point was added.
    std::uint8_t count = 0;
    // Per slot (bit): a normal was sought among the map's points (map_normal()), and found.
    std::uint8_t map_normal_sought = 0;
    std::uint8_t map_normal_found = 0;
    std::int32_t scans = 0;       // Scans that hit it.
    bool in_free_space = false;   // First hit where the scanner had seen through.
    std::uint32_t last_scan = 0;  // The last one.
    double first_stamp_s = 0.0;
    double last_stamp_s = 0.0;
  };
  using Key = std::uint64_t;
  struct CacheSlot {  // A voxel looked up in generation (0: never), see candidate_voxel().
    Key key = 0;
    const Voxel* voxel = nullptr;
    std::uint32_t generation = 0;
  };
  static constexpr unsigned kCacheShift = 52;  // 4096 slots.
  static Key key_at(std::int64_t ix, std::int64_t iy) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(ix)) << 32U) |
           static_cast<std::uint32_t>(iy);
  }
  Key key_of(const Eigen::Vector2d& p) const;
  /// Calls @p f on each voxel of the map among voxel (ix, iy) and its eight neighbours, (ix, iy)
  /// first (where a point is mostly found), until @p f returns true; returns whether it did. The
  /// map's points within explained_distance_m of a point lie in the voxels around the point's.
  template <typename F>
  bool any_voxel_around(std::int64_t ix, std::int64_t iy, F&& f) const;
  bool structure(const Voxel& v) const;
  struct Reference {  // One map point: its voxel, its slot there.
    const Voxel* voxel;
    std::uint8_t slot;
  };
  // Voxel (x, y) of the map if it can hold candidates (structure only or all, structure_only_),
  // else nullptr. The registration asks about the same voxels again and again: the answers are
  // kept in a small direct-mapped cache for the alignment (cache_generation_).
  const Voxel* candidate_voxel(std::int64_t x, std::int64_t y) {
    const Key key = key_at(x, y);
    const CacheSlot& slot =
        cache_[static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ULL) >> kCacheShift)];
    if (slot.generation == cache_generation_ && slot.key == key) return slot.voxel;
    return look_up_candidate_voxel(key);
  }
  const Voxel* look_up_candidate_voxel(Key key);
  void forget_candidate_voxels();
  bool nearest_candidate(std::size_t i, const Eigen::Vector2d& q, double threshold, bool need_any,
                         double& best, Reference& found);
  // Whose noise the seed of align() has: the odometry's (it grows with the motion) or a
  // constant-velocity guess's (also a seed that is an earlier alignment of the same scan).
  enum class SeedNoise { kOdometry, kGuess };
  /// Aligns the scan from @p seed; the prior is the constant-velocity guess or the odometry at
  /// @p prior_at (nullptr: at @p seed).
  Pose2 align(const Pose2& seed, const Pose2& delta, double threshold, SeedNoise noise,
              RegistrationReport& report, const Pose2* prior_at = nullptr);
  bool thin_and_deskew(const LaserScan& scan, const Pose2& motion_per_s, bool deskew_wanted);
  Eigen::Vector2d normal_at(std::size_t b) const;
  Eigen::Vector2d map_normal(const Voxel& voxel, std::uint8_t slot);

  // Laser-only: how the sensor moves on its robot, learnt from the registered motion (see
  // lateral_noise_mps). The x axis's prior counts as kPriorScans scans at 1 m/s.
  struct Heading {
    double sxx = 0.0, sxy = 0.0, syy = 0.0;  // Scatter of the straight, moving scans' velocity.
    Eigen::Vector2d velocity_by_turn = Eigen::Vector2d::Zero();  // Sum of velocity x turn rate.
    double turn2 = 0.0;                                          // Sum of turn rate squared.
    Eigen::Vector2d forward = Eigen::Vector2d::UnitX();
    double sideways_per_turn_m = 0.0;  // Sideways velocity per rad/s of turn (m).
    bool clear = true;                 // The direction stands out (see learn()).
    Heading();
    void learn(const Pose2& motion_per_s);
    Eigen::Vector2d sideways() const { return {-forward.y(), forward.x()}; }
  };
  // The constant-velocity guess without the sideways motion its turn does not explain.
  void hold_guess_sideways();

  RegistrationConfig config_;
  SpeedLimits limits_;
  Heading heading_;
  double sideways_sigma_m_ = 0.0;  // This scan's alignments hold sideways motion to this (0: not).
  bool sparse_ = true;  // Laser-only: the last scan matched fewer than min_points_with_odometry.
  IntegerKeyMap<Voxel> map_;
  std::int64_t voxels_restarted_ = 0;
  std::uint32_t scan_count_ = 0;
  bool have_previous_ = false;
  double previous_stamp_s_ = 0.0;
  Pose2 previous_pose_;  // Registered.
  std::optional<Pose2> previous_odometry_;
  Pose2 velocity_per_s_;  // Sensor-frame motion per second, smoothed estimate.
  bool velocity_per_s_initialised_ = false;
  Pose2 odometry_to_fixed_;       // Registered fixed frame from the odometry frame.
  double model_error_sum_ = 0.0;  // Adaptive threshold: squared deviations, count.
  std::int64_t model_error_count_ = 0;
  double last_stamp_s_ = 0.0;
  Pose2 last_pose_;
  // Per scan.
  double deskew_turn_per_beam_rad_ = 0.0;
  std::vector<Eigen::Vector2d> local_points_;  // Per beam, de-skewed, in the sensor frame.
  std::vector<Eigen::Vector2d> world_points_;  // Per beam, in the fixed frame.
  BeamDirections directions_;                  // The scanner's beam directions.
  std::vector<std::int32_t> sample_;           // Beams used for registration.
  std::int32_t alignments_ = 0;                // This scan's, all tried (report.alignments).
  std::int32_t total_iterations_ = 0;
  bool map_normals_ = false;  // The scan has odometry: map points get map_normal() (see align()).
  // The alignment's candidates (see nearest_candidate()): each sample point at the seed, the
  // voxels around it, how far, and whether only structure counts.
  std::vector<Eigen::Vector2d> seed_points_;
  const std::function<bool(const Eigen::Vector2d&)>* leave_out_ = nullptr;  // This scan's.
  std::vector<char> left_out_;  // Per sample point: left out of the alignments.
  int reach_ = 0;
  double radius_ = 0.0;
  bool structure_only_ = true;
  bool exhaustive_ = false;  // search_exhaustively().
  std::vector<CacheSlot> cache_;
  struct Candidate {
    Eigen::Vector2f point;  // The map's, as stored.
    Reference reference;
  };
  struct Listed {  // A sample point's candidates in candidates_ (begin -1: not listed).
    std::int32_t begin = -1;
    std::int32_t end = -1;
  };
  std::vector<Candidate> candidates_;
  std::vector<Listed> listed_;
  std::uint32_t cache_generation_ = 0;
  // Each sample point's candidates within kNearby_m of where it was when all its candidates were
  // last looked at (in their order; count -1: more than fit), and its nearest candidate's
  // distance at the last iteration. While that distance plus how far the point moved since
  // stays within kNearby_m, its nearest is one of these (the others are farther).
  static constexpr double kNearby_m = 0.2;
  static constexpr std::int32_t kNearbyMax = 31;
  struct Nearby {
    Eigen::Vector2d origin;
    Eigen::Vector2d at;
    double nearest_m = 0.0;
    std::int32_t count = -1;
    // Their points (the map's), kept here: the later iterations read them from one place,
    // right after the fields above (the references, read once per iteration, come after).
    std::array<Eigen::Vector2f, kNearbyMax + 1> near_points;
    std::array<Reference, kNearbyMax + 1> near{};
  };
  std::vector<Nearby> nearby_;
  // explained(): the map points that can explain points of one voxel, kept for the next beam.
  mutable std::vector<Eigen::Vector2d> explaining_;
  mutable bool explaining_valid_ = false;
  mutable std::int64_t explaining_ix_ = 0, explaining_iy_ = 0;
};

}  // namespace dispel
