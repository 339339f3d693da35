#include "dispel/core/free_space_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
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
  if (max_recent_hits < 0 || max_recent_hits > 10000) {
    bad("max_recent_hits", max_recent_hits, "in [0, 10000]");
  }
  if (min_free_observations > 10000) {
    bad("min_free_observations", min_free_observations, "<= 10000");
  }
  if (long_occupied_scans < 1 || long_occupied_scans > 10000) {
    bad("long_occupied_scans", long_occupied_scans, "in [1, 10000]");
  }
  if (!(memory_s > 0.0)) bad("memory_s", memory_s, "> 0");
  if (!(free_range_m > 0.0 && std::isfinite(free_range_m))) {
    bad("free_range_m", free_range_m, "finite and > 0");
  }
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
  tiles_per_side_ = (cells_per_side_ + kTileSide - 1) / kTileSide;
}

void FreeSpaceMap::clear() {
  cells_.clear();
  placed_ = false;
}

void FreeSpaceMap::recenter(const Eigen::Vector2d& center) {
  origin_ = center - Eigen::Vector2d::Constant(0.5 * config_.extent_m);
  cells_.assign(static_cast<std::size_t>(tiles_per_side_ * tiles_per_side_ * kTileSide * kTileSide),
                Cell{});
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
  index = cell_index(ix, iy);
  return true;
}

bool FreeSpaceMap::cell_free(const Eigen::Vector2d& p) const {
  std::int64_t i = 0;
  if (!index_of(p, i)) return false;
  const Cell& cell = cells_[static_cast<std::size_t>(i)];
  return cell.balance <= -config_.min_free_observations &&
         stamp_s_ - (epoch_s_ + cell.last_free_s) <= config_.memory_s;
}

bool FreeSpaceMap::known_free(const Eigen::Vector2d& point_m) const {
  const double c = config_.cell_size_m;
  const int n = config_.neighbourhood_cells;
  // The point's own cell first: most points asked about (a surface's) fail there.
  if (!cell_free(point_m)) return false;
  for (int dx = -n; dx <= n; ++dx) {
    for (int dy = -n; dy <= n; ++dy) {
      if ((dx != 0 || dy != 0) && !cell_free(point_m + Eigen::Vector2d(dx * c, dy * c))) {
        return false;
      }
    }
  }
  return true;
}

bool FreeSpaceMap::known_free(const Eigen::Vector2d& point_m, double max_beam_spacing_m) const {
  if (!known_free(point_m)) return false;
  const double c = config_.cell_size_m;
  const double limit = max_beam_spacing_m / kSpacingUnit_m;
  for (int dx = -1; dx <= 1; ++dx) {
    for (int dy = -1; dy <= 1; ++dy) {
      std::int64_t i = 0;
      if (!index_of(point_m + Eigen::Vector2d(dx * c, dy * c), i)) return false;
      const std::uint8_t s = cells_[static_cast<std::size_t>(i)].finest_spacing;
      if (s == kNeverSeenThrough || static_cast<double>(s) > limit) return false;
    }
  }
  return true;
}

int FreeSpaceMap::occupied_scans(const Eigen::Vector2d& point_m) const {
  std::int64_t i = 0;
  return index_of(point_m, i) ? cells_[static_cast<std::size_t>(i)].occupied : 0;
}

int FreeSpaceMap::hit_balance(const Eigen::Vector2d& point_m) const {
  std::int64_t i = 0;
  return index_of(point_m, i) ? cells_[static_cast<std::size_t>(i)].balance : 0;
}

// Every kCoarsestStride-th beam is traced from the scanner on; see add_scan().
constexpr std::size_t kCoarsestStride = 16;

void FreeSpaceMap::add_scan(const LaserScan& scan, const Pose2& sensor_pose) {
  const Eigen::Vector2d origin = sensor_pose.translation();
  if (!placed_) {
    recenter(origin);
    epoch_s_ = scan.stamp_s;
  }
  std::int64_t probe = 0;
  const double keep = 0.25 * config_.extent_m;  // Re-centre well before the edge.
  if (!index_of(origin + Eigen::Vector2d(keep, keep), probe) ||
      !index_of(origin - Eigen::Vector2d(keep, keep), probe)) {
    recenter(origin);
  }
  ++scans_;
  stamp_s_ = scan.stamp_s;
  const double c = config_.cell_size_m;
  const double no_return_reach =
      config_.no_return_is_free
          ? std::min(config_.free_range_m, static_cast<double>(scan.range_max_m))
          : 0.0;
  // Each beam's direction in the fixed frame, once per scan (both passes below need it).
  const std::vector<Eigen::Vector2d>& unit = beam_directions_.of(scan);
  const PoseTransform to_fixed(sensor_pose);
  directions_.resize(scan.size());
  for (std::size_t b = 0; b < scan.size(); ++b) directions_[b] = to_fixed.rotate(unit[b]);
  const int cap = config_.min_free_observations + config_.max_recent_hits;
  const auto free_s = static_cast<float>(scan.stamp_s - epoch_s_);
  // Beam spacing per cell of range, in kSpacingUnit_m.
  const double spacing_per_cell = std::abs(scan.angle_increment_rad) * c / kSpacingUnit_m;
  // Hits first: a cell hit in this scan counts as hit, whatever other beams passed through it.
  for (std::size_t b = 0; b < scan.size(); ++b) {
    if (!scan.is_valid(b)) continue;
    std::int64_t i = 0;
    if (!index_of(origin + scan.ranges_m[b] * directions_[b], i)) continue;
    Cell& cell = cells_[static_cast<std::size_t>(i)];
    if (cell.last_scan == scans_) continue;
    cell.last_scan = scans_;
    cell.balance = static_cast<std::int16_t>(std::min(cell.balance + 1, cap));
    cell.occupied =
        static_cast<std::int16_t>(std::min(cell.occupied + 1, 2 * config_.long_occupied_scans));
  }
  // How far each beam saw free space: to margin_m before its return, or (no return) its reach.
  free_until_.assign(scan.size(), 0.0);
  for (std::size_t b = 0; b < scan.size(); ++b) {
    if (scan.is_valid(b)) {
      free_until_[b] = std::min(scan.ranges_m[b] - config_.margin_m, config_.free_range_m);
    } else if (std::isinf(scan.ranges_m[b]) && scan.ranges_m[b] > 0.0) {
      free_until_[b] = no_return_reach;
    }
  }
  for (std::size_t b = 0; b < scan.size(); ++b) {
    const double free_until = free_until_[b];
    if (!(free_until > 0.0)) continue;
    // Near the scanner neighbouring beams cross the same cells. A beam that is a multiple of k
    // but not of 2k is traced only from where its two neighbours of the coarser level (b - k and
    // b + k) are more than a cell apart, or from where one of them ends if that is nearer (the
    // edge of an occluder). Lines at most a cell apart cross every cell between them (a square's
    // width across any direction is at least its side).
    std::size_t level = kCoarsestStride;
    while (level > 1 && b % level != 0) level /= 2;
    double start = 0.0;
    if (level < kCoarsestStride && b >= level && b + level < scan.size()) {
      start = std::min({c / (2.0 * static_cast<double>(level) * std::abs(scan.angle_increment_rad)),
                        free_until_[b - level], free_until_[b + level]});
    }
    if (!(free_until > start)) continue;
    // Every cell the beam crosses from start to free_until, each once (Amanatides and Woo's
    // traversal, in cell units).
    const Eigen::Vector2d& dir = directions_[b];
    const Eigen::Vector2d from = origin + start * dir;
    const double fx = (from.x() - origin_.x()) / c, fy = (from.y() - origin_.y()) / c;
    const double cx = std::floor(fx), cy = std::floor(fy);
    auto ix = static_cast<std::int64_t>(cx);
    auto iy = static_cast<std::int64_t>(cy);
    const int step_x = dir.x() > 0.0 ? 1 : -1, step_y = dir.y() > 0.0 ? 1 : -1;
    const double inf = std::numeric_limits<double>::infinity();
    const double delta_x = dir.x() != 0.0 ? std::abs(1.0 / dir.x()) : inf;
    const double delta_y = dir.y() != 0.0 ? std::abs(1.0 / dir.y()) : inf;
    double next_x = dir.x() != 0.0 ? (step_x > 0 ? cx + 1.0 - fx : fx - cx) * delta_x : inf;
    double next_y = dir.y() != 0.0 ? (step_y > 0 ? cy + 1.0 - fy : fy - cy) * delta_y : inf;
    const double length = (free_until - start) / c;
    const double start_cells = start / c;
    double t = 0.0;
    while (t < length && ix >= 0 && iy >= 0 && ix < cells_per_side_ && iy < cells_per_side_) {
      Cell& cell = cells_[static_cast<std::size_t>(cell_index(ix, iy))];
      if (cell.last_scan != scans_) {
        cell.last_scan = scans_;
        cell.balance = static_cast<std::int16_t>(std::max(cell.balance - 1, -cap));
        cell.occupied = static_cast<std::int16_t>(std::max(cell.occupied - 1, 0));
        cell.last_free_s = free_s;
        // Where the beam leaves the cell (the spacing is largest there).
        const double spacing = (start_cells + std::min(next_x, next_y)) * spacing_per_cell;
        if (spacing < static_cast<double>(cell.finest_spacing)) {
          cell.finest_spacing = static_cast<std::uint8_t>(spacing);
        }
      }
      if (next_x < next_y) {
        t = next_x;
        next_x += delta_x;
        ix += step_x;
      } else {
        t = next_y;
        next_y += delta_y;
        iy += step_y;
      }
    }
  }
}

}  // namespace dispel
