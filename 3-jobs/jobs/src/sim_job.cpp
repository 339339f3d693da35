#include "dispel/jobs/sim_job.hpp"

#include <limits>

namespace dispel::jobs {
void write_simulation(const sim::SimulationOutput& run, const sim::Scenario& scenario,
                      const std::string& path, const std::atomic<bool>* cancel) {
  check_cancelled(cancel);
  const std::unique_ptr<io::RecordingWriter> out = create_recording(path, Compression::kLz4);
  as_job([&] {
    const double t0 = run.sensors.empty() ? 0.0 : run.sensors.front().stamp_s;
    const io::Stamp start = io::Stamp::from_seconds(t0);
    out->write("/tf_static", start,
               io::TransformsMessage{{{start, "base_link", "laser", scenario.robot.laser_mount}}});

    std::size_t next_scan = 0;
    const auto write_scans_until = [&](double t) {
      for (; next_scan < run.scans.size() && run.scans[next_scan].scan.stamp_s <= t; ++next_scan) {
        const sim::ScanFrame& f = run.scans[next_scan];
        io::ScanMessage msg = io::scan_message(f.scan, "laser");
        msg.scan_time = static_cast<float>(1.0 / scenario.lidar.rate_hz);
        out->write("/scan", msg.header.stamp, msg);
        msg.scan.intensities.resize(f.truth.size());
        for (std::size_t i = 0; i < f.truth.size(); ++i) {
          msg.scan.intensities[i] = static_cast<float>(f.truth[i]);
        }
        out->write("/scan_truth", msg.header.stamp, msg);
        for (std::size_t i = 0; i < f.actor.size(); ++i) {
          msg.scan.intensities[i] = static_cast<float>(f.actor[i]);
        }
        out->write("/scan_truth_actor", msg.header.stamp, msg);
      }
    };
    for (const sim::SensorSample& s : run.sensors) {
      check_cancelled(cancel);
      write_scans_until(s.stamp_s);
      const io::Stamp t = io::Stamp::from_seconds(s.stamp_s);
      out->write("/odom", t,
                 io::odometry_message(s.stamp_s, "odom", "base_link", s.odom_pose, s.odom_v_mps,
                                      s.odom_w_radps));
      out->write("/ground_truth", t,
                 io::odometry_message(s.stamp_s, "map", "base_link", s.true_pose, s.true_v_mps,
                                      s.true_w_radps));
      io::JointStateMessage wheels;
      wheels.header.stamp = t;
      wheels.names = {"left_wheel", "right_wheel"};
      wheels.velocities = {s.wheel_left_mps, s.wheel_right_mps};
      out->write("/wheels", t, wheels);
      io::ImuMessage imu;
      imu.header.stamp = t;
      imu.header.frame_id = "base_link";
      imu.angular_velocity_radps.z() = s.imu_yaw_rate_radps;
      out->write("/imu", t, imu);
    }
    write_scans_until(std::numeric_limits<double>::infinity());
    out->finish();
  });
}

}  // namespace dispel::jobs
