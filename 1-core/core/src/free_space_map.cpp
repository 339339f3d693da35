#include "dispel/core/free_space_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "dispel/core/floor_index.hpp"
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

FreeSpaceMap::FreeSpaceMap(FreeSpaceConfig config)
    : FreeSpaceMap((config.validate(), config), Unallocated{}) {
  allocate();
}

// The window's size from the configuration (validated); no memory yet.
FreeSpaceMap::FreeSpaceMap(const FreeSpaceConfig& config, Unallocated /*unused*/)
    : config_(config) {
  const auto cells_per_side =
      static_cast<std::int64_t>(std::ceil(config_.extent_m / config_.cell_size_m));
  tiles_per_side_ = (cells_per_side + kTileSide - 1) / kTileSide;
  if ((tiles_per_side_ & (tiles_per_side_ - 1)) == 0) slot_mask_ = tiles_per_side_ - 1;
  reach_tiles_ = (tiles_per_side_ - 1) / 2;
}

void FreeSpaceMap::allocate() {
  const auto slots = static_cast<std::size_t>(tiles_per_side_ * tiles_per_side_);
  // Zeroed here, once (a slot's cells are emptied again when its tile is started): the window's
  // memory is resident from the start. Left untouched, its pages came in one by one as a robot
  // whose odometry drifts reached new slots: resident memory rose for hours (the soak,
  // docs/soak.md) and a scan now and then paid for page faults.
  cells_.reset(new Cell[slots * static_cast<std::size_t>(kTileCells)]());
  tags_.assign(slots, TileTag{0, 0, 0});  // Generation 0 is never current.
}

FreeSpaceMap::FreeSpaceMap(FreeSpaceConfig config, FreeSpaceMap&& earlier)
    : FreeSpaceMap((config.validate(), config), Unallocated{}) {
  if (earlier.cells_ != nullptr && earlier.tiles_per_side_ == tiles_per_side_) {
    cells_ = std::move(earlier.cells_);
    tags_ = std::move(earlier.tags_);
    generation_ = earlier.generation_;
    clear();  // Its tiles are not current here.
  } else {
    allocate();
  }
}

void FreeSpaceMap::clear() {
  placed_ = false;
  ++generation_;
  if (generation_ == 0) {  // Wrapped after 2^32 clears: no tag may look current.
    std::fill(tags_.begin(), tags_.end(), TileTag{0, 0, 0});
    generation_ = 1;
  }
}

inline bool FreeSpaceMap::cell_of(const Eigen::Vector2d& p, std::int64_t& ix,
                                  std::int64_t& iy) const {
  if (!placed_) return false;
  const double fx = (p.x() - anchor_.x()) / config_.cell_size_m;
  const double fy = (p.y() - anchor_.y()) / config_.cell_size_m;
  // Compared as doubles first: a point far away (or NaN) is refused before any integer cast (a
  // tile more than the reach; the tile's own test below is exact).
  const double reach = static_cast<double>((reach_tiles_ + 1) * kTileSide);
  if (!(std::abs(fx - static_cast<double>(sensor_tx_ * kTileSide)) <= reach &&
        std::abs(fy - static_cast<double>(sensor_ty_ * kTileSide)) <= reach)) {
    return false;
  }
  // Rounded down without a call into libm (this runs for every beam and every cell asked about).
  ix = floor_index(fx);
  iy = floor_index(fy);
  return tile_within_reach(ix >> kTileBits, iy >> kTileBits);
}

inline const FreeSpaceMap::Cell* FreeSpaceMap::find(std::int64_t ix, std::int64_t iy) const {
  // Arithmetic shifts: floor division and a non-negative remainder for negative cells too.
  const std::int64_t tx = ix >> kTileBits, ty = iy >> kTileBits;
  if (!tile_within_reach(tx, ty)) return nullptr;
  const std::size_t slot = slot_of(tx, ty);
  const TileTag& tag = tags_[slot];
  if (tag.generation != generation_ || tag.tx != tx || tag.ty != ty) return nullptr;
  return &cells_[slot * static_cast<std::size_t>(kTileCells) +
                 static_cast<std::size_t>(in_tile(ix, iy))];
}

const FreeSpaceMap::Cell* FreeSpaceMap::find(const Eigen::Vector2d& p) const {
  std::int64_t ix = 0, iy = 0;
  return cell_of(p, ix, iy) ? find(ix, iy) : nullptr;
}

inline FreeSpaceMap::Cell* FreeSpaceMap::tile(std::int64_t tx, std::int64_t ty) {
  const std::size_t slot = slot_of(tx, ty);
  Cell* cells = &cells_[slot * static_cast<std::size_t>(kTileCells)];
  TileTag& tag = tags_[slot];
  if (tag.generation != generation_ || tag.tx != tx || tag.ty != ty) {
    std::fill(cells, cells + kTileCells, kEmptyCell);
    tag = TileTag{tx, ty, generation_};
    ++tiles_started_;
  }
  return cells;
}

inline bool FreeSpaceMap::cell_free(const Cell* cell) const {
  return cell != nullptr && cell->balance <= -config_.min_free_observations &&
         stamp_s_ - (epoch_s_ + cell->last_free_s) <= config_.memory_s;
}

bool FreeSpaceMap::known_free(const Eigen::Vector2d& point_m) const {
  std::int64_t ix = 0, iy = 0;
  return cell_of(point_m, ix, iy) && known_free(ix, iy);
}

bool FreeSpaceMap::known_free(std::int64_t ix, std::int64_t iy) const {
  const int n = config_.neighbourhood_cells;
  // The point's own cell first: most points asked about (a surface's) fail there.
  if (!cell_free(find(ix, iy))) return false;
  for (int dx = -n; dx <= n; ++dx) {
    for (int dy = -n; dy <= n; ++dy) {
      if ((dx != 0 || dy != 0) && !cell_free(find(ix + dx, iy + dy))) return false;
    }
  }
  return true;
}

bool FreeSpaceMap::known_free(const Eigen::Vector2d& point_m, double max_beam_spacing_m) const {
  std::int64_t ix = 0, iy = 0;
  if (!cell_of(point_m, ix, iy) || !known_free(ix, iy)) return false;
  const double limit = max_beam_spacing_m / kSpacingUnit_m;
  for (int dx = -1; dx <= 1; ++dx) {
    for (int dy = -1; dy <= 1; ++dy) {
      const Cell* cell = find(ix + dx, iy + dy);
      if (cell == nullptr) return false;
      const std::uint8_t s = cell->finest_spacing;
      if (s == kNeverSeenThrough || static_cast<double>(s) > limit) return false;
    }
  }
  return true;
}

bool FreeSpaceMap::long_free(const Eigen::Vector2d& point_m) const {
  std::int64_t ix = 0, iy = 0;
  if (!cell_of(point_m, ix, iy)) return false;
  const Cell* cell = find(ix, iy);
  return cell != nullptr &&
         cell->balance <= -(config_.min_free_observations + config_.max_recent_hits) &&
         known_free(ix, iy);
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

void FreeSpaceMap::add_scan(const LaserScan& scan, const Pose2& sensor_pose,
                            double turn_per_beam_rad) {
  const Eigen::Vector2d origin = sensor_pose.translation();
  if (!(std::isfinite(origin.x()) && std::isfinite(origin.y()))) return;
  if (!placed_) {
    // The cells' boundaries as if the window were centred on the first pose.
    anchor_ = origin - Eigen::Vector2d::Constant(0.5 * config_.extent_m);
    placed_ = true;
    sensor_tx_ = sensor_ty_ = 0;
    epoch_s_ = scan.stamp_s;
  }
  {
    const double fx = std::floor((origin.x() - anchor_.x()) / config_.cell_size_m);
    const double fy = std::floor((origin.y() - anchor_.y()) / config_.cell_size_m);
    // A sensor that jumped absurdly far (2^40 cells) starts afresh rather than overflow.
    constexpr double kFar = 1099511627776.0;
    if (!(std::abs(fx) < kFar && std::abs(fy) < kFar)) {
      clear();
      add_scan(scan, sensor_pose, turn_per_beam_rad);
      return;
    }
    sensor_tx_ = static_cast<std::int64_t>(fx) >> kTileBits;
    sensor_ty_ = static_cast<std::int64_t>(fy) >> kTileBits;
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
  // Beam b turned by b steps of the sensor's turn during the sweep.
  SteppedRotation turn(turn_per_beam_rad);
  for (std::size_t b = 0; b < scan.size(); ++b) {
    if (b > 0) turn.advance();
    directions_[b] = to_fixed.rotate(turn.rotate(unit[b]));
  }
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
    // A beam crosses several cells of a tile in a row: the tile is looked up (and the reach, a
    // square of tiles around the sensor's, checked) when the beam enters it, known from the cell's
    // place in its tile (lx, ly) leaving 0..kTileSide-1. A beam that leaves the reach never comes
    // back.
    std::int64_t tile_x = ix >> kTileBits, tile_y = iy >> kTileBits;
    std::int64_t lx = ix & (kTileSide - 1), ly = iy & (kTileSide - 1);
    Cell* cells = tile(tile_x, tile_y);
    for (;;) {
      Cell& cell = cells[(ly << kTileBits) + lx];
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
        lx += step_x;
      } else {
        t = next_y;
        next_y += delta_y;
        ly += step_y;
      }
      if (!(t < length)) break;
      if (((lx | ly) & ~(kTileSide - 1)) != 0) {  // Into the next tile (arithmetic shifts).
        tile_x += lx >> kTileBits;
        tile_y += ly >> kTileBits;
        lx &= kTileSide - 1;
        ly &= kTileSide - 1;
        if (!tile_within_reach(tile_x, tile_y)) break;
        cells = tile(tile_x, tile_y);
      }
    }
  }
}

}  // namespace dispel
