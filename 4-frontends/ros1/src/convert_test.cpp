#include "dispel/ros1/convert.hpp"

#include <gtest/gtest.h>

#include "dispel/io/ros1_messages.hpp"

namespace dispel::ros1 {
namespace {

TEST(Ros1Convert, MarkersShowObjectsSeenNowColouredByClassWithVelocityArrows) {
  TrackedObject walker;
  walker.id = 7;
  walker.object_class = ObjectClass::kDynamic;
  walker.position_m = {2.0, 1.0};
  walker.velocity_mps = {0.5, 0.0};
  walker.first_edge_m = {2.0, 0.8};
  walker.last_edge_m = {2.0, 1.2};
  TrackedObject wall = walker;
  wall.id = 8;
  wall.object_class = ObjectClass::kStatic;
  wall.velocity_mps = {0.0, 0.0};
  TrackedObject gone = walker;
  gone.id = 9;
  gone.missed_scans = 2;
  std_msgs::Header header;
  header.frame_id = "odom";
  header.stamp = ros::Time(5);

  const visualization_msgs::MarkerArray a = object_markers({walker, wall, gone}, header);
  ASSERT_FALSE(a.markers.empty());
  EXPECT_EQ(a.markers[0].action, visualization_msgs::Marker::DELETEALL);
  int arrows = 0, bodies = 0;
  for (std::size_t i = 1; i < a.markers.size(); ++i) {
    const visualization_msgs::Marker& m = a.markers[i];
    EXPECT_EQ(m.action, visualization_msgs::Marker::ADD);
    EXPECT_EQ(m.header.frame_id, "odom");
    EXPECT_NE(m.id, 9);  // Not seen in this scan: not drawn.
    if (m.type == visualization_msgs::Marker::ARROW) {
      ++arrows;
      EXPECT_EQ(m.id, 7);
      ASSERT_EQ(m.points.size(), 2u);
      EXPECT_DOUBLE_EQ(m.points[1].x - m.points[0].x, 0.5);  // One second of motion.
    }
    if (m.type == visualization_msgs::Marker::CYLINDER) {
      ++bodies;
      if (m.id == 7) {  // Dynamic: red.
        EXPECT_GT(m.color.r, 0.8F);
        EXPECT_LT(m.color.g, 0.2F);
      } else {  // Static: grey.
        EXPECT_EQ(m.color.r, m.color.g);
      }
      EXPECT_DOUBLE_EQ(m.scale.x, 0.4);
    }
  }
  EXPECT_EQ(arrows, 1);
  EXPECT_EQ(bodies, 2);
}

TEST(Ros1Convert, OdometryMessageAndTransformCarryTheEstimate) {
  OdometryEstimate e;
  e.t_s = 12.25;
  e.x_m = 1.0;
  e.y_m = -2.0;
  e.yaw_rad = 0.5;
  e.v_mps = 0.3;
  e.omega_radps = 0.1;
  e.x_variance_m2 = 0.01;
  e.yaw_variance_rad2 = 0.002;
  const nav_msgs::Odometry m = odometry_message(e, "odom", "base_link");
  EXPECT_EQ(m.header.stamp, ros::Time(12, 250000000));
  EXPECT_EQ(m.header.frame_id, "odom");
  EXPECT_EQ(m.child_frame_id, "base_link");
  EXPECT_DOUBLE_EQ(io::yaw_of(m.pose.pose.orientation), 0.5);
  EXPECT_EQ(m.pose.covariance[0], 0.01);
  EXPECT_EQ(m.pose.covariance[7], 0.0);  // NaN (not estimated) is written as 0.
  EXPECT_EQ(m.pose.covariance[35], 0.002);
  EXPECT_EQ(m.twist.twist.linear.x, 0.3);
  const geometry_msgs::TransformStamped t = odometry_transform(e, "odom", "base_link");
  EXPECT_EQ(t.transform.translation.y, -2.0);
  EXPECT_EQ(t.child_frame_id, "base_link");
}

TEST(Ros1Convert, DiagnosticStatusHoldsTheValues) {
  pipeline::DiagnosticStatus status;
  status.level = pipeline::DiagnosticStatus::Level::kWarn;
  status.name = "f";
  status.message = "m";
  status.hardware_id = "h";
  status.values = {{"scans", "3"}, {"time", "0.1"}};
  const auto s = to_ros(status);
  EXPECT_EQ(s.level, diagnostic_msgs::DiagnosticStatus::WARN);
  EXPECT_EQ(s.name, "f");
  EXPECT_EQ(s.message, "m");
  EXPECT_EQ(s.hardware_id, "h");
  ASSERT_EQ(s.values.size(), 2u);
  EXPECT_EQ(s.values[1].key, "time");
  EXPECT_EQ(s.values[1].value, "0.1");
}

}  // namespace
}  // namespace dispel::ros1
