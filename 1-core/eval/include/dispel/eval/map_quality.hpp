#pragma once
/// @file
/// Map quality: the occupancy grid that a set of scans makes from known sensor poses, and how one
/// grid differs from a reference grid (cells wrongly occupied, cells lost). The question a mapping
/// user asks of a filter: is what it removed still in the map, and is the wall still there?

#include <array>
#include <cstdint>
#include <vector>

#include "dispel/core/integer_key_map.hpp"
#include "dispel/core/pose2.hpp"

namespace dispel::eval {

/// A log-odds occupancy grid's update rule. The defaults are OctoMap's: a hit 0.7, a miss 0.4,
/// clamped to 0.12 ... 0.97, so that a cell occupied for a long time becomes free again after a
/// bounded number of rays through it, as in the maps robots keep.
struct OccupancyGridConfig {
  double resolution_m = 0.05;
  double hit_probability = 0.7;
  double miss_probability = 0.4;
  double min_probability = 0.12;
  double max_probability = 0.97;
  /// A cell is occupied at or above this (map_saver's threshold).
  double occupied_probability = 0.65;
  /// @throws std::invalid_argument naming the first invalid value: a resolution that is not
  /// finite and positive, probabilities outside (0, 1), a hit <= 0.5 or a miss >= 0.5, a clamp
  /// range that does not hold 0.5, an occupied threshold outside the clamp range.
  void validate() const;
};

/// A grid without bounds (cells in tiles, made as rays reach them), fed beam by beam.
class OccupancyGrid {
 public:
  explicit OccupancyGrid(const OccupancyGridConfig& config = {});

  /// One return: the cells the ray from @p from_m crosses before @p to_m are missed, the cell of
  /// @p to_m is hit. Points are in the map frame (m); non-finite points are ignored.
  void add_return(const Eigen::Vector2d& from_m, const Eigen::Vector2d& to_m) {
    trace(from_m, to_m, true);
  }
  /// A beam without a return: every cell from @p from_m to @p to_m (its range limit) is missed.
  void add_no_return(const Eigen::Vector2d& from_m, const Eigen::Vector2d& to_m) {
    trace(from_m, to_m, false);
  }

  /// A cell's key: its column and row (each within +-2^31) packed into 64 bits.
  static std::uint64_t cell_key(std::int64_t col, std::int64_t row) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(col)) << 32) |
           static_cast<std::uint32_t>(row);
  }
  /// The occupied cells, as cell_key()s, sorted.
  std::vector<std::uint64_t> occupied_cells() const;
  /// Cells any ray reached.
  std::int64_t known_cells() const;
  double resolution_m() const { return resolution_m_; }

 private:
  static constexpr int kTileBits = 6;  // 64 x 64 cells
  static constexpr int kTileCells = 1 << kTileBits;
  using Tile = std::array<float, kTileCells * kTileCells>;
  void trace(const Eigen::Vector2d& from_m, const Eigen::Vector2d& to_m, bool hit);
  float& cell(std::int64_t col, std::int64_t row);
  void update(std::int64_t col, std::int64_t row, float delta);

  double resolution_m_;
  float hit_, miss_, min_, max_, occupied_;
  IntegerKeyMap<std::int32_t> tile_index_;
  std::vector<Tile> tiles_;
  std::vector<std::uint64_t> tile_keys_;  // tiles_[i]'s key
  std::uint64_t last_tile_key_ = 0;
  std::int32_t last_tile_ = -1;  // the index of last_tile_key_'s tile; -1 before the first cell
};

/// How an evaluated grid differs from a reference grid of the same resolution and frame.
struct MapComparison {
  std::int64_t reference_occupied = 0;  ///< Occupied cells of the reference grid.
  std::int64_t evaluated_occupied = 0;  ///< Occupied cells of the evaluated grid.
  std::int64_t wrongly_occupied = 0;    ///< Occupied in the evaluated grid, not in the reference.
  std::int64_t lost = 0;                ///< Occupied in the reference grid, not in the evaluated.
  /// As shares of the reference's occupied cells (NaN when it has none).
  double wrongly_occupied_share() const;
  double lost_share() const;
};

MapComparison compare_maps(const OccupancyGrid& reference, const OccupancyGrid& evaluated);

}  // namespace dispel::eval
