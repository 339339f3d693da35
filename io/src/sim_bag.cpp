#include "dispel/io/sim_bag.hpp"

#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/JointState.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_msgs/TFMessage.h>

#include <stdexcept>

#include "dispel/io/atomic_file.hpp"
#include "dispel/io/ros_convert.hpp"

namespace dispel::io {
void write_simulation_bag(const sim::SimulationOutput& run, const sim::Scenario& scenario,
                          const std::string& path) {
  AtomicFile file(path);
  try {
    rosbag::Bag bag(file.temp_path(), rosbag::bagmode::Write);
    bag.setCompression(rosbag::compression::LZ4);
    const double t0 = run.sensors.empty() ? 0.0 : run.sensors.front().stamp_s;
    tf2_msgs::TFMessage tf;
    geometry_msgs::TransformStamped mount;
    mount.header.stamp = to_ros_time(t0);
    mount.header.frame_id = "base_link";
    mount.child_frame_id = "laser";
    mount.transform.translation.x = scenario.robot.laser_mount.x_m;
    mount.transform.translation.y = scenario.robot.laser_mount.y_m;
    mount.transform.rotation = quaternion_from_yaw(scenario.robot.laser_mount.yaw_rad);
    tf.transforms = {mount};
    bag.write("/tf_static", mount.header.stamp, tf);

    std::size_t next_scan = 0;
    const auto write_scans_until = [&](double t) {
      for (; next_scan < run.scans.size() && run.scans[next_scan].scan.stamp_s <= t; ++next_scan) {
        const sim::ScanFrame& f = run.scans[next_scan];
        sensor_msgs::LaserScan msg = to_ros(f.scan, "laser");
        msg.scan_time = static_cast<float>(1.0 / scenario.lidar.rate_hz);
        bag.write("/scan", msg.header.stamp, msg);
        msg.intensities.resize(f.truth.size());
        for (std::size_t i = 0; i < f.truth.size(); ++i) {
          msg.intensities[i] = static_cast<float>(f.truth[i]);
        }
        bag.write("/scan_truth", msg.header.stamp, msg);
        for (std::size_t i = 0; i < f.actor.size(); ++i) {
          msg.intensities[i] = static_cast<float>(f.actor[i]);
        }
        bag.write("/scan_truth_actor", msg.header.stamp, msg);
      }
    };
    for (const sim::SensorSample& s : run.sensors) {
      write_scans_until(s.stamp_s);
      const ros::Time t = to_ros_time(s.stamp_s);
      bag.write("/odom", t,
                to_ros_odometry(s.stamp_s, "odom", "base_link", s.odom_pose, s.odom_v_mps,
                                s.odom_w_radps));
      bag.write("/ground_truth", t,
                to_ros_odometry(s.stamp_s, "map", "base_link", s.true_pose, s.true_v_mps,
                                s.true_w_radps));
      sensor_msgs::JointState wheels;
      wheels.header.stamp = t;
      wheels.name = {"left_wheel", "right_wheel"};
      wheels.velocity = {s.wheel_left_mps, s.wheel_right_mps};
      bag.write("/wheels", t, wheels);
      sensor_msgs::Imu imu;
      imu.header.stamp = t;
      imu.header.frame_id = "base_link";
      imu.orientation_covariance[0] = -1.0;  // No orientation (REP 145).
      imu.angular_velocity.z = s.imu_yaw_rate_radps;
      bag.write("/imu", t, imu);
    }
    write_scans_until(std::numeric_limits<double>::infinity());
    bag.close();
  } catch (const std::exception& e) {
    throw std::runtime_error(path + ": cannot write the bag (" + e.what() + ")");
  }
  file.commit();
}

}  // namespace dispel::io
