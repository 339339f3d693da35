#pragma once
/// @file
/// Occupancy grids as robotics engineers keep them: ROS map_server's map format (a YAML file and
/// a PGM image beside it), with cells as nav_msgs/OccupancyGrid holds them. No MRPT here.

#include <cstdint>
#include <string>
#include <vector>

#include "dispel/core/pose2.hpp"
#include "dispel/eval/map_quality.hpp"

namespace dispel::slam {

inline constexpr std::int8_t kUnknownCell = -1;    ///< Never observed.
inline constexpr std::int8_t kFreeCell = 0;        ///< Occupancy 0 %.
inline constexpr std::int8_t kOccupiedCell = 100;  ///< Occupancy 100 %.

/// An occupancy grid in a map frame, laid out as nav_msgs/OccupancyGrid: cell (col, row) covers
/// [col, col + 1) x [row, row + 1) cells from the origin along the grid's x and y axes; row 0 is
/// the bottom row of the map_server image.
struct GridMap {
  double resolution_m = 0.05;  ///< Edge of a cell (m).
  /// The corner of cell (0, 0) in the map frame (m, m), and the grid's x axis (rad).
  Pose2 origin;
  int width = 0;   ///< Cells along the grid's x axis.
  int height = 0;  ///< Cells along the grid's y axis.
  /// Row-major, width * height values: kUnknownCell, or the occupancy in percent (0 free ... 100
  /// occupied).
  std::vector<std::int8_t> cells;

  std::int8_t at(int col, int row) const {
    return cells[static_cast<std::size_t>(row) * static_cast<std::size_t>(width) +
                 static_cast<std::size_t>(col)];
  }
  /// Occupied cells (occupancy >= 65 %, map_saver's threshold).
  std::int64_t occupied_cells() const;
  /// Free cells (occupancy <= 25 %, map_saver's threshold).
  std::int64_t free_cells() const;
  /// @throws dispel::jobs::JobError naming the problem: a non-positive or non-finite resolution, a
  /// non-finite origin, no cells, cells.size() != width * height, a cell outside -1..100.
  void validate() const;

  friend bool operator==(const GridMap& a, const GridMap& b) {
    return a.resolution_m == b.resolution_m && a.origin.x_m == b.origin.x_m &&
           a.origin.y_m == b.origin.y_m && a.origin.yaw_rad == b.origin.yaw_rad &&
           a.width == b.width && a.height == b.height && a.cells == b.cells;
  }
  friend bool operator!=(const GridMap& a, const GridMap& b) { return !(a == b); }
};

/// How @p evaluated's occupied cells differ from @p reference's, two maps of one place in one
/// frame whose cells need not line up (each may have its own origin, rotation and resolution):
/// an occupied cell of one map counts as matched when the other map has an occupied cell whose
/// centre lies within @p tolerance_m of its centre. The counts of eval::MapComparison: occupied
/// cells of each, evaluated cells unmatched (wrongly occupied), reference cells unmatched (lost).
/// @throws dispel::jobs::JobError for an invalid map or a tolerance that is negative or not finite.
eval::MapComparison compare_grid_maps(const GridMap& reference, const GridMap& evaluated,
                                      double tolerance_m);

/// Reads a map_server map: the YAML file's keys image (a PGM, P5 or P2, with a maximum value up
/// to 255; a relative path is relative to the YAML file's folder), resolution (m/cell, > 0),
/// origin ([x, y, yaw]), negate (0/1), occupied_thresh, free_thresh (0 <= free <= occupied <= 1)
/// and the optional mode (trinary (default), scale or raw), interpreted as map_server does:
/// occupancy p = (255 - pixel) / 255 (pixel / 255 with negate) is occupied above occupied_thresh,
/// free below free_thresh, otherwise unknown (trinary) or scaled to 0-99 (scale); raw takes the
/// pixel as the cell value (above 100: unknown). The image's top row is the grid's last row.
/// @throws dispel::jobs::JobError "<file>: <problem>" for a missing or unreadable file, a file that
/// is not YAML or not PGM, a missing or malformed key, a non-positive resolution, or an image
/// whose size does not match its header.
GridMap read_map_yaml(const std::string& yaml_path);

/// Writes @p map as map_server's map_saver does: "<stem>.pgm" beside @p yaml_path (P5, occupied
/// >= 65 % black (0), free <= 25 % white (254), otherwise unknown grey (205)) and the YAML file
/// (negate 0, occupied_thresh 0.65, free_thresh 0.196, origin and resolution exact), each written
/// to "<file>.partial" and renamed, the image first. Cells between 25 % and 65 % are written as
/// unknown: read_map_yaml() gives back exactly a map whose cells are -1, 0 or 100.
/// @throws dispel::jobs::JobError for an invalid map (non-positive or non-finite resolution, an
/// empty grid, cells.size() != width * height, a cell outside -1..100) or a write failure.
void write_map_yaml(const GridMap& map, const std::string& yaml_path);

}  // namespace dispel::slam
