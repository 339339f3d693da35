#include "dispel/core/segmentation.hpp"

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

#include "dispel/core/pose2.hpp"
#include "dispel/sim/raycast.hpp"
#include "scan_csv.hpp"

namespace dispel {
namespace {

using sim::Circle;
using sim::ScanGeometry;
using sim::Segment;
using sim::World;

constexpr double kDeg = kPi / 180.0;
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// The thesis's scanner: 275 deg in 1617 beams, 40 m.
ScanGeometry thesis_geometry() {
  return {-137.5 * kDeg, 275.0 * kDeg / 1616.0, 1617, 0.05F, 40.0F};
}

// A 360-degree scanner with 0.5 degree steps, starting at -180 degrees.
ScanGeometry full_circle_geometry(double step_deg = 0.5) {
  const auto n = static_cast<std::int32_t>(std::lround(360.0 / step_deg));
  return {-kPi, step_deg * kDeg, n, 0.05F, 30.0F};
}

LaserScan cast(const World& world, const ScanGeometry& geometry) {
  return sim::raycast(world, Pose2{}, geometry);
}

Segment wall(double ax, double ay, double bx, double by) { return {{ax, ay}, {bx, by}}; }

// Beams of each object, collected from the labels.
std::vector<std::vector<std::int32_t>> beams_by_object(const Segmentation& seg) {
  std::vector<std::vector<std::int32_t>> beams(seg.objects.size());
  for (std::size_t i = 0; i < seg.beam_labels.size(); ++i) {
    if (seg.beam_labels[i] >= 0) beams[seg.beam_labels[i]].push_back(static_cast<std::int32_t>(i));
  }
  return beams;
}

// The object whose centroid is nearest to p.
const ScanObject* object_near(const Segmentation& seg, const Eigen::Vector2d& p, double tol) {
  const ScanObject* best = nullptr;
  for (const ScanObject& o : seg.objects) {
    if ((o.centroid_m - p).norm() <= tol &&
        (best == nullptr || (o.centroid_m - p).norm() < (best->centroid_m - p).norm())) {
      best = &o;
    }
  }
  return best;
}

Eigen::Vector2d point_of(const LaserScan& scan, std::int32_t i) {
  const double r = scan.ranges_m[i];
  return {r * std::cos(scan.bearing_rad(i)), r * std::sin(scan.bearing_rad(i))};
}

// What must hold of every segmentation: labels and objects agree, objects respect N_min, the
// beams of an object are joined by gaps of at most eps (in bearing order, wrapping on full
// circles) except where clusters were merged, and edge points are the points of the edge beams.
void expect_consistent(const LaserScan& scan, const Segmentation& seg,
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
    EXPECT_GE(o.point_count, config.min_points);
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
      if (config.gap_metric == GapMetric::kEuclidean && gap > config.cluster_gap_m + 1e-5) {
        ++wide_gaps;
      }
    }
    if (config.gap_metric == GapMetric::kEuclidean) {
      EXPECT_LE(wide_gaps, o.cluster_count - 1) << "object " << k;
    }
  }
}

// --- Configuration and input checks -----------------------------------------------------------

TEST(SegmentationConfig, DefaultsAreTheThesisParameters) {
  const SegmentationConfig config;
  EXPECT_DOUBLE_EQ(config.cluster_gap_m, 0.1);
  EXPECT_EQ(config.min_points, 8);
  EXPECT_EQ(config.gap_metric, GapMetric::kEuclidean);
  EXPECT_NO_THROW(config.validate());
}

void expect_rejected(const SegmentationConfig& config, const std::string& field) {
  try {
    config.validate();
    ADD_FAILURE() << "accepted a bad " << field;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
  }
  EXPECT_THROW(Segmenter{config}, std::invalid_argument);
}

TEST(SegmentationConfig, BadValuesAreRejectedByName) {
  SegmentationConfig c;
  c.cluster_gap_m = 0.0;
  expect_rejected(c, "cluster_gap_m");
  c.cluster_gap_m = -0.1;
  expect_rejected(c, "cluster_gap_m");
  c.cluster_gap_m = std::numeric_limits<double>::quiet_NaN();
  expect_rejected(c, "cluster_gap_m");
  c.cluster_gap_m = std::numeric_limits<double>::infinity();
  expect_rejected(c, "cluster_gap_m");
  c = SegmentationConfig{};
  c.min_points = 0;
  expect_rejected(c, "min_points");
  c = SegmentationConfig{};
  c.masked_sectors = {{0.5, 0.2}};
  expect_rejected(c, "masked_sectors[0]");
  c.masked_sectors = {{0.0, 0.1}, {0.0, 7.0}};
  expect_rejected(c, "masked_sectors[1]");
  c.masked_sectors = {{std::numeric_limits<double>::quiet_NaN(), 0.1}};
  expect_rejected(c, "masked_sectors[0]");
}

LaserScan small_scan() {
  LaserScan scan;
  scan.angle_min_rad = -0.5;
  scan.angle_increment_rad = 0.01;
  scan.range_min_m = 0.1F;
  scan.range_max_m = 10.0F;
  scan.ranges_m.assign(40, 2.0F);
  return scan;
}

void expect_scan_rejected(const LaserScan& scan, ScanIssue issue, const std::string& field) {
  Segmenter segmenter{SegmentationConfig{}};
  const Segmentation seg = segmenter.segment(scan);
  EXPECT_EQ(seg.issue, issue);
  EXPECT_TRUE(seg.beam_labels.empty());
  EXPECT_TRUE(seg.objects.empty());
  const std::string message = describe_scan_issue(scan, issue);
  EXPECT_NE(message.find(field), std::string::npos) << message;
}

TEST(SegmenterInput, EmptyScanIsRejected) {
  LaserScan scan = small_scan();
  scan.ranges_m.clear();
  expect_scan_rejected(scan, ScanIssue::kEmpty, "ranges");
}

TEST(SegmenterInput, ZeroOrNegativeIncrementIsRejected) {
  LaserScan scan = small_scan();
  scan.angle_increment_rad = 0.0;
  expect_scan_rejected(scan, ScanIssue::kNonPositiveIncrement, "angle_increment_rad");
  scan.angle_increment_rad = -0.01;
  expect_scan_rejected(scan, ScanIssue::kNonPositiveIncrement, "angle_increment_rad");
}

TEST(SegmenterInput, NonFiniteAnglesAndStampAreRejected) {
  LaserScan scan = small_scan();
  scan.angle_min_rad = std::numeric_limits<double>::quiet_NaN();
  expect_scan_rejected(scan, ScanIssue::kNonFiniteAngles, "angle_min_rad");
  scan = small_scan();
  scan.angle_increment_rad = std::numeric_limits<double>::infinity();
  expect_scan_rejected(scan, ScanIssue::kNonFiniteAngles, "angle_increment_rad");
  scan = small_scan();
  scan.stamp_s = std::numeric_limits<double>::quiet_NaN();
  expect_scan_rejected(scan, ScanIssue::kNonFiniteStamp, "stamp_s");
}

TEST(SegmenterInput, MismatchedIntensitiesAreRejected) {
  LaserScan scan = small_scan();
  scan.intensities.assign(scan.size() - 1, 1.0F);
  expect_scan_rejected(scan, ScanIssue::kIntensityCountMismatch, "intensities");
  scan.intensities.assign(scan.size(), 1.0F);
  EXPECT_EQ(check_scan(scan), ScanIssue::kNone);
}

TEST(SegmenterInput, BadRangeLimitsAreRejected) {
  LaserScan scan = small_scan();
  scan.range_max_m = scan.range_min_m;
  expect_scan_rejected(scan, ScanIssue::kBadRangeLimits, "range_max_m");
  scan = small_scan();
  scan.range_min_m = -1.0F;
  expect_scan_rejected(scan, ScanIssue::kBadRangeLimits, "range_min_m");
  scan = small_scan();
  scan.range_max_m = kNaN;
  expect_scan_rejected(scan, ScanIssue::kBadRangeLimits, "range_max_m");
}

TEST(SegmenterInput, AllInvalidRangesGiveNoObjectsAndCountEveryBeam) {
  LaserScan scan = small_scan();
  for (std::size_t i = 0; i < scan.size(); ++i) {
    scan.ranges_m[i] = (i % 3 == 0) ? kNaN : (i % 3 == 1 ? kInf : -kInf);
  }
  Segmenter segmenter{SegmentationConfig{}};
  const Segmentation seg = segmenter.segment(scan);
  EXPECT_EQ(seg.issue, ScanIssue::kNone);
  EXPECT_TRUE(seg.objects.empty());
  EXPECT_EQ(seg.invalid_beams, static_cast<std::int32_t>(scan.size()));
  EXPECT_EQ(seg.valid_beams, 0);
}

// --- The pass ---------------------------------------------------------------------------------

TEST(Segmentation, WallAndPillarAreSeparateObjects) {
  World world;
  world.segments = {wall(4.0, -3.0, 4.0, 3.0)};
  world.circles = {{{2.0, 0.5}, 0.15}};
  const LaserScan scan = cast(world, thesis_geometry());
  const SegmentationConfig config;
  Segmenter segmenter{config};
  const Segmentation seg = segmenter.segment(scan);
  expect_consistent(scan, seg, config);
  // The pillar splits the wall into the part left and right of its shadow.
  ASSERT_EQ(seg.objects.size(), 3u);
  EXPECT_NE(object_near(seg, {2.0 - 0.1, 0.5}, 0.1), nullptr);
  EXPECT_EQ(seg.noise_beams, 0);
  EXPECT_EQ(seg.merges, 0);
}

TEST(Segmentation, TwoLegsWithWallBetweenAreMergedIntoOnePerson) {
  // Two legs (radius 6 cm) 8 cm apart at 1.5 m, the wall at 3 m visible between them.
  World world;
  world.segments = {wall(3.0, -3.0, 3.0, 3.0)};
  world.circles = {{{1.5, 0.1}, 0.06}, {{1.5, -0.1}, 0.06}};
  const LaserScan scan = cast(world, thesis_geometry());
  SegmentationConfig config;
  Segmenter segmenter{config};
  const Segmentation seg = segmenter.segment(scan);
  expect_consistent(scan, seg, config);
  const ScanObject* person = object_near(seg, {1.45, 0.0}, 0.1);
  ASSERT_NE(person, nullptr);
  EXPECT_EQ(person->cluster_count, 2);
  EXPECT_EQ(seg.merges, 1);
  // The wall between the legs is not part of the person.
  const auto beams = beams_by_object(seg);
  const auto person_id = static_cast<std::int32_t>(person - seg.objects.data());
  std::int32_t between = 0;
  for (std::int32_t i = person->first_beam; i <= person->last_beam; ++i) {
    if (seg.beam_labels[i] != person_id) {
      ++between;
      EXPECT_GT(scan.ranges_m[i], 2.9F);
    }
  }
  EXPECT_GT(between, 0);

  // Without merging, the same scene has two leg objects.
  config.merge_facing_edges = false;
  Segmenter unmerged{config};
  const Segmentation legs = unmerged.segment(scan);
  expect_consistent(scan, legs, config);
  EXPECT_NE(object_near(legs, {1.45, 0.1}, 0.05), nullptr);
  EXPECT_NE(object_near(legs, {1.45, -0.1}, 0.05), nullptr);
  EXPECT_EQ(legs.objects.size(), seg.objects.size() + 1);
}

TEST(Segmentation, LegsFartherApartThanEpsStaySeparate) {
  World world;
  world.segments = {wall(3.0, -3.0, 3.0, 3.0)};
  world.circles = {{{1.5, 0.15}, 0.06}, {{1.5, -0.15}, 0.06}};  // 18 cm between them.
  const LaserScan scan = cast(world, thesis_geometry());
  Segmenter segmenter{SegmentationConfig{}};
  const Segmentation seg = segmenter.segment(scan);
  EXPECT_EQ(seg.merges, 0);
  EXPECT_NE(object_near(seg, {1.45, 0.15}, 0.05), nullptr);
  EXPECT_NE(object_near(seg, {1.45, -0.15}, 0.05), nullptr);
}

TEST(Segmentation, ClustersBelowMinPointsAreNoise) {
  // A 1 cm cable hanging at 2 m shows up in about 6 beams.
  World world;
  world.segments = {wall(4.0, -3.0, 4.0, 3.0)};
  world.circles = {{{2.0, 0.0}, 0.01}};
  const LaserScan scan = cast(world, thesis_geometry());
  std::int32_t cable_beams = 0;
  for (float r : scan.ranges_m) cable_beams += r < 2.5F ? 1 : 0;
  ASSERT_GT(cable_beams, 0);
  ASSERT_LT(cable_beams, 8);

  SegmentationConfig config;
  Segmenter segmenter{config};
  const Segmentation seg = segmenter.segment(scan);
  expect_consistent(scan, seg, config);
  EXPECT_EQ(seg.noise_beams, cable_beams);
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (scan.ranges_m[i] < 2.5F) {
      EXPECT_EQ(seg.beam_labels[i], kLabelNoise);
    }
  }
  EXPECT_EQ(object_near(seg, {2.0, 0.0}, 0.1), nullptr);

  config.min_points = 1;
  Segmenter keep_all{config};
  const Segmentation all = keep_all.segment(scan);
  EXPECT_EQ(all.noise_beams, 0);
  EXPECT_NE(object_near(all, {1.99, 0.0}, 0.05), nullptr);
}

TEST(Segmentation, InvalidBeamsAreNeverObjectsAndDoNotCutASurface) {
  World world;
  world.segments = {wall(3.0, -3.0, 3.0, 3.0)};
  LaserScan scan = cast(world, thesis_geometry());
  SegmentationConfig config;
  Segmenter segmenter{config};
  const Segmentation clean = segmenter.segment(scan);
  ASSERT_EQ(clean.objects.size(), 1u);
  const std::int32_t wall_points = clean.objects[0].point_count;

  // Dropouts on the wall: NaN, +inf, a return below range_min and one beyond range_max.
  const std::int32_t mid = 808;
  scan.ranges_m[mid - 2] = kNaN;
  scan.ranges_m[mid - 1] = kInf;
  scan.ranges_m[mid] = 0.01F;
  scan.ranges_m[mid + 1] = 41.0F;
  scan.ranges_m[mid + 2] = -kInf;
  const Segmentation seg = segmenter.segment(scan);
  expect_consistent(scan, seg, config);
  ASSERT_EQ(seg.objects.size(), 1u);
  EXPECT_EQ(seg.objects[0].point_count, wall_points - 5);
  EXPECT_EQ(seg.invalid_beams, clean.invalid_beams + 5);
  for (std::int32_t i = mid - 2; i <= mid + 2; ++i) EXPECT_EQ(seg.beam_labels[i], kLabelInvalid);
}

TEST(Segmentation, MaskedSectorSplitsObjectsAndIsLabelled) {
  // The thesis's sensor folds part of its view to the floor; here 10 degrees straight ahead.
  World world;
  world.segments = {wall(3.0, -3.0, 3.0, 3.0)};
  const LaserScan scan = cast(world, thesis_geometry());
  SegmentationConfig config;
  config.masked_sectors = {{-5.0 * kDeg, 5.0 * kDeg}};
  Segmenter segmenter{config};
  const Segmentation seg = segmenter.segment(scan);
  expect_consistent(scan, seg, config);
  ASSERT_EQ(seg.objects.size(), 2u);
  EXPECT_EQ(seg.objects[0].after_last, EdgeNeighbour::kMaskedSector);
  EXPECT_EQ(seg.objects[1].before_first, EdgeNeighbour::kMaskedSector);
  std::int32_t masked = 0;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const bool inside = std::abs(scan.bearing_rad(i)) <= 5.0 * kDeg;
    EXPECT_EQ(seg.beam_labels[i] == kLabelMasked, inside) << "beam " << i;
    masked += inside ? 1 : 0;
  }
  EXPECT_EQ(seg.masked_beams, masked);
  EXPECT_EQ(seg.valid_beams + seg.masked_beams + seg.invalid_beams,
            static_cast<std::int32_t>(scan.size()));
}

TEST(Segmentation, MergeNeverCrossesAMaskedSector) {
  // Legs on either side of a narrow masked sector: their facing edges are within eps but the
  // sensor did not see the space between them.
  World world;
  world.segments = {wall(3.0, -3.0, 3.0, 3.0)};
  world.circles = {{{1.0, 0.07}, 0.06}, {{1.0, -0.07}, 0.06}};
  const LaserScan scan = cast(world, thesis_geometry());
  SegmentationConfig config;
  Segmenter unmasked{config};
  EXPECT_EQ(unmasked.segment(scan).merges, 1);
  config.masked_sectors = {{-0.4 * kDeg, 0.4 * kDeg}};
  Segmenter segmenter{config};
  const Segmentation seg = segmenter.segment(scan);
  expect_consistent(scan, seg, config);
  EXPECT_EQ(seg.merges, 0);
}

TEST(Segmentation, MaskedSectorAcrossBearingPi) {
  // A sector given as 170..190 degrees covers the bearings either side of +-180.
  LaserScan scan =
      cast({{wall(-3, -3, -3, 3), wall(3, -3, 3, 3), wall(-3, 3, 3, 3), wall(-3, -3, 3, -3)}, {}},
           full_circle_geometry());
  SegmentationConfig config;
  config.masked_sectors = {{170.0 * kDeg, 190.0 * kDeg}};
  Segmenter segmenter{config};
  const Segmentation seg = segmenter.segment(scan);
  expect_consistent(scan, seg, config);
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const double b = std::abs(wrap_angle(scan.bearing_rad(i)));
    if (b > 170.5 * kDeg) {
      EXPECT_EQ(seg.beam_labels[i], kLabelMasked) << i;
    }
    if (b < 169.5 * kDeg) {
      EXPECT_NE(seg.beam_labels[i], kLabelMasked) << i;
    }
  }
  for (const ScanObject& o : seg.objects) EXPECT_FALSE(o.straddles_seam());
}

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
  // ranges differ by only 7.4 cm. The exact metric sees a row of separate points (eps is 10 cm);
  // the thesis's |r1 - r2| sees one wall.
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
