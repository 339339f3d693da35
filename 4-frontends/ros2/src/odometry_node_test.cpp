// The ROS 2 odometry node's work without DDS: its parameter file, and wheels and IMU through the
// shared runner, as `dispel odom` takes them.
#include "dispel/ros2/odometry_node.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "dispel/io/errors.hpp"
#include "test_files.hpp"

namespace dispel::ros2 {
namespace {

std::string parse_error(const std::string& yaml) {
  try {
    parse_odometry_node_parameters(yaml, "p.yaml", "dispel_odometry");
  } catch (const io::ConfigError& e) {
    return e.what();
  }
  return "parsed";
}

TEST(Ros2OdometryNodeParameters, NodeKeysTheFusionsSectionAndTheFiltersKeysIgnored) {
  const OdometryNodeSettings s = parse_odometry_node_parameters(
      "dispel_odometry:\n  ros__parameters:\n    wheel_message: odometry\n"
      "    wheels_topic: husky/odom\n    imu_topic: /imu/data\n    publish_tf: true\n"
      "    odometry: {imu_yaw_axis: y, track_width_m: 0.555}\n"
      "    tracking: {match_distance_m: 0.3}\n",
      "p.yaml", "dispel_odometry");
  EXPECT_TRUE(s.wheels_as_odometry);
  EXPECT_EQ(s.wheels_topic, "/husky/odom");
  EXPECT_EQ(s.imu_topic, "/imu/data");
  EXPECT_TRUE(s.publish_tf);
  EXPECT_EQ(s.odometry.imu_yaw_axis, 1);
  EXPECT_EQ(s.odometry.filter.track_width_m, 0.555);

  EXPECT_EQ(parse_error("base_frame: odom\n"),
            "p.yaml: odom_frame and base_frame must be two different frames (got 'odom' and "
            "'odom')");
  EXPECT_EQ(parse_error("wheel_message: twist\n"),
            "p.yaml: wheel_message must be joint_state or odometry (got 'twist')");
  EXPECT_EQ(parse_error("source_timeout_s: 0\n"),
            "p.yaml: source_timeout_s must be a finite number >= 0.001 (got '0')");
  EXPECT_EQ(parse_error("scan_topic_typo: 1\n"),
            "p.yaml: 'scan_topic_typo' is not a parameter of dispel_odometry");
  EXPECT_NE(parse_error("odometry: {no_such: 1}\n").find("no_such"), std::string::npos);
}

TEST(Ros2OdometryNodeParameters, TheShippedParameterFileStatesTheDefaults) {
  const std::string path = test::source_path("4-frontends/ros2/config/dispel_odometry.yaml");
  const OdometryNodeSettings s =
      parse_odometry_node_parameters(test::read_bytes(path), path, "dispel_odometry");
  const OdometryNodeSettings d;
  EXPECT_EQ(s.wheels_as_odometry, d.wheels_as_odometry);
  EXPECT_EQ(s.wheels_topic, d.wheels_topic);
  EXPECT_EQ(s.imu_topic, d.imu_topic);
  EXPECT_EQ(s.odometry_topic, d.odometry_topic);
  EXPECT_EQ(s.odom_frame, d.odom_frame);
  EXPECT_EQ(s.base_frame, d.base_frame);
  EXPECT_EQ(s.publish_tf, d.publish_tf);
  EXPECT_EQ(s.reorder_window_s, d.reorder_window_s);
  EXPECT_EQ(s.source_timeout_s, d.source_timeout_s);
  EXPECT_EQ(s.queue_size, d.queue_size);
  EXPECT_EQ(s.use_sim_time, d.use_sim_time);
  EXPECT_EQ(s.ros_distro, d.ros_distro);
}

io::JointStateMessage wheels(double t, double left, double right) {
  io::JointStateMessage m;
  m.header.stamp = io::Stamp::from_seconds(t);
  m.names = {"left_wheel_joint", "right_wheel_joint"};
  m.velocities = {left, right};
  return m;
}

io::ImuMessage gyro(double t, double yaw_rate) {
  io::ImuMessage m;
  m.header.stamp = io::Stamp::from_seconds(t);
  m.angular_velocity_radps.z() = yaw_rate;
  return m;
}

// Straight ahead at 1 m/s for 2 s, wheels at 50 Hz and the IMU at 100 Hz: the estimates are the
// runner's for the same measurements, released as both sources pass them, in odom -> base_link.
TEST(Ros2OdometryNodeCore, WheelsAndImuThroughTheSharedRunner) {
  OdometryNodeSettings s;
  s.source_timeout_s = 1e6;  // Released by stamps alone.
  OdometryNodeCore core(s);
  pipeline::OdometryRunner reference(s.odometry.filter, s.reorder_window_s);
  std::vector<OdometryNodeOutput> out;
  std::vector<OdometryEstimate> want;
  const auto take = [](auto& into, auto from) {
    into.insert(into.end(), from.begin(), from.end());
  };
  for (int k = 0; k < 200; ++k) {
    const double t = 100.0 + 0.01 * k;
    take(out, core.imu(gyro(t, 0.0), 0.0, {}));
    reference.add_imu(t, 0.0);
    take(want, reference.release());
    if (k % 2 == 0) {
      take(out, core.joint_state(wheels(t, 1.0, 1.0), 0.0, {}));
      reference.add_wheels(t, 1.0, 1.0);
      take(want, reference.release());
    }
  }
  ASSERT_GT(want.size(), 150u);
  ASSERT_EQ(out.size(), want.size());
  for (std::size_t k = 0; k < out.size(); ++k) {
    EXPECT_EQ(out[k].odometry.pose.x_m, want[k].x_m) << k;
    EXPECT_EQ(out[k].odometry.v_mps, want[k].v_mps) << k;
    EXPECT_EQ(out[k].odometry.header.frame_id, "odom");
    EXPECT_EQ(out[k].odometry.child_frame_id, "base_link");
    ASSERT_EQ(out[k].transform.transforms.size(), 1u);
    EXPECT_EQ(out[k].transform.transforms[0].child_in_parent.x_m, want[k].x_m);
  }
  EXPECT_NEAR(out.back().odometry.pose.x_m, 2.0, 0.1);
  EXPECT_EQ(core.published(), static_cast<std::int64_t>(out.size()));
  // A JointState without both wheels is counted, not fused.
  EXPECT_TRUE(core.joint_state(io::JointStateMessage{}, 0.0, {}).empty());
  EXPECT_EQ(core.malformed(), 1);
}

}  // namespace
}  // namespace dispel::ros2
