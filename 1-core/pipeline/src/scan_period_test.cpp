#include "dispel/pipeline/scan_period.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace dispel::pipeline {
namespace {

TEST(ScanPeriod, AGivenPeriodWinsOverWhatTheScansSay) {
  ScanPeriod p(0.025);
  EXPECT_EQ(p.add(10.0, 0.1), 0.025);
  EXPECT_EQ(p.period(), 0.025);
}

TEST(ScanPeriod, TheFirstStatedPeriodIsTaken) {
  ScanPeriod p;
  EXPECT_EQ(p.add(10.0, 0.0), std::nullopt);  // States none.
  EXPECT_EQ(p.add(10.1, 0.1), 0.1);           // The first that does.
  EXPECT_EQ(p.add(10.2, 0.05), 0.1);          // Known: stays.
  ScanPeriod bad;
  EXPECT_EQ(bad.add(10.0, std::nanf("")), std::nullopt);
  EXPECT_EQ(bad.add(10.1, -0.1), std::nullopt);
}

TEST(ScanPeriod, WithoutStatedPeriodsTheMedianIntervalOneDroppedScanCannotChange) {
  ScanPeriod p;
  EXPECT_EQ(p.add(10.0, 0.0), std::nullopt);
  EXPECT_EQ(p.add(10.1, 0.0), std::nullopt);
  EXPECT_EQ(p.add(10.3, 0.0), std::nullopt);  // A scan dropped: 0.2 s.
  const std::optional<double> period = p.add(10.4, 0.0);
  ASSERT_TRUE(period.has_value());
  EXPECT_NEAR(*period, 0.1, 1e-9);
}

TEST(ScanPeriod, StampsThatDoNotIncreaseOrAreNotFiniteArePassedOver) {
  ScanPeriod p;
  for (double t : {5.0, 5.0, 4.0, std::nan(""), 5.05, 5.1, 5.15}) p.add(t, 0.0);
  ASSERT_TRUE(p.period().has_value());
  EXPECT_NEAR(*p.period(), 0.05, 1e-9);
  ScanPeriod never;
  for (int k = 0; k < 100; ++k) never.add(7.0, 0.0);  // The same stamp over and over.
  EXPECT_FALSE(never.period().has_value());
}

}  // namespace
}  // namespace dispel::pipeline
