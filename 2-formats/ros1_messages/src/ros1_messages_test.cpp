#include "dispel/io/ros1_messages.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

namespace dispel::io {
namespace {

TEST(Ros1Messages, TimeRoundTripsWithinAMicrosecond) {
  // A double holds epoch seconds to about 0.24 us; the filter's outputs copy the original header,
  // so their stamps are exact.
  const ros::Time t(1403201183, 698857000);
  EXPECT_LT(std::abs((to_ros_time(to_seconds(t)) - t).toSec()), 1e-6);
  EXPECT_EQ(to_ros_time(12.25), ros::Time(12, 250000000));
  EXPECT_EQ(to_ros_time(1.9999999999), ros::Time(2, 0));
}

TEST(Ros1Messages, YawRoundTripsThroughAQuaternion) {
  for (double yaw : {0.0, 0.5, -2.0, 3.1, -3.1}) {
    EXPECT_NEAR(wrap_angle(yaw_of(quaternion_from_yaw(yaw)) - yaw), 0.0, 1e-12);
  }
}

TEST(Ros1Messages, ScanRoundTripsAndFilterOutputKeepsTheHeader) {
  LaserScan scan;
  scan.stamp_s = 12.5;
  scan.angle_min_rad = -1.0;
  scan.angle_increment_rad = 0.25;
  scan.range_min_m = 0.1F;
  scan.range_max_m = 20.0F;
  scan.ranges_m = {1.0F, 2.0F, 3.0F};
  scan.intensities = {7.0F, 8.0F, 9.0F};
  const sensor_msgs::LaserScan msg = to_ros(scan, "laser");
  EXPECT_EQ(msg.header.frame_id, "laser");
  EXPECT_FLOAT_EQ(msg.angle_max, -0.5F);
  const LaserScan back = from_ros(msg);
  EXPECT_DOUBLE_EQ(back.stamp_s, 12.5);
  EXPECT_EQ(back.ranges_m, scan.ranges_m);
  EXPECT_EQ(back.intensities, scan.intensities);

  FilterResult result;
  result.filtered = scan;
  result.filtered.ranges_m[1] = std::nanf("");
  result.labels = {BeamLabel::kStatic, BeamLabel::kDynamic, BeamLabel::kNoObject};
  const sensor_msgs::LaserScan filtered = filtered_message(msg, result);
  EXPECT_EQ(filtered.header.frame_id, "laser");
  EXPECT_EQ(filtered.header.stamp, msg.header.stamp);
  EXPECT_TRUE(std::isnan(filtered.ranges[1]));
  EXPECT_EQ(filtered.intensities, msg.intensities);
  const sensor_msgs::LaserScan labels = labels_message(msg, result);
  EXPECT_EQ(labels.ranges, msg.ranges);
  EXPECT_EQ(labels.intensities, (std::vector<float>{0.0F, 1.0F, 3.0F}));
}

TEST(Ros1Messages, EveryMessageRoundTripsThroughTheRecordingModel) {
  sensor_msgs::LaserScan scan;
  scan.header.seq = 17;
  scan.header.stamp = ros::Time(1403201183, 698857001);
  scan.header.frame_id = "/laser";
  scan.angle_min = -2.35619F;
  scan.angle_max = 2.35619F;
  scan.angle_increment = 0.0061359233F;
  scan.time_increment = 9.7656e-05F;
  scan.scan_time = 0.1F;
  scan.range_min = 0.02F;
  scan.range_max = 5.6F;
  scan.ranges = {1.0F, std::nanf(""), std::numeric_limits<float>::infinity(), 0.01F};
  scan.intensities = {1.0F, 2.0F, 3.0F, 4.0F};
  const sensor_msgs::LaserScan back = to_ros(to_message(scan));
  EXPECT_EQ(back.header.seq, scan.header.seq);
  EXPECT_EQ(back.header.stamp, scan.header.stamp);  // Exactly, to the nanosecond.
  EXPECT_EQ(back.header.frame_id, scan.header.frame_id);
  EXPECT_EQ(back.angle_min, scan.angle_min);
  EXPECT_EQ(back.angle_max, scan.angle_max);
  EXPECT_EQ(back.angle_increment, scan.angle_increment);
  EXPECT_EQ(back.time_increment, scan.time_increment);
  EXPECT_EQ(back.scan_time, scan.scan_time);
  EXPECT_EQ(back.range_min, scan.range_min);
  EXPECT_EQ(back.range_max, scan.range_max);
  ASSERT_EQ(back.ranges.size(), 4u);
  EXPECT_EQ(std::memcmp(back.ranges.data(), scan.ranges.data(), 4 * sizeof(float)), 0);
  EXPECT_EQ(back.intensities, scan.intensities);

  const nav_msgs::Odometry od =
      to_ros_odometry(12.5, "odom", "base_link", {1.0, 2.0, 0.3}, 0.4, -0.2);
  const OdometryMessage om = to_message(od);
  EXPECT_EQ(om.child_frame_id, "base_link");
  EXPECT_NEAR(om.pose.yaw_rad, 0.3, 1e-12);
  EXPECT_EQ(om.v_mps, 0.4);
  EXPECT_EQ(om.w_radps, -0.2);
  EXPECT_EQ(to_ros(om).header.stamp, od.header.stamp);
  // The covariances and the lateral speed go through whole, both ways.
  nav_msgs::Odometry with_covariance = od;
  for (std::size_t i = 0; i < 36; ++i) {
    with_covariance.pose.covariance[i] = 0.5 + static_cast<double>(i);
    with_covariance.twist.covariance[i] = -1.0 - static_cast<double>(i);
  }
  with_covariance.twist.twist.linear.y = 0.25;
  const OdometryMessage oc = to_message(with_covariance);
  EXPECT_EQ(oc.pose_covariance[35], 35.5);
  EXPECT_EQ(oc.twist_covariance[7], -8.0);
  EXPECT_EQ(oc.vy_mps, 0.25);
  const nav_msgs::Odometry back_c = to_ros(oc);
  EXPECT_EQ(back_c.pose.covariance, with_covariance.pose.covariance);
  EXPECT_EQ(back_c.twist.covariance, with_covariance.twist.covariance);
  EXPECT_EQ(back_c.twist.twist.linear.y, 0.25);

  tf2_msgs::TFMessage tf =
      to_ros(TransformsMessage{{{Stamp{5, 1}, "base_link", "laser", {0.2, -0.1, 0.5}}}});
  const TransformsMessage tm = to_message(tf);
  ASSERT_EQ(tm.transforms.size(), 1u);
  EXPECT_EQ(tm.transforms[0].stamp, (Stamp{5, 1}));
  EXPECT_EQ(tm.transforms[0].child, "laser");
  EXPECT_NEAR(tm.transforms[0].child_in_parent.yaw_rad, 0.5, 1e-12);

  sensor_msgs::Imu imu;
  imu.orientation_covariance[0] = -1.0;
  imu.angular_velocity.z = 0.25;
  const ImuMessage im = to_message(imu);
  EXPECT_FALSE(im.has_orientation);
  EXPECT_EQ(to_ros(im).orientation_covariance[0], -1.0);
  EXPECT_EQ(to_ros(im).angular_velocity.z, 0.25);
}

TEST(Ros1Messages, WheelSpeedsFromJointStateOdometryAndImuFollowTheSettings) {
  OdometrySettings settings;
  sensor_msgs::JointState js;
  js.header.stamp = ros::Time(10, 500000000);
  js.name = {"front_right_wheel", "front_left_wheel"};
  js.velocity = {2.0, 1.0};
  auto w = wheel_speeds(to_message(js), settings, Stamp{99, 0});
  ASSERT_TRUE(w.has_value());
  EXPECT_DOUBLE_EQ(w->t_s, 10.5);
  EXPECT_DOUBLE_EQ(w->left_mps, 1.0);  // By name, not by position.
  EXPECT_DOUBLE_EQ(w->right_mps, 2.0);
  settings.wheel_radius_m = 0.1;  // rad/s of wheels of 0.1 m.
  js.header.stamp = ros::Time();  // No stamp: the receive time.
  w = wheel_speeds(to_message(js), settings, Stamp{99, 0});
  ASSERT_TRUE(w.has_value());
  EXPECT_DOUBLE_EQ(w->t_s, 99.0);
  EXPECT_DOUBLE_EQ(w->left_mps, 0.1);
  settings.left_wheel_joint = "rear_left_wheel";  // Named but absent.
  EXPECT_FALSE(wheel_speeds(to_message(js), settings, Stamp{99, 0}).has_value());

  nav_msgs::Odometry od;
  od.header.stamp = ros::Time(3);
  od.twist.twist.linear.x = 1.0;
  od.twist.twist.angular.z = 0.5;
  const WheelSpeeds from_odom = wheel_speeds(to_message(od), 0.4, Stamp{99, 0});
  EXPECT_DOUBLE_EQ(from_odom.t_s, 3.0);
  EXPECT_DOUBLE_EQ(from_odom.left_mps, 0.9);
  EXPECT_DOUBLE_EQ(from_odom.right_mps, 1.1);

  sensor_msgs::Imu imu;
  imu.angular_velocity.x = 1.0;
  imu.angular_velocity.y = 2.0;
  imu.angular_velocity.z = 3.0;
  EXPECT_DOUBLE_EQ(yaw_rate(to_message(imu), settings), 3.0);
  settings = parse_odometry_settings("odometry: {imu_yaw_axis: -y}\n", "t.yaml");
  EXPECT_DOUBLE_EQ(yaw_rate(to_message(imu), settings), -2.0);
}

}  // namespace
}  // namespace dispel::io
