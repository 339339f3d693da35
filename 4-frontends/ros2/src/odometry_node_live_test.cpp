// dispel-ros2 odometry, live over DDS on the loopback: the test, a DDS participant of its own,
// plays robot_localization's Husky recording (test1.bag: wheel odometry at 10 Hz, an IMU at
// 30 Hz mounted with its y axis up) the way ROS 2 drivers publish them, and receives the node's
// nav_msgs/Odometry; it must be what the shared runner (the one `dispel odom` runs) makes of the
// same measurements, estimate for estimate, byte for byte.
//
// No scheduling luck: the node releases an estimate once both sources are past it by
// reorder_window_s in stamp time, and source_timeout_s is set beyond the test's length, so what
// it releases depends on the stamps alone, never on when messages came. The test sends one
// second of the recording at a time and waits for the estimates the runner releases for it
// before it sends the next, so the node's readers (best effort, keep last 100) never hold more
// than about two seconds (80 messages). The waits only bound how long a failure takes to show.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>

#include "dispel/io/odometry_inputs.hpp"
#include "dispel/io/ros2_messages.hpp"
#include "dispel/jobs/job.hpp"
#include "dispel/ros2/dds.hpp"
#include "dispel/ros2/odometry_node.hpp"
#include "live_test_support.hpp"
#include "node_process.hpp"
#include "test_files.hpp"

namespace dispel::ros2 {
namespace {

using live_test::eventually;
using live_test::kLoopback;
using live_test::NodeProcess;

TEST(Ros2OdometryNodeLive, FusesTheHuskyRecordingLikeTheSharedRunner) {
  ::setenv("CYCLONEDDS_URI", kLoopback, 1);
  // Domains 10-49: below Linux's ephemeral ports; topics and node of this process alone.
  const int domain = 10 + static_cast<int>(::getpid() % 40);
  const std::string own = "_p" + std::to_string(::getpid());
  const std::string wheels_topic = "/wheels" + own, imu_topic = "/imu" + own;
  const std::string odometry_topic = "/odometry" + own;
  const std::string params =
      "/**:\n  ros__parameters:\n    wheel_message: odometry\n"
      "    wheels_topic: " +
      wheels_topic + "\n    imu_topic: " + imu_topic + "\n    odometry_topic: " + odometry_topic +
      "\n    source_timeout_s: 100000\n    ros_distro: humble\n"
      "    odometry: {imu_yaw_axis: y, track_width_m: 0.555}\n";
  const OdometryNodeSettings settings =
      parse_odometry_node_parameters(params, "params", "dispel_odometry");

  // The recording's wheels and IMU, in time order.
  struct Measurement {
    bool is_imu = false;
    io::OdometryMessage wheels;
    io::ImuMessage imu;
    double t_s = 0.0;
  };
  std::vector<Measurement> recorded;
  auto reader = jobs::open_recording(test::source_path("data/robot_localization/test1.bag"));
  reader->read({"/husky_velocity_controller/odom", "/imu/data"}, [&](const io::RecordedMessage& m) {
    Measurement measurement;
    if (auto o = m.odometry()) {
      measurement.wheels = *o;
      measurement.t_s = o->header.stamp.seconds();
    } else if (auto i = m.imu()) {
      measurement.is_imu = true;
      measurement.imu = *i;
      measurement.t_s = i->header.stamp.seconds();
    } else {
      return;
    }
    recorded.push_back(std::move(measurement));
  });
  ASSERT_GT(recorded.size(), 10000u);

  const std::string node_name = "dispel_odometry" + own;
  NodeProcess node("odometry", params, node_name, domain);
  Participant test(domain);
  const Qos driver_qos = Qos::sensor_data();
  Writer wheels(test, wheels_topic, "nav_msgs/msg/Odometry", driver_qos);
  Writer imu(test, imu_topic, "sensor_msgs/msg/Imu", driver_qos);
  Reader odometry(test, odometry_topic, "nav_msgs/msg/Odometry",
                  {Qos::Reliability::kReliable, Qos::Durability::kVolatile, 100000});
  ASSERT_TRUE(eventually([&] {
    const std::string log = node.log();
    return wheels.matches().current == 1 && imu.matches().current == 1 &&
           odometry.matches().current == 1 &&
           log.find(wheels_topic + ": 1 publishers matched") != std::string::npos &&
           log.find(imu_topic + ": 1 publishers matched") != std::string::npos &&
           log.find(odometry_topic + ": 1 subscribers matched") != std::string::npos;
  })) << node.log();

  pipeline::OdometryRunner reference(settings.odometry.filter, settings.reorder_window_s);
  std::vector<OdometryEstimate> want;
  std::vector<std::vector<std::uint8_t>> got;
  std::size_t next = 0;
  while (next < recorded.size()) {
    const double end_s = recorded[next].t_s + 1.0;  // One second of the recording.
    for (; next < recorded.size() && recorded[next].t_s < end_s; ++next) {
      const Measurement& m = recorded[next];
      if (m.is_imu) {
        imu.write(io::encode_ros2(m.imu));
        reference.add_imu(io::stamp_or(m.imu.header.stamp, {}),
                          io::yaw_rate(m.imu, settings.odometry));
      } else {
        wheels.write(io::encode_ros2(m.wheels));
        const io::WheelSpeeds w =
            io::wheel_speeds(m.wheels, settings.odometry.filter.track_width_m, {});
        reference.add_wheels(w.t_s, w.left_mps, w.right_mps);
      }
      for (const OdometryEstimate& e : reference.release()) want.push_back(e);
    }
    ASSERT_TRUE(eventually([&] {
      for (auto& b : odometry.take(0.0)) got.push_back(std::move(b));
      return got.size() >= want.size();
    })) << "at "
        << end_s << " s: " << got.size() << " estimates of " << want.size() << "\n"
        << node.log();
  }
  ASSERT_GT(want.size(), 10000u);
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t k = 0; k < want.size(); ++k) {
    const io::OdometryMessage m = io::odometry_message(want[k], "odom", "base_link");
    ASSERT_EQ(got[k], io::encode_ros2(m)) << "estimate " << k;
  }
  EXPECT_EQ(node.stop(), 0) << node.log();
  EXPECT_NE(node.log().find(std::to_string(want.size()) + " estimates published"),
            std::string::npos)
      << node.log();
}

}  // namespace
}  // namespace dispel::ros2
