#include "dispel/core/free_space_map.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "dispel/core/invalid_field.hpp"

namespace dispel {

void FreeSpaceConfig::validate() const {
  auto bad = [](const char* field, double v, const char* rule) {
    reject_field(std::string("free_space.") + field, v, rule);
  };
  if (!(cell_size_m > 0.0 && std::isfinite(cell_size_m))) bad("cell_size_m", cell_size_m, "> 0");
  if (!(extent_m >= 10.0 * cell_size_m && extent_m / cell_size_m <= 8192.0)) {
    bad("extent_m", extent_m, "between 10 and 8192 cells");
  }
  if (!(margin_m >= 0.0)) bad("margin_m", margin_m, ">= 0");
  if (min_free_observations < 1) bad("min_free_observations", min_free_observations, ">= 1");
  if (max_recent_hits < 0) bad("max_recent_hits", max_recent_hits, ">= 0");
  if (neighbourhood_cells < 0 || neighbourhood_cells > 10) {
    bad("neighbourhood_cells", neighbourhood_cells, "in [0, 10]");
  }
  if (!(min_object_share > 0.0 && min_object_share <= 1.0)) {
    bad("min_object_share", min_object_share, "in (0, 1]");
  }
}

FreeSpaceMap::FreeSpaceMap(FreeSpaceConfig config) : config_(config) {
  config_.validate();
  cells_per_side_ = static_cast<std::int64_t>(std::ceil(config_.extent_m / config_.cell_size_m));
}

void FreeSpaceMap::clear() {
  cells_.clear();
  placed_ = false;
}

void FreeSpaceMap::recenter(const Eigen::Vector2d& center) {
  origin_ = center - Eigen::Vector2d::Constant(0.5 * config_.extent_m);
  cells_.assign(static_cast<std::size_t>(cells_per_side_ * cells_per_side_), Cell{});
  placed_ = true;
}

bool FreeSpaceMap::index_of(const Eigen::Vector2d& p, std::int64_t& index) const {
  if (!placed_) return false;
  const double fx = (p.x() - origin_.x()) / config_.cell_size_m;
  const double fy = (p.y() - origin_.y()) / config_.cell_size_m;
  if (!(fx >= 0.0 && fy >= 0.0)) return false;
  const auto ix = static_cast<std::int64_t>(fx);
  const auto iy = static_cast<std::int64_t>(fy);
  if (ix >= cells_per_side_ || iy >= cells_per_side_) return false;
  index = iy * cells_per_side_ + ix;
  return true;
}

bool FreeSpaceMap::known_free(const Eigen::Vector2d& point_m) const {
  const double c = config_.cell_size_m;
  const int n = config_.neighbourhood_cells;
  for (int dx = -n; dx <= n; ++dx) {
    for (int dy = -n; dy <= n; ++dy) {
      std::int64_t i = 0;
      if (!index_of(point_m + Eigen::Vector2d(dx * c, dy * c), i)) return false;
      const Cell& cell = cells_[static_cast<std::size_t>(i)];
      if (cell.free < config_.min_free_observations || cell.hits > config_.max_recent_hits) {
        return false;
      }
    }
  }
  return true;
}

void FreeSpaceMap::add_scan(const LaserScan& scan, const Pose2& sensor_pose) {
  const Eigen::Vector2d origin = sensor_pose.translation();
  if (!placed_) recenter(origin);
  std::int64_t probe = 0;
  const double keep = 0.25 * config_.extent_m;  // Re-centre well before the edge.
  if (!index_of(origin + Eigen::Vector2d(keep, keep), probe) ||
      !index_of(origin - Eigen::Vector2d(keep, keep), probe)) {
    recenter(origin);
  }
  ++scans_;
  const double step = 0.5 * config_.cell_size_m;
  for (std::size_t b = 0; b < scan.size(); ++b) {
    if (!scan.is_valid(b)) continue;
    const double r = scan.ranges_m[b];
    const double bearing = sensor_pose.yaw_rad + scan.bearing_rad(b);
    const Eigen::Vector2d dir(std::cos(bearing), std::sin(bearing));
    std::int64_t last = -1;
    for (double s = 0.0; s < r - config_.margin_m; s += step) {
      std::int64_t i = 0;
      if (!index_of(origin + s * dir, i) || i == last) continue;
      last = i;
      Cell& cell = cells_[static_cast<std::size_t>(i)];
      if (cell.last_scan != scans_ && cell.free < 65535) ++cell.free;
      cell.last_scan = scans_;
      cell.hits = 0;
    }
    std::int64_t hit = 0;
    if (index_of(origin + r * dir, hit)) {
      Cell& cell = cells_[static_cast<std::size_t>(hit)];
      if (cell.last_hit_scan != scans_ && cell.hits < 65535) ++cell.hits;
      cell.last_hit_scan = scans_;
    }
  }
}

}  // namespace dispel
