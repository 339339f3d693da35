#include "dispel/io/ros2_messages.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace dispel::io {
namespace {

ScanMessage a_scan() {
  ScanMessage m;
  m.header.stamp = {1700000000, 123456789};
  m.header.frame_id = "laser";
  m.scan.stamp_s = m.header.stamp.seconds();
  m.scan.angle_min_rad = -1.5F;
  m.scan.angle_increment_rad = 0.01F;
  m.scan.range_min_m = 0.05F;
  m.scan.range_max_m = 30.0F;
  m.scan.ranges_m = {1.0F, std::numeric_limits<float>::quiet_NaN(),
                     std::numeric_limits<float>::infinity(), 2.5F};
  m.scan.intensities = {10.0F, 0.0F, 5.0F, 7.0F};
  m.angle_max = -1.47F;
  m.time_increment = 1e-4F;
  m.scan.time_increment_s = m.time_increment;
  m.scan_time = 0.1F;
  return m;
}

TEST(Ros2Messages, AScanComesBackFieldByField) {
  const ScanMessage m = a_scan();
  const std::vector<std::uint8_t> b = encode_ros2(m);
  ASSERT_GE(b.size(), 4U);
  EXPECT_EQ(b[0], 0);
  EXPECT_EQ(b[1], 1);  // Little-endian CDR.
  const ScanMessage d = decode_ros2_scan(b.data(), b.size());
  EXPECT_EQ(d.header.stamp, m.header.stamp);
  EXPECT_EQ(d.header.frame_id, "laser");
  EXPECT_FLOAT_EQ(static_cast<float>(d.scan.angle_min_rad), -1.5F);
  EXPECT_FLOAT_EQ(static_cast<float>(d.scan.angle_increment_rad), 0.01F);
  EXPECT_EQ(d.angle_max, m.angle_max);
  EXPECT_EQ(d.time_increment, m.time_increment);
  EXPECT_EQ(d.scan_time, m.scan_time);
  EXPECT_EQ(d.scan.range_min_m, m.scan.range_min_m);
  EXPECT_EQ(d.scan.range_max_m, m.scan.range_max_m);
  ASSERT_EQ(d.scan.ranges_m.size(), 4U);
  EXPECT_EQ(d.scan.ranges_m[0], 1.0F);
  EXPECT_TRUE(std::isnan(d.scan.ranges_m[1]));
  EXPECT_TRUE(std::isinf(d.scan.ranges_m[2]));
  EXPECT_EQ(d.scan.intensities, m.scan.intensities);
  EXPECT_DOUBLE_EQ(d.scan.stamp_s, m.header.stamp.seconds());
}

// The layout of a LaserScan in ROS 2's CDR, worked out by hand: the header (int32 sec, uint32
// nanosec, string), seven float32, then two float32 sequences.
TEST(Ros2Messages, AScanHasTheLayoutOfRos2sCdr) {
  ScanMessage m;
  m.header.stamp = {5, 6};
  m.header.frame_id = "ab";
  m.scan.ranges_m = {1.0F};
  const std::vector<std::uint8_t> b = encode_ros2(m);
  // 4 header + 4 sec + 4 nsec + 4 len + "ab\0" (3) + 1 pad + 7*4 + 4 + 4 + 4 (empty sequence).
  ASSERT_EQ(b.size(), 4U + 4 + 4 + 4 + 3 + 1 + 28 + 4 + 4 + 4);
  EXPECT_EQ(b[4], 5);
  EXPECT_EQ(b[8], 6);
  EXPECT_EQ(b[12], 3);  // String length with its NUL.
  EXPECT_EQ(b[16], 'a');
  EXPECT_EQ(b[18], 0);
}

// A big-endian message: the same scan written by hand in CDR_BE.
TEST(Ros2Messages, ABigEndianScanIsRead) {
  std::vector<std::uint8_t> b = {0, 0, 0, 0};
  const auto u32 = [&](std::uint32_t v) {
    for (int i = 3; i >= 0; --i) b.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  };
  const auto f32 = [&](float f) {
    std::uint32_t v = 0;
    std::memcpy(&v, &f, 4);
    u32(v);
  };
  u32(7);  // sec
  u32(8);  // nanosec
  u32(2);  // "x\0"
  b.push_back('x');
  b.push_back(0);
  b.push_back(0);  // Padding to 4.
  b.push_back(0);
  f32(-1.0F);
  f32(1.0F);
  f32(0.5F);
  f32(0.0F);
  f32(0.1F);
  f32(0.1F);
  f32(10.0F);
  u32(2);
  f32(3.0F);
  f32(4.0F);
  u32(0);
  const ScanMessage d = decode_ros2_scan(b.data(), b.size());
  EXPECT_EQ(d.header.stamp, (Stamp{7, 8}));
  EXPECT_EQ(d.header.frame_id, "x");
  EXPECT_EQ(d.scan.range_max_m, 10.0F);
  EXPECT_EQ(d.scan.ranges_m, (std::vector<float>{3.0F, 4.0F}));
  EXPECT_TRUE(d.scan.intensities.empty());
}

TEST(Ros2Messages, OdometryTransformsJointStatesAndImuComeBack) {
  OdometryMessage o = odometry_message(12.5, "odom", "base_link", {1.0, -2.0, 0.7}, 0.4, -0.1);
  const OdometryMessage od = [&] {
    const auto b = encode_ros2(o);
    return decode_ros2_odometry(b.data(), b.size());
  }();
  EXPECT_EQ(od.header.stamp, o.header.stamp);
  EXPECT_EQ(od.header.frame_id, "odom");
  EXPECT_EQ(od.child_frame_id, "base_link");
  EXPECT_NEAR(od.pose.x_m, 1.0, 1e-12);
  EXPECT_NEAR(od.pose.y_m, -2.0, 1e-12);
  EXPECT_NEAR(od.pose.yaw_rad, 0.7, 1e-12);
  EXPECT_DOUBLE_EQ(od.v_mps, 0.4);
  EXPECT_DOUBLE_EQ(od.w_radps, -0.1);

  // A fused estimate: its lateral speed and variances go into the message and come back.
  OdometryEstimate e;
  e.t_s = 3.5;
  e.x_m = 1.0;
  e.v_mps = 0.5;
  e.lateral_velocity_mps = 0.125;
  e.omega_radps = 0.25;
  e.x_variance_m2 = 0.01;
  e.y_variance_m2 = 0.02;
  e.yaw_variance_rad2 = 0.03;
  e.v_variance_m2ps2 = 0.04;  // omega's stays unknown (NaN): published as 0.
  const OdometryMessage oe = odometry_message(e, "odom", "base_link");
  const OdometryMessage ode = [&] {
    const auto b = encode_ros2(oe);
    return decode_ros2_odometry(b.data(), b.size());
  }();
  EXPECT_EQ(ode.vy_mps, 0.125);
  EXPECT_EQ(ode.w_radps, 0.25);
  std::array<double, 36> pose{}, twist{};
  pose[0] = 0.01;   // x
  pose[7] = 0.02;   // y
  pose[35] = 0.03;  // yaw
  twist[0] = 0.04;  // forward speed
  EXPECT_EQ(ode.pose_covariance, pose);
  EXPECT_EQ(ode.twist_covariance, twist);

  TransformsMessage t;
  t.transforms.push_back({{3, 4}, "odom", "base_link", {0.1, 0.2, -0.3}});
  t.transforms.push_back({{3, 5}, "base_link", "laser", {0.2, -0.1, 0.3}});
  const auto tb = encode_ros2(t);
  const TransformsMessage td = decode_ros2_transforms(tb.data(), tb.size());
  ASSERT_EQ(td.transforms.size(), 2U);
  EXPECT_EQ(td.transforms[1].stamp, (Stamp{3, 5}));
  EXPECT_EQ(td.transforms[1].parent, "base_link");
  EXPECT_EQ(td.transforms[1].child, "laser");
  EXPECT_NEAR(td.transforms[1].child_in_parent.yaw_rad, 0.3, 1e-12);

  JointStateMessage j;
  j.header.stamp = {9, 1};
  j.header.frame_id = "base";
  j.names = {"left", "right"};
  j.positions = {1.0, 2.0};
  j.velocities = {0.5, -0.5};
  const auto jb = encode_ros2(j);
  const JointStateMessage jd = decode_ros2_joint_state(jb.data(), jb.size());
  EXPECT_EQ(jd.names, j.names);
  EXPECT_EQ(jd.positions, j.positions);
  EXPECT_EQ(jd.velocities, j.velocities);

  for (const bool orientation : {true, false}) {
    ImuMessage i;
    i.header.stamp = {1, 2};
    i.angular_velocity_radps = {0.1, 0.2, 0.3};
    i.has_orientation = orientation;
    const auto ib = encode_ros2(i);
    const ImuMessage id = decode_ros2_imu(ib.data(), ib.size());
    EXPECT_EQ(id.has_orientation, orientation);
    EXPECT_EQ(id.angular_velocity_radps, i.angular_velocity_radps);
  }
}

TEST(Ros2Messages, ACutOrLyingMessageIsAnErrorNeverACrash) {
  const std::vector<std::uint8_t> b = encode_ros2(a_scan());
  for (std::size_t n = 0; n < b.size(); ++n) {
    EXPECT_THROW((void)decode_ros2_scan(b.data(), n), CdrError) << n << " bytes";
  }
  // A sequence that claims 2^32-1 floats.
  std::vector<std::uint8_t> lying = b;
  const std::size_t ranges_at = 4 + 8 + 4 + 6 + 2 + 28;  // The ranges' count.
  for (std::size_t k = 0; k < 4; ++k) lying[ranges_at + k] = 0xff;
  try {
    (void)decode_ros2_scan(lying.data(), lying.size());
    FAIL() << "no error";
  } catch (const CdrError& e) {
    EXPECT_NE(std::string(e.what()).find("longer than the message"), std::string::npos) << e.what();
  }
  std::vector<std::uint8_t> xcdr2 = b;
  xcdr2[1] = 7;
  EXPECT_THROW((void)decode_ros2_scan(xcdr2.data(), xcdr2.size()), CdrError);
}

TEST(Ros2Messages, TypesAndDefinitionsFollowRos2) {
  EXPECT_STREQ(ros2_type_name(MessageKind::kLaserScan), "sensor_msgs/msg/LaserScan");
  EXPECT_EQ(ros2_message_kind("tf2_msgs/msg/TFMessage"), MessageKind::kTransforms);
  EXPECT_EQ(ros2_message_kind("std_msgs/msg/String"), MessageKind::kOther);
  EXPECT_EQ(ros2_type_name(MessageKind::kOther), nullptr);
  const std::string& d = ros2_definition(MessageKind::kOdometry);
  EXPECT_EQ(d.rfind("std_msgs/Header header\n", 0), 0U);
  EXPECT_NE(d.find("\n\n" + std::string(80, '=') + "\nMSG: geometry_msgs/PoseWithCovariance\n"),
            std::string::npos);
  EXPECT_EQ(ros2_clamped({5000000000LL, 3}), (Stamp{2147483647, 999999999}));
}

}  // namespace
}  // namespace dispel::io
