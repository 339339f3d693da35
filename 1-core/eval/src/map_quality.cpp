#include "dispel/eval/map_quality.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <string>

namespace dispel::eval {
namespace {

float log_odds(double p) { return static_cast<float>(std::log(p / (1.0 - p))); }

}  // namespace

void OccupancyGridConfig::validate() const {
  const auto fail = [](const std::string& what) { throw std::invalid_argument(what); };
  if (!std::isfinite(resolution_m) || resolution_m <= 0.0) {
    fail("map resolution " + std::to_string(resolution_m) + " m must be finite and positive");
  }
  const auto probability = [&](const char* name, double p) {
    if (!(p > 0.0 && p < 1.0)) {
      fail(std::string(name) + " " + std::to_string(p) + " must lie in (0, 1)");
    }
  };
  probability("hit probability", hit_probability);
  probability("miss probability", miss_probability);
  probability("min probability", min_probability);
  probability("max probability", max_probability);
  probability("occupied probability", occupied_probability);
  if (hit_probability <= 0.5) fail("hit probability must be above 0.5");
  if (miss_probability >= 0.5) fail("miss probability must be below 0.5");
  if (!(min_probability < 0.5 && max_probability > 0.5)) {
    fail("the clamp range (min probability, max probability) must hold 0.5");
  }
  if (occupied_probability < min_probability || occupied_probability > max_probability) {
    fail("occupied probability must lie within the clamp range");
  }
}

OccupancyGrid::OccupancyGrid(const OccupancyGridConfig& config) {
  config.validate();
  resolution_m_ = config.resolution_m;
  hit_ = log_odds(config.hit_probability);
  miss_ = log_odds(config.miss_probability);
  min_ = log_odds(config.min_probability);
  max_ = log_odds(config.max_probability);
  occupied_ = log_odds(config.occupied_probability);
}

float& OccupancyGrid::cell(std::int64_t col, std::int64_t row) {
  // Floor division, negative cells too (no shifts: a negative value's left shift is undefined).
  const auto floor_div = [](std::int64_t v) {
    return v >= 0 ? v / kTileCells : -((-v + kTileCells - 1) / kTileCells);
  };
  const std::int64_t tile_col = floor_div(col), tile_row = floor_div(row);
  const std::uint64_t key = cell_key(tile_col, tile_row);
  if (last_tile_ < 0 || key != last_tile_key_) {
    std::int32_t* index = tile_index_.find(key);
    if (index == nullptr) {
      Tile fresh;
      fresh.fill(std::numeric_limits<float>::quiet_NaN());  // NaN: no ray reached it.
      tiles_.push_back(fresh);
      tile_keys_.push_back(key);
      tile_index_[key] = static_cast<std::int32_t>(tiles_.size() - 1);
      index = tile_index_.find(key);
    }
    last_tile_key_ = key;
    last_tile_ = *index;
  }
  const std::int64_t c = col - tile_col * kTileCells, r = row - tile_row * kTileCells;
  return tiles_[static_cast<std::size_t>(last_tile_)][static_cast<std::size_t>(r * kTileCells + c)];
}

void OccupancyGrid::update(std::int64_t col, std::int64_t row, float delta) {
  float& l = cell(col, row);
  l = std::clamp((std::isnan(l) ? 0.0F : l) + delta, min_, max_);
}

void OccupancyGrid::trace(const Eigen::Vector2d& from_m, const Eigen::Vector2d& to_m, bool hit) {
  if (!from_m.allFinite() || !to_m.allFinite()) return;
  const Eigen::Vector2d a = from_m / resolution_m_, b = to_m / resolution_m_;
  // Cells beyond +-2^31 cannot be packed: such a return is no map (about 10^8 m at 0.05 m).
  constexpr double kLimit = 2.0e9;
  if (a.cwiseAbs().maxCoeff() > kLimit || b.cwiseAbs().maxCoeff() > kLimit) return;
  std::int64_t col = static_cast<std::int64_t>(std::floor(a.x()));
  std::int64_t row = static_cast<std::int64_t>(std::floor(a.y()));
  const std::int64_t end_col = static_cast<std::int64_t>(std::floor(b.x()));
  const std::int64_t end_row = static_cast<std::int64_t>(std::floor(b.y()));
  // A grid traversal (Amanatides and Woo): step into the neighbour whose border the ray meets
  // first, until the end cell; at most |dcol| + |drow| steps.
  const Eigen::Vector2d d = b - a;
  const std::int64_t step_col = d.x() > 0.0 ? 1 : -1, step_row = d.y() > 0.0 ? 1 : -1;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const double delta_col = d.x() != 0.0 ? std::abs(1.0 / d.x()) : kInf;
  const double delta_row = d.y() != 0.0 ? std::abs(1.0 / d.y()) : kInf;
  double next_col = d.x() != 0.0 ? (step_col > 0 ? (static_cast<double>(col) + 1.0 - a.x())
                                                 : (a.x() - static_cast<double>(col))) *
                                       delta_col
                                 : kInf;
  double next_row = d.y() != 0.0 ? (step_row > 0 ? (static_cast<double>(row) + 1.0 - a.y())
                                                 : (a.y() - static_cast<double>(row))) *
                                       delta_row
                                 : kInf;
  std::int64_t steps = std::abs(end_col - col) + std::abs(end_row - row);
  for (; steps > 0 && (col != end_col || row != end_row); --steps) {
    update(col, row, miss_);
    if (next_col < next_row) {
      col += step_col;
      next_col += delta_col;
    } else {
      row += step_row;
      next_row += delta_row;
    }
  }
  update(end_col, end_row, hit ? hit_ : miss_);
}

std::vector<std::uint64_t> OccupancyGrid::occupied_cells() const {
  std::vector<std::uint64_t> out;
  for (std::size_t t = 0; t < tiles_.size(); ++t) {
    const std::int64_t tile_col = static_cast<std::int32_t>(tile_keys_[t] >> 32);
    const std::int64_t tile_row = static_cast<std::int32_t>(tile_keys_[t] & 0xffffffffU);
    const Tile& tile = tiles_[t];
    for (int r = 0; r < kTileCells; ++r) {
      for (int c = 0; c < kTileCells; ++c) {
        const float l = tile[static_cast<std::size_t>(r * kTileCells + c)];
        if (l >= occupied_) {  // false for NaN
          out.push_back(cell_key(tile_col * kTileCells + c, tile_row * kTileCells + r));
        }
      }
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::int64_t OccupancyGrid::known_cells() const {
  std::int64_t n = 0;
  for (const Tile& tile : tiles_) {
    n += std::count_if(tile.begin(), tile.end(), [](float l) { return !std::isnan(l); });
  }
  return n;
}

double MapComparison::wrongly_occupied_share() const {
  return reference_occupied > 0
             ? static_cast<double>(wrongly_occupied) / static_cast<double>(reference_occupied)
             : std::numeric_limits<double>::quiet_NaN();
}

double MapComparison::lost_share() const {
  return reference_occupied > 0
             ? static_cast<double>(lost) / static_cast<double>(reference_occupied)
             : std::numeric_limits<double>::quiet_NaN();
}

MapComparison compare_maps(const OccupancyGrid& reference, const OccupancyGrid& evaluated) {
  if (reference.resolution_m() != evaluated.resolution_m()) {
    throw std::invalid_argument("the grids to compare have different resolutions");
  }
  const std::vector<std::uint64_t> ref = reference.occupied_cells();
  const std::vector<std::uint64_t> got = evaluated.occupied_cells();
  MapComparison out;
  out.reference_occupied = static_cast<std::int64_t>(ref.size());
  out.evaluated_occupied = static_cast<std::int64_t>(got.size());
  std::size_t i = 0, j = 0;
  while (i < ref.size() || j < got.size()) {
    if (j == got.size() || (i < ref.size() && ref[i] < got[j])) {
      ++out.lost;
      ++i;
    } else if (i == ref.size() || got[j] < ref[i]) {
      ++out.wrongly_occupied;
      ++j;
    } else {
      ++i;
      ++j;
    }
  }
  return out;
}

}  // namespace dispel::eval
