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

struct FreeSpaceConfig {
  bool enabled = false;  ///< Off: the thesis's filter, without this evidence.
  double cell_size_m = 0.1;
  double extent_m = 102.4;  ///< Side of the square window kept around the first pose.
  /// Free space ends this far before each return, so a surface's own cells are never "free".
  double margin_m = 0.3;
  int min_free_observations = 3;  ///< A cell is known free once seen through in this many scans...
  /// ...unless it has since been hit in more scans than this in a row (then something stands
  /// there; a walker passing through holds a cell for a few scans only).
  int max_recent_hits = 10;
  /// A point is in free space when every cell within this many cells of it is known free (room
  /// for odometry errors: a slip that shifts the map must not put a pillar in "free" space).
  int neighbourhood_cells = 2;
  /// An object whose points are in free space by at least this share appeared in free space.
  double min_object_share = 0.5;

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

/// A square window of cells around the first pose; each cell remembers how often beams passed
/// through it and whether it was last seen free or hit. Moving out of the window re-centres it.
class FreeSpaceMap {
 public:
  explicit FreeSpaceMap(FreeSpaceConfig config);

  /// True when every cell within neighbourhood_cells of the point's cell is known free.
  bool known_free(const Eigen::Vector2d& point_m) const;

  /// Adds a scan taken from @p sensor_pose: cells along each valid beam, up to margin_m before its
  /// return, are seen free; the return's cell is seen hit.
  void add_scan(const LaserScan& scan, const Pose2& sensor_pose);

  void clear();
  const FreeSpaceConfig& config() const { return config_; }

 private:
  struct Cell {
    std::uint32_t last_scan = 0;  // The scan that last saw through it (counts once per scan).
    std::uint32_t last_hit_scan = 0;
    std::uint16_t free = 0;
    std::uint16_t hits = 0;  // Scans in a row in which it was hit since it was last seen free.
  };
  bool index_of(const Eigen::Vector2d& p, std::int64_t& index) const;
  void recenter(const Eigen::Vector2d& center);

  FreeSpaceConfig config_;
  std::int64_t cells_per_side_ = 0;
  Eigen::Vector2d origin_ = Eigen::Vector2d::Zero();  // Corner of the window.
  bool placed_ = false;
  std::uint32_t scans_ = 0;
  std::vector<Cell> cells_;
};

}  // namespace dispel
