// Segmentation on 360-degree scanners, with either gap metric, the edges' neighbours, and on the
// recorded leg_tracker scans.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "dispel/core/segmentation.hpp"
#include "scan_csv.hpp"
#include "segmentation_checks.hpp"

namespace dispel {
namespace {

using namespace segmentation_checks;  // NOLINT: the checks' vocabulary.

// --- 360-degree scanners ----------------------------------------------------------------------

TEST(Segmentation, ObjectAcrossTheSeamOfAFullCircleIsOneObject) {
  // The seam of this scanner is at +-180 degrees; a pillar sits right on it.
  World world;
  world.circles = {{{-2.0, 0.0}, 0.3}};
  const LaserScan scan = cast(world, full_circle_geometry());
  ASSERT_TRUE(scan.is_valid(0));
  ASSERT_TRUE(scan.is_valid(scan.size() - 1));
  SegmentationConfig config;
  config.min_points = 4;
  Segmenter segmenter{config};
  const Segmentation seg = segmenter.segment(scan);
  expect_consistent(scan, seg, config);
  EXPECT_TRUE(seg.full_circle);
  ASSERT_EQ(seg.objects.size(), 1u);
  EXPECT_TRUE(seg.objects[0].straddles_seam());
  EXPECT_NEAR(seg.objects[0].centroid_m.x(), -1.75, 0.05);
  EXPECT_NEAR(seg.objects[0].centroid_m.y(), 0.0, 1e-3);

  config.join_full_circle_seam = false;
  Segmenter open{config};
  const Segmentation cut = open.segment(scan);
  EXPECT_FALSE(cut.full_circle);
  EXPECT_EQ(cut.objects.size(), 2u);
}

TEST(Segmentation, LegsEitherSideOfTheSeamAreMerged) {
  // Two legs straddle the seam with the wall visible between them, exactly at +-180 degrees.
  World world;
  world.segments = {wall(-4.0, -3.0, -4.0, 3.0)};
  world.circles = {{{-1.5, 0.1}, 0.06}, {{-1.5, -0.1}, 0.06}};
  const LaserScan scan = cast(world, full_circle_geometry(0.2));
  SegmentationConfig config;
  Segmenter segmenter{config};
  const Segmentation seg = segmenter.segment(scan);
  expect_consistent(scan, seg, config);
  const ScanObject* person = object_near(seg, {-1.45, 0.0}, 0.1);
  ASSERT_NE(person, nullptr);
  EXPECT_EQ(person->cluster_count, 2);
  EXPECT_TRUE(person->straddles_seam());
}

// Rotating a full-circle scan by k beams must rotate its segmentation: the seam is not special.
TEST(Segmentation, FullCircleResultDoesNotDependOnWhereTheSeamIs) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    World world;
    world.segments = {wall(-6, -5, 6, -5), wall(6, -5, 6, 5), wall(6, 5, -6, 5),
                      wall(-6, 5, -6, -5)};
    for (int p = 0; p < 6; ++p) {  // Pairs of legs and pillars around the sensor.
      const Eigen::Vector2d c(3.5 * u(rng), 3.5 * u(rng));
      if (c.norm() < 0.8) continue;
      const Eigen::Vector2d side =
          Eigen::Vector2d(-c.y(), c.x()).normalized() * (0.08 + 0.04 * u(rng));
      world.circles.push_back({c + side, 0.06});
      world.circles.push_back({c - side, 0.06});
    }
    const LaserScan scan = cast(world, full_circle_geometry(0.25));
    const SegmentationConfig config;
    Segmenter segmenter{config};
    const Segmentation ref = segmenter.segment(scan);
    expect_consistent(scan, ref, config);
    const auto ref_beams = beams_by_object(ref);
    std::set<std::set<std::int32_t>> ref_sets;
    for (const auto& b : ref_beams) ref_sets.emplace(b.begin(), b.end());

    const auto n = static_cast<std::int32_t>(scan.size());
    for (std::int32_t shift : {1, 37, 360, 719, 1000}) {
      LaserScan rotated = scan;
      // rotated beam j = original beam (j + shift) % n, so angle_min moves by shift steps.
      std::rotate(rotated.ranges_m.begin(), rotated.ranges_m.begin() + shift,
                  rotated.ranges_m.end());
      rotated.angle_min_rad += shift * scan.angle_increment_rad;
      const Segmentation seg = segmenter.segment(rotated);
      expect_consistent(rotated, seg, config);
      std::set<std::set<std::int32_t>> sets;
      for (const auto& b : beams_by_object(seg)) {
        std::set<std::int32_t> original;
        for (std::int32_t j : b) original.insert((j + shift) % n);
        sets.insert(original);
      }
      EXPECT_EQ(sets, ref_sets) << "trial " << trial << " shift " << shift;
      EXPECT_EQ(seg.merges, ref.merges) << "trial " << trial << " shift " << shift;
    }
  }
}

TEST(Segmentation, FullCircleWithOneSurroundingWallIsOneRing) {
  World world;
  world.circles = {{{0.0, 0.0}, 2.0}};  // Sensor inside a round tank.
  const LaserScan scan = cast(world, full_circle_geometry());
  Segmenter segmenter{SegmentationConfig{}};
  const Segmentation seg = segmenter.segment(scan);
  ASSERT_EQ(seg.objects.size(), 1u);
  EXPECT_EQ(seg.objects[0].point_count, static_cast<std::int32_t>(scan.size()));
}

// --- Gap metric -------------------------------------------------------------------------------

TEST(Segmentation, RangeDifferenceOverJoinsAnObliqueWallAtRange) {
  // A wall 25 m away seen at 45 degrees incidence: neighbouring points are 10.5 cm apart but their
  // ranges differ by only 7.4 cm. The exact metric with eps alone sees a row of separate points
  // (eps is 10 cm); the thesis's |r1 - r2| sees one wall, and so does the exact metric with
  // dispel's default cluster_gap_spacings (3 beam spacings: 22 cm at 25 m).
  World world;
  const Eigen::Vector2d hit(25.0, 0.0);
  const Eigen::Vector2d along = Eigen::Vector2d(1.0, 1.0).normalized();
  world.segments = {{hit - 1.5 * along, hit + 1.5 * along}};
  const LaserScan scan = cast(world, thesis_geometry());
  std::int32_t centre = -1;
  for (std::int32_t i = 0; i + 1 < static_cast<std::int32_t>(scan.size()); ++i) {
    if (scan.is_valid(i) && scan.is_valid(i + 1) && std::abs(scan.bearing_rad(i)) < 0.003) {
      centre = i;
    }
  }
  ASSERT_GE(centre, 0);
  const double gap = (point_of(scan, centre + 1) - point_of(scan, centre)).norm();
  const double range_step = std::abs(scan.ranges_m[centre + 1] - scan.ranges_m[centre]);
  ASSERT_GT(gap, 0.1);
  ASSERT_LT(range_step, 0.1);

  SegmentationConfig config;
  const Segmentation within_spacings = Segmenter{config}.segment(scan);
  expect_consistent(scan, within_spacings, config);
  ASSERT_EQ(within_spacings.objects.size(), 1u);
  EXPECT_GT(within_spacings.objects[0].point_count, 20);
  config.cluster_gap_spacings = 0.0;
  Segmenter exact{config};
  const Segmentation e = exact.segment(scan);
  EXPECT_TRUE(e.objects.empty());
  config.gap_metric = GapMetric::kRangeDifference;
  Segmenter approx{config};
  const Segmentation a = approx.segment(scan);
  expect_consistent(scan, a, config);
  ASSERT_EQ(a.objects.size(), 1u);
  EXPECT_GT(a.objects[0].point_count, 20);
}

TEST(Segmentation, RangeDifferenceJoinsSeparateObjectsAcrossInvalidBeams) {
  // Two boxes side by side at 5 m with 1 m of open space (no return) between them.
  World world;
  world.segments = {wall(5.0, -1.5, 5.0, -0.5), wall(5.0, 0.5, 5.0, 1.5)};
  const LaserScan scan = cast(world, thesis_geometry());
  SegmentationConfig config;
  Segmenter exact{config};
  EXPECT_EQ(exact.segment(scan).objects.size(), 2u);
  config.gap_metric = GapMetric::kRangeDifference;
  Segmenter approx{config};
  EXPECT_EQ(approx.segment(scan).objects.size(), 1u);
}

TEST(Segmentation, BothMetricsAgreeOnNearbyDenseScenes) {
  World world;
  world.segments = {wall(4.0, -3.0, 4.0, 3.0), wall(-1.0, 3.0, 4.0, 3.0)};
  world.circles = {{{2.0, 0.8}, 0.2}, {{1.5, -1.0}, 0.1}};
  const LaserScan scan = cast(world, thesis_geometry());
  SegmentationConfig config;
  Segmenter exact{config};
  config.gap_metric = GapMetric::kRangeDifference;
  Segmenter approx{config};
  EXPECT_EQ(exact.segment(scan).beam_labels, approx.segment(scan).beam_labels);
}

// --- Edges ------------------------------------------------------------------------------------

TEST(Segmentation, EdgeNeighboursTellWhatLiesBeyondEachEdge) {
  // A walker in front of a wall (thesis Figure 3.6): the wall's edges next to the walker may be
  // occluded; the walker's edges are its outline. The wall's far ends reach the field of view.
  World world;
  world.segments = {wall(3.0, -30.0, 3.0, -2.0), wall(3.0, -1.0, 3.0, 30.0)};  // A doorway.
  world.circles = {{{1.5, 0.0}, 0.2}};
  ScanGeometry g = thesis_geometry();
  g.angle_min_rad = -60.0 * kDeg;
  g.beam_count = 707;  // -60 .. +60 degrees.
  const LaserScan scan = cast(world, g);
  Segmenter segmenter{SegmentationConfig{}};
  const Segmentation seg = segmenter.segment(scan);
  ASSERT_EQ(seg.objects.size(), 4u);
  EXPECT_EQ(seg.objects[0].before_first, EdgeNeighbour::kFieldOfViewEnd);
  EXPECT_EQ(seg.objects[0].after_last, EdgeNeighbour::kInvalid);
  EXPECT_EQ(seg.objects[1].before_first, EdgeNeighbour::kInvalid);
  EXPECT_EQ(seg.objects[1].after_last, EdgeNeighbour::kCloser);
  EXPECT_EQ(seg.objects[2].before_first, EdgeNeighbour::kFarther);  // The walker.
  EXPECT_EQ(seg.objects[2].after_last, EdgeNeighbour::kFarther);
  EXPECT_EQ(seg.objects[3].before_first, EdgeNeighbour::kCloser);
  EXPECT_EQ(seg.objects[3].after_last, EdgeNeighbour::kFieldOfViewEnd);
}

// --- Reuse and real data ----------------------------------------------------------------------

TEST(Segmenter, ReusedAcrossGeometriesGivesTheSameAsAFreshSegmenter) {
  World world;
  world.segments = {wall(4.0, -3.0, 4.0, 3.0)};
  world.circles = {{{2.0, 0.5}, 0.15}, {{-1.0, -1.0}, 0.3}};
  Segmenter reused{SegmentationConfig{}};
  for (const ScanGeometry& g :
       {thesis_geometry(), full_circle_geometry(), thesis_geometry(), full_circle_geometry(1.0)}) {
    const LaserScan scan = cast(world, g);
    Segmenter fresh{SegmentationConfig{}};
    EXPECT_EQ(reused.segment(scan).beam_labels, fresh.segment(scan).beam_labels);
  }
}

TEST(SegmentationOnRecordedScans, LegTrackerScansAreSegmentedConsistently) {
  // 127 real scans of a Hokuyo-class scanner (512 beams, 5.6 m) in a room with walking people.
  const auto scans = testing::read_scan_csv(testing::data_path("leg_tracker/scans_every10.csv"));
  ASSERT_EQ(scans.size(), 127u);
  const SegmentationConfig config;
  Segmenter segmenter{config};
  std::int32_t objects = 0;
  std::int32_t merged = 0;
  for (const LaserScan& scan : scans) {
    const Segmentation seg = segmenter.segment(scan);
    expect_consistent(scan, seg, config);
    objects += static_cast<std::int32_t>(seg.objects.size());
    merged += seg.merges;
  }
  // Every scan sees the room's walls and furniture; people add more.
  EXPECT_GE(objects, 2 * static_cast<std::int32_t>(scans.size()));
  EXPECT_GT(merged, 0);  // Legs, or surfaces cut by a leg's shadow, are merged somewhere.
}

}  // namespace
}  // namespace dispel
