// The offline cleaner (offline_cleaner.hpp): pass 1 remembers each scan's online labels, objects
// and tracks and, per cell, when beams ended there and whether later scans saw through it; pass 2
// labels each beam with what the whole recording says of it.
#include "dispel/core/offline_cleaner.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "dispel/core/floor_index.hpp"
#include "dispel/core/invalid_field.hpp"

namespace dispel {

void CleanConfig::validate() const {
  if (!(cell_size_m >= 0.02 && cell_size_m <= 2.0))
    reject_field("clean.cell_size_m", cell_size_m, "in [0.02, 2]");
  if (moving_min_scans < 1 || moving_min_scans > 10000)
    reject_field("clean.moving_min_scans", moving_min_scans, "in [1, 10000]");
  if (!(moving_min_travel_m >= 0.0 && moving_min_travel_m <= 100.0))
    reject_field("clean.moving_min_travel_m", moving_min_travel_m, "in [0, 100]");
  if (!(moved_from_m > 0.0 && moved_from_m <= 100.0))
    reject_field("clean.moved_from_m", moved_from_m, "in (0, 100]");
  if (!(moved_max_width_m > 0.0 && moved_max_width_m <= 100.0))
    reject_field("clean.moved_max_width_m", moved_max_width_m, "in (0, 100]");
  if (vacated_min_scans < 0 || vacated_min_scans > 10000)
    reject_field("clean.vacated_min_scans", vacated_min_scans, "0 (off) or in [1, 10000]");
  if (!(free_margin_m >= 0.0 && free_margin_m <= 10.0))
    reject_field("clean.free_margin_m", free_margin_m, "in [0, 10]");
  if (!(max_trace_range_m > 0.0 && max_trace_range_m <= 1000.0))
    reject_field("clean.max_trace_range_m", max_trace_range_m, "in (0, 1000]");
}

OfflineCleaner::OfflineCleaner(CleanConfig config) : config_((config.validate(), config)) {}

std::uint64_t OfflineCleaner::key_of(const Eigen::Vector2d& p) const {
  const auto ix = floor_index(p.x() / config_.cell_size_m);
  const auto iy = floor_index(p.y() / config_.cell_size_m);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(ix)) << 32U) |
         static_cast<std::uint32_t>(iy);
}

// The cells a beam passed through from @p from to @p to (a grid traversal: every cell the segment
// crosses, in order). A cell that beams ended in and that has not been hit since is seen through
// once per scan; after vacated_min_scans scans it is vacated: its hits from the first to the last
// become an episode of something that stood there and left.
void OfflineCleaner::see_through(const Eigen::Vector2d& from, const Eigen::Vector2d& to,
                                 std::uint32_t scan) {
  const double size = config_.cell_size_m;
  std::int64_t x = floor_index(from.x() / size), y = floor_index(from.y() / size);
  const std::int64_t x_end = floor_index(to.x() / size), y_end = floor_index(to.y() / size);
  const Eigen::Vector2d d = to - from;
  const int step_x = d.x() > 0.0 ? 1 : -1, step_y = d.y() > 0.0 ? 1 : -1;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const double delta_x = d.x() != 0.0 ? size / std::abs(d.x()) : kInf;
  const double delta_y = d.y() != 0.0 ? size / std::abs(d.y()) : kInf;
  const double next_x = static_cast<double>(x + (step_x > 0 ? 1 : 0)) * size;
  const double next_y = static_cast<double>(y + (step_y > 0 ? 1 : 0)) * size;
  double t_x = d.x() != 0.0 ? (next_x - from.x()) / d.x() : kInf;
  double t_y = d.y() != 0.0 ? (next_y - from.y()) / d.y() : kInf;
  const std::int64_t steps = std::abs(x_end - x) + std::abs(y_end - y);
  for (std::int64_t k = 0; k <= steps; ++k) {
    Cell* cell = cells_.find((static_cast<std::uint64_t>(static_cast<std::uint32_t>(x)) << 32U) |
                             static_cast<std::uint32_t>(y));
    if (cell != nullptr && cell->open && cell->last_free_scan != scan &&
        cell->last_hit_scan != scan) {
      cell->last_free_scan = scan;
      if (++cell->free_scans >= config_.vacated_min_scans) {
        episodes_.push_back(Episode{cell->start_s, cell->last_hit_s, cell->episodes});
        cell->episodes = static_cast<std::int32_t>(episodes_.size() - 1);
        cell->open = false;
        ++counts_.vacated_episodes;
      }
    }
    if (t_x < t_y) {
      x += step_x;
      t_x += delta_x;
    } else {
      y += step_y;
      t_y += delta_y;
    }
  }
}

Pose2 OfflineCleaner::beam_pose(const ScanRecord& record, std::size_t b) {
  const double t = record.time_increment_s * static_cast<double>(b);
  const Pose2& v = record.motion_per_s;
  return *record.pose * Pose2{v.x_m * t, v.y_m * t, v.yaw_rad * t};
}

void OfflineCleaner::add(const LaserScan& scan, const FilterResult& result) {
  if (finished_) throw std::logic_error("OfflineCleaner::add() after finish()");
  const std::size_t n = scan.size();
  ScanRecord record;
  record.stamp_s = scan.stamp_s;
  record.pose = result.sensor_pose;
  record.labels.assign(n, static_cast<std::uint8_t>(BeamLabel::kInvalid));
  for (std::size_t b = 0; b < n && b < result.labels.size(); ++b) {
    record.labels[b] = static_cast<std::uint8_t>(result.labels[b]);
  }
  const Segmentation& seg = result.segmentation;
  if (!seg.objects.empty() && seg.beam_labels.size() == n) {
    record.object.assign(n, kNone);
    for (std::size_t b = 0; b < n; ++b) {
      const std::int32_t o = seg.beam_labels[b];
      if (o >= 0 && o < kNone) record.object[b] = static_cast<std::uint16_t>(o);
    }
    record.track_of.assign(seg.objects.size(), kNone32);
    record.position_of.assign(seg.objects.size(), Eigen::Vector2f::Zero());
    record.width_of.resize(seg.objects.size());
    for (std::size_t i = 0; i < seg.objects.size(); ++i) {
      const double width = (seg.objects[i].last_point_m - seg.objects[i].first_point_m).norm();
      record.width_of[i] = static_cast<std::uint8_t>(std::min(255.0, std::ceil(width / 0.02)));
    }
    for (const TrackedObject& t : result.tracks) {
      if (t.object_index < 0 || static_cast<std::size_t>(t.object_index) >= seg.objects.size()) {
        continue;
      }
      auto [it, created] =
          track_index_.try_emplace(t.id, static_cast<std::uint32_t>(tracks_.size()));
      if (created) {
        Track track;
        track.object.track_id = t.id;
        track.object.first_seen_s = scan.stamp_s;
        track.first_position = t.position_m;
        tracks_.push_back(track);
      }
      Track& track = tracks_[it->second];
      CleanedObject& o = track.object;
      o.last_seen_s = scan.stamp_s;
      ++o.scans;
      if (t.object_class == ObjectClass::kDynamic) {
        if (o.dynamic_scans == 0) o.first_dynamic_s = scan.stamp_s;
        o.last_dynamic_s = scan.stamp_s;
        ++o.dynamic_scans;
        track.moving_at.emplace_back(scan.stamp_s, t.position_m.cast<float>());
      }
      o.travel_m = std::max(o.travel_m, (t.position_m - track.first_position).norm());
      record.track_of[static_cast<std::size_t>(t.object_index)] = it->second;
      record.position_of[static_cast<std::size_t>(t.object_index)] = t.position_m.cast<float>();
    }
  }
  // The motion since the last scan with a pose, within a second, for the de-skew.
  const double ti = scan.time_increment_s;
  if (record.pose && std::isfinite(ti) && ti > 0.0 && ti * static_cast<double>(n) <= 1.0) {
    for (auto it = scans_.rbegin(); it != scans_.rend(); ++it) {
      if (!it->pose) continue;
      const double dt = scan.stamp_s - it->stamp_s;
      if (dt > 0.0 && dt <= 1.0) {
        const Pose2 moved = it->pose->inverse() * *record.pose;
        record.motion_per_s = {moved.x_m / dt, moved.y_m / dt, moved.yaw_rad / dt};
        record.time_increment_s = ti;
      }
      break;
    }
  }
  const auto scan_no = static_cast<std::uint32_t>(scans_.size() + 1);  // 0: never.
  ++counts_.scans;
  if (record.pose) ++counts_.scans_with_pose;
  for (std::size_t b = 0; b < n; ++b) counts_.valid_beams += scan.is_valid(b) ? 1 : 0;
  if (record.pose && config_.vacated_min_scans > 0) {
    const std::vector<Eigen::Vector2d>& unit = directions_.of(scan);
    // What each beam saw through first, then where beams ended. A beam sees through up to
    // free_margin_m before its end (or up to the range it would have measured when nothing
    // returned); more before the end of a beam that meets its surface at a slant: near its end it
    // runs beside that surface, through cells where the neighbouring beams end (a wall seen at
    // 10 degrees is within a cell's width of the beam for the last 0.8 m).
    const auto point = [&](std::size_t b) {
      return static_cast<double>(scan.ranges_m[b]) * unit[b];
    };
    const double diagonal = config_.cell_size_m * std::sqrt(2.0);
    for (std::size_t b = 0; b < n; ++b) {
      const float r = scan.ranges_m[b];
      const bool valid = scan.is_valid(b);
      const bool nothing = !valid && (std::isinf(r) || r > scan.range_max_m) && !std::isnan(r);
      if (!valid && !nothing) continue;
      double margin = config_.free_margin_m;
      if (valid && b > 0 && b + 1 < n && scan.is_valid(b - 1) && scan.is_valid(b + 1)) {
        const Eigen::Vector2d along = point(b + 1) - point(b - 1);
        const double length = along.norm();
        if (length > 0.0 && length < 1.0) {
          const double slant = std::abs(unit[b].x() * along.y() - unit[b].y() * along.x()) / length;
          margin = std::max(margin, diagonal / std::max(slant, 1e-3));
        }
      }
      const double reach =
          std::min(valid ? static_cast<double>(r) - margin
                         : std::min(static_cast<double>(scan.range_max_m), 1e9) - margin,
                   config_.max_trace_range_m);
      if (reach > 0.0) {
        const Pose2 at = beam_pose(record, b);
        see_through(at.translation(), PoseTransform(at)(reach * unit[b]), scan_no);
      }
    }
    for (std::size_t b = 0; b < n; ++b) {
      if (!scan.is_valid(b)) continue;
      Cell& cell = cells_[key_of(PoseTransform(beam_pose(record, b))(point(b)))];
      if (cell.last_hit_scan == scan_no) continue;
      if (!cell.open) {
        cell.open = true;
        cell.start_s = scan.stamp_s;
      }
      cell.last_hit_s = scan.stamp_s;
      cell.last_hit_scan = scan_no;
      cell.free_scans = 0;
    }
  }
  scans_.push_back(std::move(record));
}

void OfflineCleaner::finish() {
  finished_ = true;
  for (Track& t : tracks_) {
    t.object.moving = t.object.dynamic_scans >= config_.moving_min_scans &&
                      t.object.travel_m >= config_.moving_min_travel_m;
  }
  counts_.cells = static_cast<std::int64_t>(cells_.size());
}

bool OfflineCleaner::near_where_it_moved(const Track& track, double stamp_s,
                                         const Eigen::Vector2f& position) const {
  const auto& at = track.moving_at;
  const auto later = std::lower_bound(
      at.begin(), at.end(), stamp_s,
      [](const std::pair<double, Eigen::Vector2f>& a, double t) { return a.first < t; });
  const auto near = [&](const std::pair<double, Eigen::Vector2f>& a) {
    return static_cast<double>((a.second - position).norm()) <= config_.moved_from_m;
  };
  return (later != at.end() && near(*later)) || (later != at.begin() && near(*(later - 1)));
}

bool OfflineCleaner::vacated_at(const Eigen::Vector2d& p, double stamp_s) const {
  const Cell* cell = cells_.find(key_of(p));
  if (cell == nullptr) return false;
  for (std::int32_t e = cell->episodes; e >= 0; e = episodes_[static_cast<std::size_t>(e)].next) {
    const Episode& episode = episodes_[static_cast<std::size_t>(e)];
    if (episode.start_s <= stamp_s && stamp_s <= episode.end_s) return true;
  }
  return false;
}

void OfflineCleaner::label(std::size_t index, const LaserScan& scan, std::vector<CleanLabel>& out) {
  if (!finished_) finish();
  const ScanRecord& record = scans_.at(index);
  const std::size_t n = record.labels.size();
  if (scan.size() != n) {
    throw std::invalid_argument("scan " + std::to_string(index) + " has " +
                                std::to_string(scan.size()) + " beams, " + std::to_string(n) +
                                " when it was added");
  }
  out.assign(n, CleanLabel::kInvalid);
  const std::vector<Eigen::Vector2d>& unit = directions_.of(scan);
  for (std::size_t b = 0; b < n; ++b) {
    const auto online = static_cast<BeamLabel>(record.labels[b]);
    if (online == BeamLabel::kInvalid) continue;
    std::uint32_t track = kNone32;
    if (!record.object.empty() && record.object[b] != kNone) {
      track = record.track_of[record.object[b]];
    }
    Track* t = track != kNone32 ? &tracks_[track] : nullptr;
    const bool moving = t != nullptr && t->object.moving;
    // Until it last moved (what stopped and stayed to the end is there from then on), and near
    // where it moved.
    const bool moved_later =
        moving && record.stamp_s <= t->object.last_dynamic_s &&
        (online == BeamLabel::kDynamic ||
         record.width_of[record.object[b]] * 0.02 <= config_.moved_max_width_m) &&
        near_where_it_moved(*t, record.stamp_s, record.position_of[record.object[b]]);
    const bool vacated =
        config_.vacated_min_scans > 0 && record.pose && scan.is_valid(b) &&
        vacated_at(
            PoseTransform(beam_pose(record, b))(static_cast<double>(scan.ranges_m[b]) * unit[b]),
            record.stamp_s);
    CleanLabel label;
    if (online == BeamLabel::kDynamic || online == BeamLabel::kUnknown) {
      // Removed online: kept only when its object never moved and its place was never left.
      label = t != nullptr && !moving && !vacated ? CleanLabel::kRestored
                                                  : static_cast<CleanLabel>(online);
    } else if (moved_later) {
      label = CleanLabel::kMovedLater;
    } else if (vacated) {
      label = CleanLabel::kVacated;
    } else {
      label = static_cast<CleanLabel>(online);
    }
    out[b] = label;
    switch (label) {
      case CleanLabel::kDynamic:
      case CleanLabel::kUnknown:
        ++counts_.removed_online;
        break;
      case CleanLabel::kMovedLater:
        ++counts_.moved_later;
        break;
      case CleanLabel::kVacated:
        ++counts_.vacated;
        break;
      case CleanLabel::kRestored:
        ++counts_.restored;
        break;
      default:
        break;
    }
    if (t != nullptr) {
      ++t->object.beams;
      if (removed(label)) ++t->object.beams_removed;
    }
  }
}

std::vector<CleanedObject> OfflineCleaner::objects() const {
  std::vector<CleanedObject> out;
  out.reserve(tracks_.size());
  for (const Track& t : tracks_) out.push_back(t.object);
  return out;
}

}  // namespace dispel
