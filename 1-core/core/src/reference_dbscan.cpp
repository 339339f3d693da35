#include "dispel/core/reference_dbscan.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

namespace dispel {
namespace {

constexpr std::int32_t kUnvisited = -100;

struct Point {
  double x, y;
};

// Region queries by brute force: every point is compared.
class BruteForce {
 public:
  BruteForce(const std::vector<Point>& points, double eps) : points_(points), eps_sq_(eps * eps) {}

  void query(std::size_t p, std::vector<std::int32_t>& out) const {
    out.clear();
    const Point& a = points_[p];
    for (std::size_t q = 0; q < points_.size(); ++q) {
      const double dx = points_[q].x - a.x;
      const double dy = points_[q].y - a.y;
      if (dx * dx + dy * dy <= eps_sq_) out.push_back(static_cast<std::int32_t>(q));
    }
  }

 private:
  const std::vector<Point>& points_;
  double eps_sq_;
};

// Region queries through a grid of eps-sized cells: only the 3 x 3 cells around a point are
// searched. Cells are found by binary search in the points sorted by cell key.
class Grid {
 public:
  Grid(const std::vector<Point>& points, double eps)
      : points_(points), eps_(eps), eps_sq_(eps * eps) {
    sorted_.reserve(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
      sorted_.push_back({key(points[i]), static_cast<std::int32_t>(i)});
    }
    std::sort(sorted_.begin(), sorted_.end());
  }

  void query(std::size_t p, std::vector<std::int32_t>& out) const {
    out.clear();
    const Point& a = points_[p];
    const auto [cx, cy] = cell(a);
    for (std::int64_t dx = -1; dx <= 1; ++dx) {
      for (std::int64_t dy = -1; dy <= 1; ++dy) {
        const std::int64_t k = pack(cx + dx, cy + dy);
        auto it = std::lower_bound(sorted_.begin(), sorted_.end(),
                                   std::pair<std::int64_t, std::int32_t>{k, -1});
        for (; it != sorted_.end() && it->first == k; ++it) {
          const Point& b = points_[it->second];
          const double ex = b.x - a.x;
          const double ey = b.y - a.y;
          if (ex * ex + ey * ey <= eps_sq_) out.push_back(it->second);
        }
      }
    }
  }

 private:
  std::pair<std::int64_t, std::int64_t> cell(const Point& p) const {
    return {static_cast<std::int64_t>(std::floor(p.x / eps_)),
            static_cast<std::int64_t>(std::floor(p.y / eps_))};
  }
  static std::int64_t pack(std::int64_t cx, std::int64_t cy) {
    // Cells of a scan span far less than 2^31 in each direction.
    const auto high = static_cast<std::uint64_t>(static_cast<std::uint32_t>(cx)) << 32;
    return static_cast<std::int64_t>(high | static_cast<std::uint32_t>(cy));
  }
  std::int64_t key(const Point& p) const {
    const auto [cx, cy] = cell(p);
    return pack(cx, cy);
  }

  const std::vector<Point>& points_;
  double eps_;
  double eps_sq_;
  std::vector<std::pair<std::int64_t, std::int32_t>> sorted_;
};

template <typename Index>
std::int32_t run_dbscan(const Index& index, std::size_t count, int min_points,
                        std::vector<std::int32_t>& label) {
  label.assign(count, kUnvisited);
  std::vector<std::int32_t> neighbours;
  std::vector<std::int32_t> seeds;
  std::int32_t clusters = 0;
  const auto min_pts = static_cast<std::size_t>(min_points);
  for (std::size_t p = 0; p < count; ++p) {
    if (label[p] != kUnvisited) continue;
    index.query(p, neighbours);
    if (neighbours.size() < min_pts) {
      label[p] = kLabelNoise;  // May later become a border point of a cluster.
      continue;
    }
    // Expand the new cluster from p. Each point is queued once: on its first labelling.
    // Points first seen as noise become border points and are not expanded (they are not core).
    const std::int32_t id = clusters++;
    label[p] = id;
    seeds.clear();
    for (std::size_t s = 0;; ++s) {
      for (const std::int32_t q : neighbours) {
        if (label[q] == kLabelNoise) {
          label[q] = id;
        } else if (label[q] == kUnvisited) {
          label[q] = id;
          seeds.push_back(q);
        }
      }
      if (s == seeds.size()) break;
      index.query(static_cast<std::size_t>(seeds[s]), neighbours);
      if (neighbours.size() < min_pts) neighbours.clear();  // Border: reaches no further.
    }
  }
  return clusters;
}

}  // namespace

DbscanResult reference_dbscan(const LaserScan& scan, const SegmentationConfig& config,
                              NeighbourSearch search) {
  config.validate();
  DbscanResult result;
  result.issue = check_scan(scan);
  if (result.issue != ScanIssue::kNone) return result;

  const std::size_t n = scan.size();
  result.beam_labels.assign(n, kLabelInvalid);
  std::vector<Point> points;
  std::vector<std::int32_t> beam_of_point;
  for (std::size_t i = 0; i < n; ++i) {
    const double bearing = scan.bearing_rad(i);
    const bool masked =
        std::any_of(config.masked_sectors.begin(), config.masked_sectors.end(),
                    [&](const AngleSector& s) { return sector_contains(s, bearing); });
    if (masked) {
      result.beam_labels[i] = kLabelMasked;
    } else if (scan.is_valid(i)) {
      const double r = scan.ranges_m[i];
      points.push_back({r * std::cos(bearing), r * std::sin(bearing)});
      beam_of_point.push_back(static_cast<std::int32_t>(i));
    }
  }

  std::vector<std::int32_t> labels;
  if (search == NeighbourSearch::kGrid) {
    result.cluster_count =
        run_dbscan(Grid(points, config.cluster_gap_m), points.size(), config.min_points, labels);
  } else {
    result.cluster_count = run_dbscan(BruteForce(points, config.cluster_gap_m), points.size(),
                                      config.min_points, labels);
  }
  for (std::size_t p = 0; p < points.size(); ++p) result.beam_labels[beam_of_point[p]] = labels[p];
  return result;
}

}  // namespace dispel
