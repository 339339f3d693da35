#pragma once
// Test support for the segmentation's tests (never installed): scenes ray-cast by the simulator,
// and what must hold of every segmentation.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "dispel/core/pose2.hpp"
#include "dispel/core/segmentation.hpp"
#include "dispel/sim/raycast.hpp"

namespace dispel::segmentation_checks {

using sim::Circle;
using sim::ScanGeometry;
using sim::Segment;
using sim::World;

inline constexpr double kDeg = kPi / 180.0;
inline constexpr float kInf = std::numeric_limits<float>::infinity();
inline constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// The thesis's scanner: 275 deg in 1617 beams, 40 m.
inline ScanGeometry thesis_geometry() {
  return {-137.5 * kDeg, 275.0 * kDeg / 1616.0, 1617, 0.05F, 40.0F};
}

// A 360-degree scanner with 0.5 degree steps, starting at -180 degrees.
inline ScanGeometry full_circle_geometry(double step_deg = 0.5) {
  const auto n = static_cast<std::int32_t>(std::lround(360.0 / step_deg));
  return {-kPi, step_deg * kDeg, n, 0.05F, 30.0F};
}

inline LaserScan cast(const World& world, const ScanGeometry& geometry) {
  return sim::raycast(world, Pose2{}, geometry);
}

inline Segment wall(double ax, double ay, double bx, double by) { return {{ax, ay}, {bx, by}}; }

// Beams of each object, collected from the labels.
inline std::vector<std::vector<std::int32_t>> beams_by_object(const Segmentation& seg) {
  std::vector<std::vector<std::int32_t>> beams(seg.objects.size());
  for (std::size_t i = 0; i < seg.beam_labels.size(); ++i) {
    if (seg.beam_labels[i] >= 0) beams[seg.beam_labels[i]].push_back(static_cast<std::int32_t>(i));
  }
  return beams;
}

// The object whose centroid is nearest to p.
inline const ScanObject* object_near(const Segmentation& seg, const Eigen::Vector2d& p,
                                     double tol) {
  const ScanObject* best = nullptr;
  for (const ScanObject& o : seg.objects) {
    if ((o.centroid_m - p).norm() <= tol &&
        (best == nullptr || (o.centroid_m - p).norm() < (best->centroid_m - p).norm())) {
      best = &o;
    }
  }
  return best;
}

inline Eigen::Vector2d point_of(const LaserScan& scan, std::int32_t i) {
  const double r = scan.ranges_m[i];
  return {r * std::cos(scan.bearing_rad(i)), r * std::sin(scan.bearing_rad(i))};
}

// What must hold of every segmentation: labels and objects agree, objects respect N_min, the
// beams of an object are joined by gaps of at most eps or cluster_gap_spacings beam spacings at
// their range (in bearing order, wrapping on full
// circles) except where clusters were merged, and edge points are the points of the edge beams.
inline void expect_consistent(const LaserScan& scan, const Segmentation& seg,
                              const SegmentationConfig& config) {
  ASSERT_EQ(seg.issue, ScanIssue::kNone);
  ASSERT_EQ(seg.beam_labels.size(), scan.size());
  const auto beams = beams_by_object(seg);
  std::int32_t invalid = 0;
  std::int32_t noise = 0;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const std::int32_t label = seg.beam_labels[i];
    if (label == kLabelInvalid) {
      ++invalid;
      EXPECT_FALSE(scan.is_valid(i)) << "beam " << i;
    } else if (label != kLabelMasked) {
      EXPECT_TRUE(scan.is_valid(i)) << "beam " << i;
      noise += label == kLabelNoise ? 1 : 0;
    }
    EXPECT_GE(label, kLabelMasked);
    EXPECT_LT(label, static_cast<std::int32_t>(seg.objects.size()));
  }
  EXPECT_EQ(invalid, seg.invalid_beams);
  EXPECT_EQ(noise, seg.noise_beams);
  for (std::size_t k = 0; k < seg.objects.size(); ++k) {
    const ScanObject& o = seg.objects[k];
    ASSERT_FALSE(beams[k].empty());
    EXPECT_EQ(static_cast<std::int32_t>(beams[k].size()), o.point_count);
    // min_width_m lowers N_min with range, never below 2 (a single beam is noise).
    EXPECT_GE(o.point_count,
              config.min_width_m > 0.0 ? std::min(2, config.min_points) : config.min_points);
    EXPECT_EQ(seg.beam_labels[o.first_beam], static_cast<std::int32_t>(k));
    EXPECT_EQ(seg.beam_labels[o.last_beam], static_cast<std::int32_t>(k));
    EXPECT_LT((o.first_point_m - point_of(scan, o.first_beam)).norm(), 1e-4);
    EXPECT_LT((o.last_point_m - point_of(scan, o.last_beam)).norm(), 1e-4);
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    for (std::int32_t b : beams[k]) sum += point_of(scan, b);
    EXPECT_LT((o.centroid_m - sum / o.point_count).norm(), 1e-4);
    if (k > 0) {
      EXPECT_LT(seg.objects[k - 1].first_beam, o.first_beam);
    }
    // Gaps between consecutive beams of the object, in bearing order from its first beam.
    std::vector<std::int32_t> ordered = beams[k];
    if (o.straddles_seam()) {
      std::rotate(ordered.begin(), std::find(ordered.begin(), ordered.end(), o.first_beam),
                  ordered.end());
    }
    EXPECT_EQ(ordered.front(), o.first_beam);
    EXPECT_EQ(ordered.back(), o.last_beam);
    std::int32_t wide_gaps = 0;
    for (std::size_t j = 1; j < ordered.size(); ++j) {
      const double gap = (point_of(scan, ordered[j]) - point_of(scan, ordered[j - 1])).norm();
      // Within eps, or within cluster_gap_spacings beam spacings at the nearer point's range.
      const double nearer = std::min(scan.ranges_m[static_cast<std::size_t>(ordered[j])],
                                     scan.ranges_m[static_cast<std::size_t>(ordered[j - 1])]);
      const double allowed =
          std::max(config.cluster_gap_m,
                   config.cluster_gap_spacings * std::fabs(scan.angle_increment_rad) * nearer);
      if (config.gap_metric == GapMetric::kEuclidean && gap > allowed + 1e-5) {
        ++wide_gaps;
      }
    }
    if (config.gap_metric == GapMetric::kEuclidean) {
      EXPECT_LE(wide_gaps, o.cluster_count - 1) << "object " << k;
    }
  }
}

}  // namespace dispel::segmentation_checks
