#pragma once
/// @file
/// Where the scanner has seen through: free-space evidence in the fixed frame. Something that now
/// stands where beams used to pass freely has moved there (the visibility idea of map-cleaning
/// methods such as ERASOR and Removert, used here online as one more piece of evidence).

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "dispel/core/laser_scan.hpp"
#include "dispel/core/pose2.hpp"

namespace dispel {

/// Free-space evidence (beyond the thesis: thesis_config() turns it off). Defaults are dispel's.
struct FreeSpaceConfig {
  bool enabled = true;
  double cell_size_m = 0.1;
  double extent_m = 102.4;  ///< Side of the square window kept around the first pose.
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

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

/// A square window of cells around the first pose; each cell keeps the balance of the scans that
/// hit it and the scans that saw through it. Moving out of the window re-centres it.
class FreeSpaceMap {
 public:
  explicit FreeSpaceMap(FreeSpaceConfig config);

  /// True when every cell within neighbourhood_cells of the point's cell is known free.
  bool known_free(const Eigen::Vector2d& point_m) const;
  /// known_free(), and the point's cell and its eight neighbours were seen through by beams at
  /// most @p max_beam_spacing_m apart (range times angle increment, where the beams crossed the
  /// cell) in one of the scans counted: dense enough that an object of twice that width could not
  /// have stood there unseen. Beams farther apart pass each side of a thin thing (a chair leg, a
  /// railing's bar) and see "through" it; the same thing seen close later did not arrive there.
  bool known_free(const Eigen::Vector2d& point_m, double max_beam_spacing_m) const;

  /// Scans the point's cell has been hit in more than seen through, between 0 and
  /// 2 * long_occupied_scans (0 outside the window).
  int occupied_scans(const Eigen::Vector2d& point_m) const;
  /// The balance of the point's cell (see min_free_observations; 0 outside the window).
  int hit_balance(const Eigen::Vector2d& point_m) const;

  /// Adds a scan taken from @p sensor_pose: cells along each valid beam, up to margin_m before its
  /// return, are seen free, as are cells along a beam with no return, all up to free_range_m;
  /// then every return's cell is hit (a hit in the same scan wins over a beam passing by).
  void add_scan(const LaserScan& scan, const Pose2& sensor_pose);

  void clear();
  const FreeSpaceConfig& config() const { return config_; }

 private:
  struct Cell {
    float last_free_s = 0.0F;     // When a beam last saw through it, seconds after epoch_s_.
    std::uint32_t last_scan = 0;  // The scan that last counted for it (counts once per scan).
    std::int16_t balance = 0;     // Scans hit minus scans seen through, clamped.
    std::int16_t occupied = 0;    // The same, clamped to [0, 2 * long_occupied_scans].
    /// The finest beam spacing it was seen through at, in kSpacingUnit_m (kNeverSeenThrough:
    /// never), since the window was placed.
    std::uint8_t finest_spacing = kNeverSeenThrough;
  };
  static constexpr std::uint8_t kNeverSeenThrough = 255;
  static constexpr double kSpacingUnit_m = 0.002;
  bool cell_free(const Eigen::Vector2d& p) const;
  bool index_of(const Eigen::Vector2d& p, std::int64_t& index) const;
  /// Cells are stored in square tiles of kTileSide x kTileSide (a beam crosses cells near each
  /// other in memory, whatever its direction); the index of cell (ix, iy) of the window.
  static constexpr std::int64_t kTileBits = 3;
  static constexpr std::int64_t kTileSide = std::int64_t{1} << kTileBits;
  std::int64_t cell_index(std::int64_t ix, std::int64_t iy) const {
    constexpr std::int64_t mask = kTileSide - 1;
    return (((iy >> kTileBits) * tiles_per_side_ + (ix >> kTileBits)) << (2 * kTileBits)) +
           ((iy & mask) << kTileBits) + (ix & mask);
  }
  void recenter(const Eigen::Vector2d& center);

  FreeSpaceConfig config_;
  std::int64_t cells_per_side_ = 0;
  std::int64_t tiles_per_side_ = 0;
  Eigen::Vector2d origin_ = Eigen::Vector2d::Zero();  // Corner of the window.
  bool placed_ = false;
  std::uint32_t scans_ = 0;
  double stamp_s_ = 0.0;  // Of the latest scan.
  double epoch_s_ = 0.0;  // Cells keep their stamps relative to this (the first scan's stamp).
  std::vector<Cell> cells_;
  std::vector<double> free_until_;           // Scratch: per beam, how far it saw free space.
  std::vector<Eigen::Vector2d> directions_;  // Scratch: per beam, its direction.
  BeamDirections beam_directions_;           // The scanner's beam directions (sensor frame).
};

}  // namespace dispel
