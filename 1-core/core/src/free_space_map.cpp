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
  const auto cells_per_side =
      static_cast<std::int64_t>(std::ceil(config_.extent_m / config_.cell_size_m));
  tiles_per_side_ = (cells_per_side + kTileSide - 1) / kTileSide;
  reach_cells_ = std::max<std::int64_t>(0, tiles_per_side_ * kTileSide / 2 - kTileSide);
  const auto slots = static_cast<std::size_t>(tiles_per_side_ * tiles_per_side_);
  // Not value-initialised: a slot's cells are written when its tile is started, and the pages of
  // slots never used are never touched.
  cells_.reset(new Cell[slots * static_cast<std::size_t>(kTileCells)]);
  tags_.assign(slots, TileTag{0, 0, 0});  // Generation 0 is never current.
}

void FreeSpaceMap::clear() {
  placed_ = false;
  ++generation_;
  if (generation_ == 0) {  // Wrapped after 2^32 clears: no tag may look current.
    std::fill(tags_.begin(), tags_.end(), TileTag{0, 0, 0});
    generation_ = 1;
  }
}

std::size_t FreeSpaceMap::slot_of(std::int64_t tx, std::int64_t ty) const {
  const std::int64_t sx = ((tx % tiles_per_side_) + tiles_per_side_) % tiles_per_side_;
  const std::int64_t sy = ((ty % tiles_per_side_) + tiles_per_side_) % tiles_per_side_;
  return static_cast<std::size_t>(sy * tiles_per_side_ + sx);
}

bool FreeSpaceMap::within_reach(std::int64_t ix, std::int64_t iy) const {
  return std::abs(ix - sensor_ix_) <= reach_cells_ && std::abs(iy - sensor_iy_) <= reach_cells_;
}

bool FreeSpaceMap::cell_of(const Eigen::Vector2d& p, std::int64_t& ix, std::int64_t& iy) const {
  if (!placed_) return false;
  const double fx = std::floor((p.x() - anchor_.x()) / config_.cell_size_m);
  const double fy = std::floor((p.y() - anchor_.y()) / config_.cell_size_m);
  // Compared as doubles first: a point far away (or NaN) is refused before any integer cast.
  const double reach = static_cast<double>(reach_cells_);
  if (!(std::abs(fx - static_cast<double>(sensor_ix_)) <= reach &&
        std::abs(fy - static_cast<double>(sensor_iy_)) <= reach)) {
    return false;
  }
  ix = static_cast<std::int64_t>(fx);
  iy = static_cast<std::int64_t>(fy);
  return true;
}

const FreeSpaceMap::Cell* FreeSpaceMap::find(std::int64_t ix, std::int64_t iy) const {
  // Arithmetic shifts: floor division and a non-negative remainder for negative cells too.
  const std::int64_t tx = ix >> kTileBits, ty = iy >> kTileBits;
  const std::size_t slot = slot_of(tx, ty);
  const TileTag& tag = tags_[slot];
  if (tag.generation != generation_ || tag.tx != tx || tag.ty != ty) return nullptr;
  constexpr std::int64_t mask = kTileSide - 1;
  return &cells_[slot * static_cast<std::size_t>(kTileCells) +
                 static_cast<std::size_t>(((iy & mask) << kTileBits) + (ix & mask))];
}

const FreeSpaceMap::Cell* FreeSpaceMap::find(const Eigen::Vector2d& p) const {
  std::int64_t ix = 0, iy = 0;
  return cell_of(p, ix, iy) ? find(ix, iy) : nullptr;
}

FreeSpaceMap::Cell& FreeSpaceMap::touch(std::int64_t ix, std::int64_t iy) {
  const std::int64_t tx = ix >> kTileBits, ty = iy >> kTileBits;
  const std::size_t slot = slot_of(tx, ty);
  Cell* tile = &cells_[slot * static_cast<std::size_t>(kTileCells)];
  TileTag& tag = tags_[slot];
  if (tag.generation != generation_ || tag.tx != tx || tag.ty != ty) {
    std::fill(tile, tile + kTileCells, kEmptyCell);
    tag = TileTag{tx, ty, generation_};
    ++tiles_started_;
  }
  constexpr std::int64_t mask = kTileSide - 1;
  return tile[((iy & mask) << kTileBits) + (ix & mask)];
}

bool FreeSpaceMap::cell_free(const Eigen::Vector2d& p) const {
  const Cell* cell = find(p);
  return cell != nullptr && cell->balance <= -config_.min_free_observations &&
         stamp_s_ - (epoch_s_ + cell->last_free_s) <= config_.memory_s;
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
      const Cell* cell = find(point_m + Eigen::Vector2d(dx * c, dy * c));
      if (cell == nullptr) return false;
      const std::uint8_t s = cell->finest_spacing;
      if (s == kNeverSeenThrough || static_cast<double>(s) > limit) return false;
    }
  }
  return true;
}

int FreeSpaceMap::occupied_scans(const Eigen::Vector2d& point_m) const {
  const Cell* cell = find(point_m);
  return cell != nullptr ? cell->occupied : 0;
}

int FreeSpaceMap::hit_balance(const Eigen::Vector2d& point_m) const {
  const Cell* cell = find(point_m);
  return cell != nullptr ? cell->balance : 0;
}

// Every kCoarsestStride-th beam is traced from the scanner on; see add_scan().
constexpr std::size_t kCoarsestStride = 16;

void FreeSpaceMap::add_scan(const LaserScan& scan, const Pose2& sensor_pose) {
  const Eigen::Vector2d origin = sensor_pose.translation();
  if (!(std::isfinite(origin.x()) && std::isfinite(origin.y()))) return;
  if (!placed_) {
    // The cells' boundaries as if the window were centred on the first pose.
    anchor_ = origin - Eigen::Vector2d::Constant(0.5 * config_.extent_m);
    placed_ = true;
    sensor_ix_ = sensor_iy_ = 0;
    epoch_s_ = scan.stamp_s;
  }
  {
    const double fx = std::floor((origin.x() - anchor_.x()) / config_.cell_size_m);
    const double fy = std::floor((origin.y() - anchor_.y()) / config_.cell_size_m);
    // A sensor that jumped absurdly far (2^40 cells) starts afresh rather than overflow.
    constexpr double kFar = 1099511627776.0;
    if (!(std::abs(fx) < kFar && std::abs(fy) < kFar)) {
      clear();
      add_scan(scan, sensor_pose);
      return;
    }
    sensor_ix_ = static_cast<std::int64_t>(fx);
    sensor_iy_ = static_cast<std::int64_t>(fy);
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
    std::int64_t ix = 0, iy = 0;
    if (!cell_of(origin + scan.ranges_m[b] * directions_[b], ix, iy)) continue;
    Cell& cell = touch(ix, iy);
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
    const double fx = (from.x() - anchor_.x()) / c, fy = (from.y() - anchor_.y()) / c;
    const double cx = std::floor(fx), cy = std::floor(fy);
    std::int64_t ix = 0, iy = 0;
    if (!cell_of(from, ix, iy)) continue;
    const int step_x = dir.x() > 0.0 ? 1 : -1, step_y = dir.y() > 0.0 ? 1 : -1;
    const double inf = std::numeric_limits<double>::infinity();
    const double delta_x = dir.x() != 0.0 ? std::abs(1.0 / dir.x()) : inf;
    const double delta_y = dir.y() != 0.0 ? std::abs(1.0 / dir.y()) : inf;
    double next_x = dir.x() != 0.0 ? (step_x > 0 ? cx + 1.0 - fx : fx - cx) * delta_x : inf;
    double next_y = dir.y() != 0.0 ? (step_y > 0 ? cy + 1.0 - fy : fy - cy) * delta_y : inf;
    const double length = (free_until - start) / c;
    const double start_cells = start / c;
    double t = 0.0;
    // The reach is a square around the sensor: a beam that leaves it never comes back.
    while (t < length && within_reach(ix, iy)) {
      Cell& cell = touch(ix, iy);
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
