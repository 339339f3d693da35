// dispel::slam: particle-filter localisation over a ROS 1 bag in a known map. No MRPT here: it
// lives in pf_localization_engine.cpp.

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "slam_input.hpp"
#include "dispel/core/pose_buffer.hpp"
#include "dispel/jobs/job.hpp"
#include "dispel/slam/localization.hpp"

namespace dispel::slam {
namespace {

using jobs::JobError;

eval::TrajectoryPoint point(double t, const Pose2& p) { return {t, p.x_m, p.y_m, p.yaw_rad}; }

void require(bool ok, const char* name, double value, const char* rule) {
  if (ok) return;
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  throw JobError(std::string(name) + " = " + text + ": " + rule);
}

}  // namespace

void ParticleFilterOptions::validate() const {
  const auto non_negative = [](double v) { return std::isfinite(v) && v >= 0.0; };
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  require(particles >= 1 && particles <= 10000000, "particles", particles, "must be 1 to 10000000");
  require(
      std::isfinite(resample_below_ess) && resample_below_ess >= 0.0 && resample_below_ess <= 1.0,
      "resample_below_ess", resample_below_ess, "must be in [0, 1]");
  require(non_negative(initial_std_x_m), "initial_std_x_m", initial_std_x_m, "must be >= 0");
  require(non_negative(initial_std_y_m), "initial_std_y_m", initial_std_y_m, "must be >= 0");
  require(non_negative(initial_std_yaw_rad), "initial_std_yaw_rad", initial_std_yaw_rad,
          "must be >= 0");
  require(non_negative(motion_std_xy_m), "motion_std_xy_m", motion_std_xy_m, "must be >= 0");
  require(non_negative(motion_std_yaw_rad), "motion_std_yaw_rad", motion_std_yaw_rad,
          "must be >= 0");
  require(non_negative(motion_std_xy_per_m), "motion_std_xy_per_m", motion_std_xy_per_m,
          "must be >= 0");
  require(non_negative(motion_std_xy_per_rad), "motion_std_xy_per_rad", motion_std_xy_per_rad,
          "must be >= 0");
  require(non_negative(motion_std_yaw_per_m), "motion_std_yaw_per_m", motion_std_yaw_per_m,
          "must be >= 0");
  require(non_negative(motion_std_yaw_per_rad), "motion_std_yaw_per_rad", motion_std_yaw_per_rad,
          "must be >= 0");
  require(positive(likelihood_std_m), "likelihood_std_m", likelihood_std_m, "must be > 0");
  require(likelihood_decimation >= 1, "likelihood_decimation", likelihood_decimation,
          "must be >= 1");
  require(positive(likelihood_max_distance_m), "likelihood_max_distance_m",
          likelihood_max_distance_m, "must be > 0");
}

LocalizationResult run_pf_localization(const LocalizationOptions& o) {
  o.filter.validate();
  jobs::check_input_file(o.input);
  GridMap map;
  if (o.map) {
    map = *o.map;
    map.validate();
  } else if (!o.map_yaml.empty()) {
    map = read_map_yaml(o.map_yaml);
  } else {
    throw JobError("no map: set map_yaml (a map_server map) or map");
  }
  if (o.initial_pose &&
      (!std::isfinite(o.initial_pose->x_m) || !std::isfinite(o.initial_pose->y_m) ||
       !std::isfinite(o.initial_pose->yaw_rad))) {
    throw JobError("initial pose is not finite");
  }

  detail::SlamInput in =
      detail::open_slam_input(o.input, o.scan_topic, o.odom_topic, o.odom_tolerance_s);
  const io::RecordingMotion& motion = in.motion;
  LocalizationResult result;
  result.odometry_refused = motion.poses_refused;
  result.scan_topic = motion.scan_topic;

  // Made at the first scan used, where the initial pose holds.
  std::unique_ptr<PfLocalizer> localizer;
  detail::for_each_scan(in, [&](const LaserScan& scan) {
    ++result.scans;
    Pose2 odom_pose;
    if (motion.base_poses.lookup(scan.stamp_s, odom_pose) != PoseLookup::kOk) {
      ++result.scans_no_odometry;
      return;
    }
    const bool first = !localizer;
    if (first) {
      localizer = std::make_unique<PfLocalizer>(map, o.filter, o.initial_pose.value_or(odom_pose));
    }
    const std::optional<PoseEstimate> estimate =
        localizer->process(scan, odom_pose, motion.mount, &result.beams_invalid);
    if (!estimate) {
      ++result.scans_bad;
      if (first) localizer.reset();
      return;
    }
    ++result.scans_used;
    result.trajectory.push_back(point(scan.stamp_s, estimate->pose));
    result.odometry.push_back(point(scan.stamp_s, odom_pose));
    result.position_std_m.push_back(estimate->position_std_m);
    result.yaw_std_rad.push_back(estimate->yaw_std_rad);
  });
  if (result.scans_used == 0) {
    throw JobError(o.input + ": no scan on " + result.scan_topic + " has odometry on " +
                   o.odom_topic + " at its stamp");
  }
  return result;
}

}  // namespace dispel::slam
