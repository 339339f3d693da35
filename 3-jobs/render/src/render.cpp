// dispel render: the checks, the recording's first pass (the frame the views are drawn in), and
// the view asked for (map_view.cpp, scan_view.cpp).
#include "dispel/render/render.hpp"

#include "dispel/io/config_yaml.hpp"
#include "dispel/io/recording_motion.hpp"
#include "dispel/io/text.hpp"
#include "dispel/jobs/job.hpp"
#include "layout.hpp"

namespace dispel::render {

using jobs::JobError;

RenderResult render_bag(const RenderOptions& o, const std::atomic<bool>* cancel) {
  if (o.view != "map" && o.view != "scan") {
    throw JobError("unknown view " + io::quote(o.view) + " (use --view map or --view scan)");
  }
  if (o.frame != "odom" && o.frame != "truth") {
    throw JobError("unknown frame " + io::quote(o.frame) + " (use --frame odom or --frame truth)");
  }
  if (o.width_px < 200 || o.height_px < 200 || o.width_px > 10000 || o.height_px > 10000) {
    throw JobError("picture size " + std::to_string(o.width_px) + "x" +
                   std::to_string(o.height_px) + " out of range (200 to 10000 pixels each way)");
  }
  if (o.scan_index < 0) {
    throw JobError("scan index " + std::to_string(o.scan_index) + " out of range (from 0)");
  }
  jobs::check_input_file(o.input);
  if (o.output.empty()) throw JobError("no output file given (-o OUT.png or OUT.svg)");
  { Canvas check(o.output, 200, 200); }  // Fails now on a bad extension, before any reading.
  if (o.config_path) jobs::as_job([&] { return io::load_filter_config(*o.config_path); });

  const std::unique_ptr<io::RecordingReader> in = jobs::open_recording(o.input);
  detail::Scene scene;
  scene.recording = in.get();
  scene.begin_s = in->begin_time().seconds();
  scene.end_s = in->end_time().seconds();
  io::MotionQuery query;
  query.scan_topic = o.scan_topic;
  query.pose_tolerance_s = o.pose_tolerance_s;
  query.missing_scan_hint = "; choose one with --scan-topic";
  query.missing_mount_hint = "; record the sensor mount, or use --static-sensor";
  if (o.static_sensor) {
    query.pose_topic.reset();
  } else if (o.frame == "truth") {
    scene.pose_topic = o.truth_topic;
    query.pose_topic = o.truth_topic;
    query.default_fixed_frame = "map";
    query.missing_pose_hint = "; --frame truth draws the ground truth of dispel sim";
  } else {
    scene.pose_topic = o.odom_topic;
    query.pose_topic = o.odom_topic;
    query.missing_pose_hint =
        "; choose one with --odom-topic, or use --static-sensor for a sensor that does not move";
  }
  if (o.view == "scan" && in->topics().has(o.scan_topic, io::MessageKind::kLaserScan)) {
    const std::int64_t count = in->topics().messages(o.scan_topic);
    if (o.scan_index >= count) {
      throw JobError(o.input + ": scan index " + std::to_string(o.scan_index) +
                     " out of range: " + std::to_string(count) + " scans on " + o.scan_topic +
                     " (0 to " + std::to_string(count - 1) + ")");
    }
  }
  scene.motion = jobs::as_job(
      [&] { return io::read_motion(*in, query, [&] { jobs::check_cancelled(cancel); }); });
  if (scene.motion.static_sensor) {
    scene.description = "static sensor (identity pose)";
  } else {
    const std::string laser =
        scene.motion.laser_frame.empty() ? scene.motion.base_frame : scene.motion.laser_frame;
    scene.description = std::string(o.frame == "truth" ? "ground truth " : "odometry ") +
                        scene.pose_topic + " + mount " + scene.motion.base_frame + " \u2192 " +
                        laser;
  }
  return o.view == "map" ? detail::render_map(scene, o, cancel)
                         : detail::render_scan(scene, o, cancel);
}

}  // namespace dispel::render
