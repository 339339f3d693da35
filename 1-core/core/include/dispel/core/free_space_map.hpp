#pragma once
/// @file
/// Where the scanner has seen through: free-space evidence in the fixed frame. Something that now
/// stands where beams used to pass freely has moved there (the visibility idea of map-cleaning
/// methods such as ERASOR and Removert, used here online as one more piece of evidence).

#include <Eigen/Core>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <vector>

#include "dispel/core/laser_scan.hpp"
#include "dispel/core/pose2.hpp"

namespace dispel {

/// When an object's point counts as in free space only if it is new there (FreeSpaceConfig::
/// require_unseen).
enum class RequireUnseen { kNever, kLaserOnly, kAlways };

/// Free-space evidence (beyond the thesis: thesis_config() turns it off). Defaults are dispel's.
struct FreeSpaceConfig {
  bool enabled = true;
  double cell_size_m = 0.1;
  /// Side of the square window of cells kept. Cells are kept in tiles of 8 x 8 within half of it of
  /// the sensor's tile (less a tile: 50.4 m); beyond that, beams are not traced, returns not
  /// counted, and nothing is known free.
  double extent_m = 102.4;
  /// Free space ends this far before each return, so a surface's own cells are never "free".
  double margin_m = 0.3;
  /// Each cell keeps a balance of evidence: +1 for a scan that hit it, -1 for a scan that saw
  /// through it (and was not hit), clamped to +-(min_free_observations + max_recent_hits). A cell
  /// is known free while its balance is at most -min_free_observations: once seen through in
  /// enough scans, it stays free while a walker crosses it (up to max_recent_hits scans of hits);
  /// a surface's cell, hit in most scans and seen through only now and then (a dropout, a grazing
  /// beam), never is.
  int min_free_observations = 3;
  int max_recent_hits = 10;
  /// A beam of a dynamic object that ends where something has stood for a while (a pillar, a
  /// parked vehicle) is kept: a person's track that slid onto a pillar next to it takes the
  /// pillar's beams out of the scan no more. "A while" is a cell hit in long_occupied_scans scans
  /// more than seen through; for an object that is slow now (at most twice L_v: a track that has
  /// come to rest on something), a balance of max_recent_hits (see min_free_observations). 100
  /// scans is 5 s at 20 Hz: longer than the side of a forklift driving along itself keeps a cell
  /// hit.
  bool keep_long_occupied = true;
  int long_occupied_scans = 100;
  /// Free space seen longer ago than this is forgotten: odometry drifts, and space seen free
  /// minutes ago in a frame that has since drifted would put a pillar "in free space".
  double memory_s = 30.0;
  /// Free space is traced along each beam up to this far from the scanner (and up to margin_m
  /// before its return). The cost grows with it; 20 m covers what a forklift is tracked at.
  double free_range_m = 20.0;
  /// A beam with no return (+inf, REP 117) passed freely (up to free_range_m, capped at the
  /// scan's maximum range): in a hall whose walls are out of range, most of what the scanner sees
  /// through gives no return. NaN beams never do.
  bool no_return_is_free = true;
  /// A point is in free space when every cell within this many cells of it is known free (room
  /// for odometry errors: a slip that shifts the map must not put a pillar in "free" space).
  int neighbourhood_cells = 3;
  /// An object whose points are in free space by at least this share appeared in free space.
  double min_object_share = 0.5;
  /// Free space is asked about the objects of young tracks only (10 scans: an older track that
  /// has shown no motion is a known thing seen from a new side). With this, also about an older
  /// track's object beside a dynamic track confirmed by its motion: a walker's leg, long hidden
  /// behind the other leg as it walks beside the robot, that steps out into space seen free.
  bool mark_beside_dynamic = true;
  /// A point counts as in free space only if the registration's map holds no point within
  /// registration.explained_distance_m of it from before its track began: a place that returned
  /// before, however briefly, and was seen through since is one that returns now and then (glass
  /// seen square-on, a surface at the end of the scanner's reach, a registration's slip), not one
  /// something arrived at. kLaserOnly (the default): only without odometry, where it cut
  /// negative_2's false removals by 26-43 % and the background person_following_outdoor_1 lost by
  /// 60 %, for 0.2-2.6 points of the simulated laser-only walkers' removal and a tenth of the
  /// followed person's; with odometry it also turned away walkers coming back along paths walked
  /// before, whose first beams the map had learnt (the simulated thesis hall 0.910 -> 0.898
  /// removed). docs/dynamic_filter.md, "Seen there before".
  RequireUnseen require_unseen = RequireUnseen::kLaserOnly;

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

/// A square window of cells that scrolls with the sensor; each cell keeps the balance of the scans
/// that hit it and the scans that saw through it. The cells are stored in tiles of 8 x 8, each in
/// the slot given by its coordinates modulo the window: a tile is started (its 64 cells emptied)
/// when a beam first reaches it, and a tile the sensor has left behind by more than half a window
/// is overwritten by the one that takes its slot. So the cost of a scan never depends on how far
/// the sensor has gone or how often the filter was reset (clear() is O(1)); memory is the window's
/// (16 MiB by default), all of it resident from the start.
class FreeSpaceMap {
 public:
  explicit FreeSpaceMap(FreeSpaceConfig config);
  /// A map with @p config that takes @p earlier's window when it is of the same size (the same
  /// cell_size_m and extent_m), emptied: the window's memory is made and zeroed once, before the
  /// first scan, even where the filter's settings are known only from it (scale_to_scanner).
  FreeSpaceMap(FreeSpaceConfig config, FreeSpaceMap&& earlier);

  /// True when every cell within neighbourhood_cells of the point's cell is known free.
  bool known_free(const Eigen::Vector2d& point_m) const;
  /// known_free(), and the point's cell and its eight neighbours were seen through by beams at
  /// most @p max_beam_spacing_m apart (range times angle increment, where the beams crossed the
  /// cell) in one of the scans counted: dense enough that an object of twice that width could not
  /// have stood there unseen. Beams farther apart pass each side of a thin thing (a chair leg, a
  /// railing's bar) and see "through" it; the same thing seen close later did not arrive there.
  bool known_free(const Eigen::Vector2d& point_m, double max_beam_spacing_m) const;

  /// known_free(), and the point's own cell has been seen through in at least
  /// min_free_observations + max_recent_hits scans more than it was hit, the most its balance
  /// counts: whatever stood there left long ago (within memory_s).
  bool long_free(const Eigen::Vector2d& point_m) const;

  /// Scans the point's cell has been hit in more than seen through, between 0 and
  /// 2 * long_occupied_scans (0 outside the window).
  int occupied_scans(const Eigen::Vector2d& point_m) const;
  /// The balance of the point's cell (see min_free_observations; 0 outside the window).
  int hit_balance(const Eigen::Vector2d& point_m) const;

  /// Adds a scan taken from @p sensor_pose: cells along each valid beam, up to margin_m before its
  /// return, are seen free, as are cells along a beam with no return, all up to free_range_m;
  /// then every return's cell is hit (a hit in the same scan wins over a beam passing by). Beam b
  /// is turned by b x @p turn_per_beam_rad: the sensor's turn while it swept the scan, by which
  /// the registration de-skewed it.
  void add_scan(const LaserScan& scan, const Pose2& sensor_pose, double turn_per_beam_rad = 0.0);

  /// Forgets everything (O(1): the tiles are marked of an earlier generation).
  void clear();
  const FreeSpaceConfig& config() const { return config_; }
  /// Tiles started since the last call (the work of emptying them: a statistic).
  std::int64_t take_tiles_started() {
    const std::int64_t n = tiles_started_;
    tiles_started_ = 0;
    return n;
  }

 private:
  struct Unallocated {};
  FreeSpaceMap(const FreeSpaceConfig& config, Unallocated);  // The window's size, no memory.
  void allocate();
  /// Trivially constructible: emptied by writing kEmptyCell when a tile is started.
  struct Cell {
    float last_free_s;        // When a beam last saw through it, seconds after epoch_s_.
    std::uint32_t last_scan;  // The scan that last counted for it (counts once per scan).
    std::int16_t balance;     // Scans hit minus scans seen through, clamped.
    std::int16_t occupied;    // The same, clamped to [0, 2 * long_occupied_scans].
    /// The finest beam spacing it was seen through at, in kSpacingUnit_m (kNeverSeenThrough:
    /// never), since its tile was started.
    std::uint8_t finest_spacing;
  };
  static constexpr std::uint8_t kNeverSeenThrough = 255;
  static constexpr double kSpacingUnit_m = 0.002;
  static constexpr Cell kEmptyCell{0.0F, 0, 0, 0, kNeverSeenThrough};
  /// Which tile a slot holds: tile coordinates (in tiles from the anchor) and the map's generation
  /// when it was started (a tile of an earlier generation was cleared).
  struct TileTag {
    std::int64_t tx = 0;
    std::int64_t ty = 0;
    std::uint32_t generation = 0;
  };
  static constexpr std::int64_t kTileBits = 3;
  static constexpr std::int64_t kTileSide = std::int64_t{1} << kTileBits;
  static constexpr std::int64_t kTileCells = kTileSide * kTileSide;

  bool cell_free(const Cell* cell) const;
  bool known_free(std::int64_t ix, std::int64_t iy) const;
  /// The cell holding @p p (cell coordinates from the anchor), if the point is within reach of
  /// the latest sensor position.
  bool cell_of(const Eigen::Vector2d& p, std::int64_t& ix, std::int64_t& iy) const;
  /// The cell (ix, iy) if its tile is held, else nullptr.
  const Cell* find(std::int64_t ix, std::int64_t iy) const;
  const Cell* find(const Eigen::Vector2d& p) const;
  /// The cells of tile (tx, ty), the tile started if it was not held.
  Cell* tile(std::int64_t tx, std::int64_t ty);
  /// The cell (ix, iy), its tile started if it was not held.
  Cell& touch(std::int64_t ix, std::int64_t iy) {
    return tile(ix >> kTileBits, iy >> kTileBits)[in_tile(ix, iy)];
  }
  static std::int64_t in_tile(std::int64_t ix, std::int64_t iy) {
    constexpr std::int64_t mask = kTileSide - 1;
    return ((iy & mask) << kTileBits) + (ix & mask);
  }
  std::size_t slot_of(std::int64_t tx, std::int64_t ty) const {
    if (slot_mask_ >= 0)
      return static_cast<std::size_t>((ty & slot_mask_) * tiles_per_side_ + (tx & slot_mask_));
    const std::int64_t sx = ((tx % tiles_per_side_) + tiles_per_side_) % tiles_per_side_;
    const std::int64_t sy = ((ty % tiles_per_side_) + tiles_per_side_) % tiles_per_side_;
    return static_cast<std::size_t>(sy * tiles_per_side_ + sx);
  }
  bool tile_within_reach(std::int64_t tx, std::int64_t ty) const {
    return std::abs(tx - sensor_tx_) <= reach_tiles_ && std::abs(ty - sensor_ty_) <= reach_tiles_;
  }

  FreeSpaceConfig config_;
  std::int64_t tiles_per_side_ = 0;
  std::int64_t slot_mask_ = -1;  // tiles_per_side_ - 1 when that is a power of two (the default).
  /// Cells are written and read in tiles within this many tiles of the sensor's tile ((tiles a
  /// side - 1) / 2: 63 of 128, 50.4 m): a tile and the one that shares its slot are never both
  /// within reach.
  std::int64_t reach_tiles_ = 0;
  Eigen::Vector2d anchor_ = Eigen::Vector2d::Zero();  // Corner of cell (0, 0).
  bool placed_ = false;
  std::uint32_t generation_ = 1;
  std::int64_t sensor_tx_ = 0;  // The latest sensor position's tile.
  std::int64_t sensor_ty_ = 0;
  std::uint32_t scans_ = 0;
  double stamp_s_ = 0.0;  // Of the latest scan.
  double epoch_s_ = 0.0;  // Cells keep their stamps relative to this (the first scan's stamp).
  std::unique_ptr<Cell[]> cells_;  // tiles_per_side_^2 slots of kTileCells cells.
  std::vector<TileTag> tags_;      // Per slot.
  std::int64_t tiles_started_ = 0;
  std::vector<double> free_until_;           // Scratch: per beam, how far it saw free space.
  std::vector<Eigen::Vector2d> directions_;  // Scratch: per beam, its direction.
  BeamDirections beam_directions_;           // The scanner's beam directions (sensor frame).
};

}  // namespace dispel
