#include "dispel/io/frame_tree.hpp"

#include <gtest/gtest.h>

namespace dispel::io {
namespace {

TEST(FrameTree, ChainsMountsBothWaysAndIgnoresLeadingSlashes) {
  FrameTree tree;
  tree.set("base_footprint", "base_link", {0.0, 0.0, 0.0});
  tree.set("/base_link", "laser_mount", {0.3, 0.1, 0.5});
  tree.set("laser_mount", "laser", {0.05, 0.0, kPi});
  const auto direct = tree.lookup("base_footprint", "/laser");
  ASSERT_TRUE(direct.has_value());
  const Pose2 expected = Pose2{0.3, 0.1, 0.5} * Pose2{0.05, 0.0, kPi};
  EXPECT_NEAR(direct->x_m, expected.x_m, 1e-12);
  EXPECT_NEAR(direct->y_m, expected.y_m, 1e-12);
  EXPECT_NEAR(wrap_angle(direct->yaw_rad - expected.yaw_rad), 0.0, 1e-12);
  const auto back = tree.lookup("laser", "base_footprint");
  ASSERT_TRUE(back.has_value());
  const Pose2 identity = *direct * *back;
  EXPECT_NEAR(identity.x_m, 0.0, 1e-12);
  EXPECT_NEAR(identity.y_m, 0.0, 1e-12);
  EXPECT_TRUE(tree.lookup("laser", "laser").has_value());
  EXPECT_FALSE(tree.lookup("base_link", "camera").has_value());
}

TEST(FrameTree, ALaterValueOfAnEdgeReplacesTheEarlierOneInEitherDirection) {
  FrameTree tree;
  tree.set("base_link", "laser", {1.0, 0.0, 0.0});
  tree.set("laser", "base_link", {-2.0, 0.0, 0.0});
  EXPECT_EQ(tree.edge_count(), 1u);
  EXPECT_NEAR(tree.lookup("base_link", "laser")->x_m, 2.0, 1e-12);
}

}  // namespace
}  // namespace dispel::io
