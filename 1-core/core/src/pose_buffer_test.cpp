#include "dispel/core/pose_buffer.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace dispel {
namespace {

TEST(PoseBuffer, InterpolatesPositionAndYawAlongTheShorterArc) {
  PoseBuffer buffer(0.05, 0.5);
  ASSERT_TRUE(buffer.add(1.0, {0.0, 0.0, 3.0}));
  ASSERT_TRUE(buffer.add(1.2, {2.0, -1.0, -3.0}));  // Crosses +-pi: 0.28 rad the short way.
  Pose2 p;
  ASSERT_EQ(buffer.lookup(1.05, p), PoseLookup::kOk);
  EXPECT_NEAR(p.x_m, 0.5, 1e-12);
  EXPECT_NEAR(p.y_m, -0.25, 1e-12);
  EXPECT_NEAR(wrap_angle(p.yaw_rad - (3.0 + 0.25 * (2.0 * kPi - 6.0))), 0.0, 1e-12);
}

TEST(PoseBuffer, NeverExtrapolatesBeyondTheTolerance) {
  PoseBuffer buffer(0.05, 0.5);
  buffer.add(1.0, {1.0, 2.0, 0.1});
  buffer.add(2.0 - 1.6, {0.0, 0.0, 0.0});  // Out of order: refused.
  buffer.add(1.1, {2.0, 2.0, 0.1});
  Pose2 p;
  EXPECT_EQ(buffer.lookup(0.96, p), PoseLookup::kOk);
  EXPECT_EQ(p.x_m, 1.0);
  EXPECT_EQ(buffer.lookup(0.9, p), PoseLookup::kBeforeFirst);
  EXPECT_EQ(buffer.lookup(1.14, p), PoseLookup::kOk);
  EXPECT_EQ(p.x_m, 2.0);
  EXPECT_EQ(buffer.lookup(1.2, p), PoseLookup::kAfterLast);
  EXPECT_EQ(buffer.size(), 2u);
}

TEST(PoseBuffer, RefusesNonFiniteAndRepeatedStampsAndDoesNotBridgeGaps) {
  PoseBuffer buffer(0.05, 0.5);
  Pose2 p;
  EXPECT_EQ(buffer.lookup(0.0, p), PoseLookup::kEmpty);
  EXPECT_FALSE(buffer.add(std::nan(""), {}));
  EXPECT_FALSE(buffer.add(1.0, {std::nan(""), 0.0, 0.0}));
  EXPECT_TRUE(buffer.add(1.0, {}));
  EXPECT_FALSE(buffer.add(1.0, {}));
  EXPECT_TRUE(buffer.add(3.0, {}));
  EXPECT_EQ(buffer.lookup(2.0, p), PoseLookup::kGap);
  // At either side of the gap, within the tolerance, the pose there (not interpolated).
  ASSERT_TRUE(buffer.add(4.0, {1.0, 0.0, 0.0}));
  EXPECT_EQ(buffer.lookup(3.0, p), PoseLookup::kOk);
  EXPECT_EQ(p.x_m, 0.0);
  EXPECT_EQ(buffer.lookup(3.96, p), PoseLookup::kOk);
  EXPECT_EQ(p.x_m, 1.0);
  EXPECT_EQ(buffer.lookup(3.03, p), PoseLookup::kOk);
  EXPECT_EQ(p.x_m, 0.0);
  EXPECT_EQ(buffer.lookup(3.9, p), PoseLookup::kGap);
  EXPECT_STREQ(pose_lookup_name(PoseLookup::kGap), "pose_gap");
}

// Forgetting what lies before a stamp changes no lookup at that stamp or later, and keeps the
// buffer short when it is fed for a long time.
TEST(PoseBuffer, ForgettingTheOldPosesChangesNoLaterLookup) {
  PoseBuffer full(0.05, 0.5), pruned(0.05, 0.5);
  for (int k = 0; k < 1000; ++k) {
    const double t = 0.01 * k + (k > 500 ? 0.7 : 0.0);  // One gap after k = 500.
    const Pose2 pose{std::cos(t), std::sin(2.0 * t), wrap_angle(3.0 * t)};
    ASSERT_TRUE(full.add(t, pose));
    ASSERT_TRUE(pruned.add(t, pose));
    const double asked = t - 0.013;  // A scan a little older than the newest pose.
    pruned.forget_before(asked);
    EXPECT_LE(pruned.size(), 3u) << k;
    for (const double u : {asked, asked + 0.004, t, t + 0.02}) {
      Pose2 a, b;
      const PoseLookup ra = full.lookup(u, a), rb = pruned.lookup(u, b);
      ASSERT_EQ(ra, rb) << k << " " << u;
      if (ra != PoseLookup::kOk) continue;
      EXPECT_EQ(a.x_m, b.x_m);
      EXPECT_EQ(a.y_m, b.y_m);
      EXPECT_EQ(a.yaw_rad, b.yaw_rad);
    }
  }
  pruned.forget_before(1e9);
  EXPECT_EQ(pruned.size(), 1u);  // The last pose stays: a lookup within the tolerance needs it.
}

}  // namespace
}  // namespace dispel
