// Internal to dispel::slam: the shared first pass over a recording, and its scans.

#include "slam_input.hpp"

#include "dispel/jobs/job.hpp"

namespace dispel::slam::detail {

SlamInput open_slam_input(const std::string& path, const std::string& scan_topic,
                          const std::string& odom_topic, double odom_tolerance_s) {
  SlamInput in;
  in.recording = jobs::open_recording(path);
  io::MotionQuery query;
  query.scan_topic = scan_topic;
  query.pose_topic = odom_topic;
  query.pose_tolerance_s = odom_tolerance_s;
  query.missing_mount_hint = "; record the sensor mount";
  in.motion = jobs::as_job([&] { return io::read_motion(*in.recording, query); });
  return in;
}

void for_each_scan(SlamInput& input, const std::function<void(const LaserScan&)>& visit) {
  jobs::as_job([&] {
    input.recording->read({input.motion.scan_topic}, [&](const io::RecordedMessage& m) {
      if (const auto scan = m.scan()) visit(scan->scan);
    });
  });
}

}  // namespace dispel::slam::detail
