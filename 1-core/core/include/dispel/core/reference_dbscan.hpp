#pragma once
/// @file
/// Classic DBSCAN (Ester et al., 1996) on the Cartesian points of a scan: the textbook algorithm
/// the single-pass segmentation replaces, kept to cross-check it and to benchmark against.

#include <cstdint>
#include <vector>

#include "dispel/core/laser_scan.hpp"
#include "dispel/core/segmentation.hpp"

namespace dispel {

/// How region queries find the points within eps.
enum class NeighbourSearch {
  kBruteForce,  ///< Compare with every point: O(n) per query, O(n^2) in all (the textbook cost).
  kGrid,        ///< Bucket points in a grid of eps-sized cells: O(points nearby) per query.
};

/// Labels of a DBSCAN run: per beam a cluster index (0, 1, ... in order of discovery), or
/// kLabelNoise, kLabelInvalid or kLabelMasked as in Segmentation.
struct DbscanResult {
  ScanIssue issue = ScanIssue::kNone;
  std::vector<std::int32_t> beam_labels;
  std::int32_t cluster_count = 0;
};

/// Runs DBSCAN on the valid, unmasked beams of @p scan with eps = config.cluster_gap_m and
/// MinPts = config.min_points. A point is core when at least MinPts points (itself included) lie
/// within eps; clusters are the core points connected through eps-neighbourhoods, plus the border
/// points within eps of one of their core points (a border point near two clusters joins the one
/// found first). Points are visited in beam order, so the result is deterministic and the same for
/// both neighbour searches. The config's gap metric and merge settings do not apply.
/// @throws std::invalid_argument if config.validate() does.
DbscanResult reference_dbscan(const LaserScan& scan, const SegmentationConfig& config,
                              NeighbourSearch search = NeighbourSearch::kBruteForce);

}  // namespace dispel
