#include "dispel/core/pose2.hpp"

#include <gtest/gtest.h>

namespace dispel {
namespace {

TEST(WrapAngle, MapsIntoHalfOpenInterval) {
  EXPECT_NEAR(wrap_angle(0.0), 0.0, 1e-12);
  EXPECT_NEAR(wrap_angle(3.0 * kPi / 2.0), -kPi / 2.0, 1e-12);
  EXPECT_NEAR(wrap_angle(-3.0 * kPi / 2.0), kPi / 2.0, 1e-12);
  EXPECT_NEAR(wrap_angle(kPi), -kPi, 1e-12);
  EXPECT_NEAR(wrap_angle(21.0 * kPi + 0.1), -kPi + 0.1, 1e-9);
}

TEST(Pose2, AppliesRotationThenTranslation) {
  const Pose2 pose{1.0, 2.0, kPi / 2.0};
  const Eigen::Vector2d p = pose.apply({1.0, 0.0});
  EXPECT_NEAR(p.x(), 1.0, 1e-12);
  EXPECT_NEAR(p.y(), 3.0, 1e-12);
}

TEST(Pose2, InverseUndoesTheTransform) {
  const Pose2 pose{-0.7, 3.1, 2.4};
  const Eigen::Vector2d q(0.3, -1.2);
  const Eigen::Vector2d back = pose.inverse().apply(pose.apply(q));
  EXPECT_NEAR(back.x(), q.x(), 1e-12);
  EXPECT_NEAR(back.y(), q.y(), 1e-12);
  const Pose2 identity = pose * pose.inverse();
  EXPECT_NEAR(identity.x_m, 0.0, 1e-12);
  EXPECT_NEAR(identity.y_m, 0.0, 1e-12);
  EXPECT_NEAR(identity.yaw_rad, 0.0, 1e-12);
}

TEST(Pose2, CompositionMatchesApplyingInTurn) {
  const Pose2 odom_base{2.0, -1.0, 0.9};
  const Pose2 base_laser{0.3, 0.05, -0.2};
  const Eigen::Vector2d p(1.5, 0.4);
  const Eigen::Vector2d direct = (odom_base * base_laser).apply(p);
  const Eigen::Vector2d in_turn = odom_base.apply(base_laser.apply(p));
  EXPECT_NEAR(direct.x(), in_turn.x(), 1e-12);
  EXPECT_NEAR(direct.y(), in_turn.y(), 1e-12);
}

// A scan's beams each turned by the sensor's turn up to its time: 2000 beams by recurrence stay
// within 1e-12 of the rotation computed anew, and a zero step leaves every direction as it was.
TEST(SteppedRotation, MatchesTheRotationByEachMultipleAndIsExactWithoutATurn) {
  const double step = 0.5 * 0.1 / 768.0;  // one beam of a 768-beam 0.1 s sweep at 0.5 rad/s
  SteppedRotation turn(100.0 * step);     // a hundred times that: 2000 steps make 13 rad
  SteppedRotation none(0.0);
  const Eigen::Vector2d v(0.6, -0.8);
  for (int b = 0; b < 2000; ++b) {
    if (b > 0) {
      turn.advance();
      none.advance();
    }
    const Eigen::Vector2d expected = PoseTransform(Pose2{0.0, 0.0, 100.0 * step * b}).rotate(v);
    const Eigen::Vector2d got = turn.rotate(v);
    ASSERT_NEAR(got.x(), expected.x(), 1e-12) << "beam " << b;
    ASSERT_NEAR(got.y(), expected.y(), 1e-12) << "beam " << b;
    ASSERT_EQ(none.rotate(v), v) << "beam " << b;
  }
}

}  // namespace
}  // namespace dispel
