#include "dispel/core/laser_scan.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <set>
#include <string>

namespace dispel {
namespace {

LaserScan good_scan() {
  LaserScan scan;
  scan.angle_min_rad = -1.0;
  scan.angle_increment_rad = 0.01;
  scan.range_min_m = 0.1F;
  scan.range_max_m = 20.0F;
  scan.ranges_m = {0.05F,
                   0.1F,
                   5.0F,
                   20.0F,
                   20.5F,
                   std::numeric_limits<float>::quiet_NaN(),
                   std::numeric_limits<float>::infinity()};
  return scan;
}

TEST(LaserScan, ValidityFollowsRangeLimitsInclusive) {
  const LaserScan scan = good_scan();
  EXPECT_FALSE(scan.is_valid(0));
  EXPECT_TRUE(scan.is_valid(1));
  EXPECT_TRUE(scan.is_valid(2));
  EXPECT_TRUE(scan.is_valid(3));
  EXPECT_FALSE(scan.is_valid(4));
  EXPECT_FALSE(scan.is_valid(5));
  EXPECT_FALSE(scan.is_valid(6));
}

TEST(LaserScan, InfiniteRangeMaxAcceptsInfiniteRanges) {
  LaserScan scan = good_scan();
  scan.range_max_m = std::numeric_limits<float>::infinity();
  EXPECT_EQ(check_scan(scan), ScanIssue::kNone);
  EXPECT_TRUE(scan.is_valid(6));
  EXPECT_FALSE(scan.is_valid(5));
}

TEST(LaserScan, BearingOfBeam) {
  const LaserScan scan = good_scan();
  EXPECT_DOUBLE_EQ(scan.bearing_rad(0), -1.0);
  EXPECT_DOUBLE_EQ(scan.bearing_rad(100), 0.0);
}

TEST(LaserScan, GoodScanPassesTheCheck) { EXPECT_EQ(check_scan(good_scan()), ScanIssue::kNone); }

TEST(LaserScan, EveryIssueHasADistinctNameAndADescription) {
  std::set<std::string> names;
  for (std::size_t i = 0; i < kScanIssueCount; ++i) {
    const auto issue = static_cast<ScanIssue>(i);
    names.insert(scan_issue_name(issue));
    if (issue != ScanIssue::kNone) {
      EXPECT_FALSE(describe_scan_issue(good_scan(), issue).empty());
    }
  }
  EXPECT_EQ(names.size(), kScanIssueCount);
  EXPECT_EQ(names.count("unknown"), 0u);
  EXPECT_TRUE(describe_scan_issue(good_scan(), ScanIssue::kNone).empty());
}

TEST(LaserScan, DescriptionNamesTheValue) {
  LaserScan scan = good_scan();
  scan.angle_increment_rad = -0.25;
  ASSERT_EQ(check_scan(scan), ScanIssue::kNonPositiveIncrement);
  const std::string message = describe_scan_issue(scan, ScanIssue::kNonPositiveIncrement);
  EXPECT_NE(message.find("angle_increment_rad"), std::string::npos);
  EXPECT_NE(message.find("-0.25"), std::string::npos);
}

}  // namespace
}  // namespace dispel
