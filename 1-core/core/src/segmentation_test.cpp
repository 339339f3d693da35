// Segmentation (thesis section 3.2.1): its configuration and input checks, and the pass on
// scripted scenes. 360-degree scanners, the gap metric, edges and recorded scans:
// segmentation_scanners_test.cpp.
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

#include "scan_csv.hpp"
#include "segmentation_checks.hpp"

namespace dispel {
namespace {

using namespace segmentation_checks;  // NOLINT: the checks' vocabulary.

// --- Configuration and input checks -----------------------------------------------------------

TEST(SegmentationConfig, DefaultsAreTheThesisEpsAndNminWithExactGaps) {
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
  c.cluster_gap_spacings = -1.0;
  expect_rejected(c, "cluster_gap_spacings");
  c.cluster_gap_spacings = 21.0;
  expect_rejected(c, "cluster_gap_spacings");
  c.cluster_gap_spacings = std::numeric_limits<double>::quiet_NaN();
  expect_rejected(c, "cluster_gap_spacings");
  c = SegmentationConfig{};
  c.min_points = 0;
  expect_rejected(c, "min_points");
  c = SegmentationConfig{};
  c.min_width_m = -0.1;
  expect_rejected(c, "min_width_m");
  c.min_width_m = std::numeric_limits<double>::infinity();
  expect_rejected(c, "min_width_m");
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

// A 768-beam, 270-degree scanner (0.352 degrees), N_min 4 as --scale-to-scanner makes it.
ScanGeometry scanner_768() { return {-135.0 * kDeg, 270.0 * kDeg / 767.0, 768, 0.05F, 30.0F}; }

std::int32_t beams_nearer_than(const LaserScan& scan, float range_m) {
  return static_cast<std::int32_t>(std::count_if(scan.ranges_m.begin(), scan.ranges_m.end(),
                                                 [&](float r) { return r < range_m; }));
}

// Far away a surface seen at a slant has its points farther apart than eps: a 768-beam scanner's
// beams (0.35 degrees) land 6 cm apart square-on at 10 m, and 14-18 cm apart at 65-70 degrees
// from square-on. With eps alone the surface breaks into pieces under N_min, different ones in
// every scan as the robot drives (the simulated warehouse's cart at 10 m was missed so, and real
// walls at a slant become "walkers" whose centroids slide). cluster_gap_spacings joins points
// within that many beam spacings at the nearer one's range; a person 0.3 m across, 0.4 m before
// a wall at 8.5 m (3 spacings there: 16 cm), stays apart from it.
TEST(Segmentation, FarAwayASlantedSurfaceIsOneObjectAndAPersonBeforeAWallStaysApart) {
  World world;
  const Eigen::Vector2d hit(10.0, 0.0);
  const Eigen::Vector2d along(std::sin(65.0 * kPi / 180.0), std::cos(65.0 * kPi / 180.0));
  world.segments = {{hit - 1.0 * along, hit + 1.0 * along}, wall(-3.0, 8.55, 3.0, 8.55)};
  world.circles = {{{0.0, 8.0}, 0.15}};
  const LaserScan scan = cast(world, scanner_768());
  SegmentationConfig config;
  config.min_points = 4;
  const Segmentation seg = Segmenter{config}.segment(scan);
  expect_consistent(scan, seg, config);
  const ScanObject* slanted = object_near(seg, hit, 0.2);
  ASSERT_NE(slanted, nullptr);
  std::int32_t slanted_beams = 0;
  for (std::int32_t b = 0; b < static_cast<std::int32_t>(scan.size()); ++b) {
    if (scan.is_valid(b) && (point_of(scan, b) - hit).norm() < 1.1) {
      ++slanted_beams;
    }
  }
  EXPECT_EQ(slanted->point_count, slanted_beams);  // The whole surface, one object.
  const ScanObject* person = object_near(seg, {0.0, 7.9}, 0.1);
  ASSERT_NE(person, nullptr);
  EXPECT_LE(person->point_count, 8);  // The person alone (about 6 beams), not the wall behind.
  EXPECT_EQ(person->before_first, EdgeNeighbour::kFarther);
  EXPECT_EQ(person->after_last, EdgeNeighbour::kFarther);

  config.cluster_gap_spacings = 0.0;  // eps at every range: the thesis.
  const Segmentation eps_only = Segmenter{config}.segment(scan);
  expect_consistent(scan, eps_only, config);
  const ScanObject* piece = object_near(eps_only, hit, 0.2);
  EXPECT_TRUE(piece == nullptr || piece->point_count < slanted_beams / 2);
}

TEST(Segmentation, ALegAtRangeIsAnObjectWhenNminFallsWithItsWidth) {
  // A leg 12 cm across at 7 m in front of a wall at 10 m, and one against nothing.
  World world;
  world.segments = {wall(10.0, -10.0, 10.0, 1.0)};
  world.circles = {{{7.0, 0.0}, 0.06}, {{0.0, 7.0}, 0.06}};
  const LaserScan scan = cast(world, scanner_768());

  SegmentationConfig config;
  config.min_points = 4;
  const Segmentation fixed = Segmenter{config}.segment(scan);
  expect_consistent(scan, fixed, config);
  EXPECT_EQ(object_near(fixed, {6.95, 0.0}, 0.1), nullptr);
  EXPECT_EQ(object_near(fixed, {0.0, 6.95}, 0.1), nullptr);  // Each leg is below N_min.

  config.min_width_m = 0.1;  // 0.1 m at 7 m is 2.3 beams: N_min 2 there.
  const Segmentation by_width = Segmenter{config}.segment(scan);
  expect_consistent(scan, by_width, config);
  for (const Eigen::Vector2d& leg : {Eigen::Vector2d(6.95, 0.0), Eigen::Vector2d(0.0, 6.95)}) {
    const ScanObject* o = object_near(by_width, leg, 0.1);
    ASSERT_NE(o, nullptr);
    EXPECT_GE(o->point_count, 2);
    EXPECT_LE(o->point_count, 3);
  }
  EXPECT_EQ(by_width.noise_beams, fixed.noise_beams - beams_nearer_than(scan, 7.5F));
  // A thin thing at 9 m (0.1 m there is 1.8 beams): one beam stays noise.
  world.circles = {{{6.36, 6.36}, 0.02}};
  const LaserScan cable = cast(world, scanner_768());
  ASSERT_EQ(beams_nearer_than(cable, 9.5F), 1);
  EXPECT_EQ(Segmenter{config}.segment(cable).objects.size(), 1U);  // The wall alone.
}

// Near the end of a scanner's reach a few beams that return may be its noise, not a thing: N_min
// falls with width only within 0.8 of range_max (person_following_outdoor_1's 5.6 m scanner
// returns runs of 1-4 beams at 4-5.6 m among beams that return nothing, in the same places scan
// after scan).
TEST(Segmentation, NminFallsWithWidthOnlyWithinFourFifthsOfTheScannersReach) {
  World world;
  world.circles = {{{7.0, 0.0}, 0.06}};  // A leg at 7 m against nothing: 2-3 beams.
  LaserScan scan = cast(world, scanner_768());
  SegmentationConfig config;
  config.min_points = 4;
  config.min_width_m = 0.1;
  scan.range_max_m = 8.0F;  // The leg at 0.87 of the reach: noise.
  const Segmentation near_the_end = Segmenter{config}.segment(scan);
  expect_consistent(scan, near_the_end, config);
  EXPECT_EQ(object_near(near_the_end, {6.95, 0.0}, 0.1), nullptr);
  scan.range_max_m = 9.0F;  // At 0.78 of it: an object.
  const Segmentation within = Segmenter{config}.segment(scan);
  expect_consistent(scan, within, config);
  EXPECT_NE(object_near(within, {6.95, 0.0}, 0.1), nullptr);
}

// N_min 4, falling with range to the beams a thing 0.1 m wide covers; @p scan segmented with it.
Segmentation segment_by_width(const LaserScan& scan) {
  SegmentationConfig config;
  config.min_points = 4;
  config.min_width_m = 0.1;
  Segmentation seg = Segmenter{config}.segment(scan);
  expect_consistent(scan, seg, config);
  return seg;
}

TEST(Segmentation, APieceCutByWhatIsBesideItStaysNoiseWhateverItsWidth) {
  // Three beams at 6 m against nothing; three more beside something nearer; three at the end of
  // the view. Only the first stand out whole: the others may be part of something larger.
  LaserScan scan = cast(World{}, scanner_768());
  const auto set = [&](std::size_t from, std::size_t to, float range) {
    for (std::size_t i = from; i <= to; ++i) scan.ranges_m[i] = range;
  };
  set(300, 302, 6.0F);
  set(400, 402, 6.0F);
  set(403, 412, 3.0F);  // A pillar beside the second piece.
  set(0, 2, 6.0F);
  const Segmentation seg = segment_by_width(scan);
  EXPECT_EQ(seg.objects.size(), 2U);
  EXPECT_GE(seg.beam_labels[301], 0);
  EXPECT_GE(seg.beam_labels[405], 0);
  for (std::size_t i : {0, 1, 2, 400, 401, 402}) EXPECT_EQ(seg.beam_labels[i], kLabelNoise) << i;
}

TEST(Segmentation, APieceBesideABeamThatMeasuredNothingStaysNoiseWhateverItsWidth) {
  // Three beams at 6 m, each piece beside a different kind of invalid beam on both sides. Only
  // no return at all (+inf, or beyond range_max: REP 117's "nothing there") shows it standing out
  // in front of what is beside it; an erroneous reading (NaN, below range_min: a scanner's error
  // code, which negative_2's lasers give on a fifth of their beams) may be more of the same wall.
  LaserScan scan = cast(World{}, scanner_768());
  const auto piece = [&](std::size_t from, float beside) {
    scan.ranges_m[from - 1] = beside;
    for (std::size_t i = from; i < from + 3; ++i) scan.ranges_m[i] = 6.0F;
    scan.ranges_m[from + 3] = beside;
  };
  piece(100, kInf);
  piece(200, 41.0F);  // Beyond the scanner's range_max.
  piece(300, kNaN);
  piece(400, 0.0F);  // Below range_min: an error code.
  const Segmentation seg = segment_by_width(scan);
  EXPECT_EQ(seg.objects.size(), 2U);
  for (std::size_t i : {100, 101, 102, 200, 201, 202}) EXPECT_GE(seg.beam_labels[i], 0) << i;
  for (std::size_t i : {300, 301, 302, 400, 401, 402})
    EXPECT_EQ(seg.beam_labels[i], kLabelNoise) << i;
}

TEST(Segmentation, APieceBelowNminIsAnObjectOnlyWhereSomethingWasSeenBefore) {
  // Two legs of three beams at 6 m against nothing; the caller's scan before saw something only
  // near the first (x > 0 in the sensor frame). Objects at min_points are not asked.
  LaserScan scan = cast(World{}, scanner_768());
  for (std::size_t i = 500; i < 503; ++i) scan.ranges_m[i] = 6.0F;  // Bearing about +40 degrees.
  for (std::size_t i = 100; i < 103; ++i) scan.ranges_m[i] = 6.0F;  // About -100 degrees.
  for (std::size_t i = 300; i < 310; ++i) scan.ranges_m[i] = 2.0F;  // A pillar, 10 beams.
  SegmentationConfig config;
  config.min_points = 4;
  config.min_width_m = 0.1;
  Segmenter segmenter{config};
  int asked = 0;
  Segmentation seg;
  segmenter.segment(scan, seg, [&](const Eigen::Vector2d& centroid_m) {
    ++asked;
    EXPECT_NEAR(centroid_m.norm(), 6.0, 0.05);
    return centroid_m.x() > 0.0;
  });
  expect_consistent(scan, seg, config);
  EXPECT_EQ(asked, 2);
  EXPECT_EQ(seg.objects.size(), 2U);
  EXPECT_GE(seg.beam_labels[501], 0);
  EXPECT_GE(seg.beam_labels[305], 0);
  EXPECT_EQ(seg.beam_labels[101], kLabelNoise);
  // Without the question both legs are objects.
  EXPECT_EQ(segmenter.segment(scan).objects.size(), 3U);
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
}  // namespace
}  // namespace dispel
