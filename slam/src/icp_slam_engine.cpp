// The MRPT side of dispel::slam: CMetricMapBuilderICP fed one scan and one odometry increment at a
// time. The only file that includes MRPT.

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/core/Clock.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/maps/CPointsMap.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/poses/CPose3DPDF.h>
#include <mrpt/slam/CMetricMapBuilderICP.h>

#include <cmath>
#include <exception>
#include <string>

#include "dispel/io/filter_job.hpp"
#include "dispel/slam/icp_slam.hpp"

namespace dispel::slam {
namespace {

// MRPT's exceptions carry a call stack over many lines: keep the first line with text.
std::string first_line(const std::exception& e) {
  const std::string s = e.what();
  std::size_t start = 0;
  while (start < s.size()) {
    std::size_t end = s.find('\n', start);
    if (end == std::string::npos) end = s.size();
    const std::string line = s.substr(start, end - start);
    if (line.find_first_not_of(" \t\r") != std::string::npos) return line;
    start = end + 1;
  }
  return "unknown error";
}

bool finite_non_negative(double v) { return std::isfinite(v) && v >= 0.0; }

}  // namespace

struct IcpSlamEngine::Impl {
  mrpt::slam::CMetricMapBuilderICP builder;
  bool started = false;
  Pose2 first_odometry;  // The engine's frame is the robot at the first scan.
  Pose2 last_odometry;
};

IcpSlamEngine::IcpSlamEngine(const std::string& config) : impl_(std::make_unique<Impl>()) {
  auto& b = impl_->builder;
  b.setVerbosityLevel(mrpt::system::LVL_ERROR);
  try {
    const mrpt::config::CConfigFileMemory ini(config);
    b.ICP_options.loadFromConfigFile(ini, "MappingApplication");
    b.ICP_params.loadFromConfigFile(ini, "ICP");
  } catch (const std::exception& e) {
    throw io::JobError("SLAM engine configuration: " + first_line(e));
  }
  const auto& o = b.ICP_options;
  if (!finite_non_negative(o.insertionLinDistance) ||
      !finite_non_negative(o.insertionAngDistance) ||
      !finite_non_negative(o.localizationLinDistance) ||
      !finite_non_negative(o.localizationAngDistance) || !std::isfinite(o.minICPgoodnessToAccept)) {
    throw io::JobError(
        "SLAM engine configuration: insertion and localization distances must be finite and >= 0");
  }
  // Removed beams must never clear map cells (an occupancy grid would otherwise treat an invalid
  // range as free space up to the maximum range).
  for (auto& def : b.ICP_options.mapInitializers) {
    if (auto* grid = dynamic_cast<mrpt::maps::COccupancyGridMap2D::TMapDefinition*>(def.get())) {
      grid->insertionOpts.considerInvalidRangesAsFreeSpace = false;
    }
  }
  try {
    b.initialize();
  } catch (const std::exception& e) {
    throw io::JobError("SLAM engine configuration: " + first_line(e));
  }
  if (!b.getCurrentlyBuiltMetricMap()->mapByClass<mrpt::maps::CPointsMap>()) {
    throw io::JobError(
        "SLAM engine configuration: no points map (set pointsMap_count=1 in "
        "[MappingApplication]); ICP-SLAM matches against one");
  }
}

IcpSlamEngine::~IcpSlamEngine() = default;

std::optional<Pose2> IcpSlamEngine::process(const LaserScan& scan, const Pose2& odometry,
                                            const Pose2& mount, std::int64_t* invalid_beams) {
  const std::size_t n = scan.size();
  if (n < 2 || !(scan.angle_increment_rad > 0.0) || !std::isfinite(scan.angle_min_rad) ||
      !std::isfinite(scan.stamp_s)) {
    return std::nullopt;
  }
  Impl& m = *impl_;

  // MRPT's beams are spread evenly over `aperture`, symmetric about the sensor's x axis: beam i
  // is at -aperture/2 + i * aperture / (n - 1). A ROS scan need not be symmetric, so its centre
  // bearing goes into the sensor pose.
  const double aperture = scan.angle_increment_rad * static_cast<double>(n - 1);
  const double centre = scan.angle_min_rad + 0.5 * aperture;
  float max_range = scan.range_max_m;
  if (!std::isfinite(max_range)) {
    max_range = 0.0F;
    for (const float r : scan.ranges_m) {
      if (std::isfinite(r)) max_range = std::max(max_range, r);
    }
    max_range = max_range > 0.0F ? 1.01F * max_range : 100.0F;
  }
  auto obs = mrpt::obs::CObservation2DRangeScan::Create();
  obs->timestamp = mrpt::Clock::fromDouble(scan.stamp_s);
  obs->sensorLabel = "LIDAR";
  obs->aperture = static_cast<float>(aperture);
  obs->rightToLeft = true;
  obs->maxRange = max_range;
  obs->sensorPose =
      mrpt::poses::CPose3D(mount.x_m, mount.y_m, 0.0, wrap_angle(mount.yaw_rad + centre), 0.0, 0.0);
  obs->resizeScan(n);
  std::int64_t invalid = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const float r = scan.ranges_m[i];
    // REP 117: NaN is an invalid measurement (and what `dispel filter` writes for removed beams),
    // +inf no return. A return at range_max is taken as no return too.
    const bool valid = std::isfinite(r) && r > 0.0F && r >= scan.range_min_m && r < max_range;
    obs->setScanRange(i, valid ? r : max_range);
    obs->setScanRangeValidity(i, valid);
    invalid += valid ? 0 : 1;
  }
  if (invalid_beams != nullptr) *invalid_beams += invalid;

  Pose2 increment;
  if (!m.started) {
    m.first_odometry = odometry;
    m.started = true;
  } else {
    increment = m.last_odometry.inverse() * odometry;
  }
  m.last_odometry = odometry;

  mrpt::obs::CActionRobotMovement2D action;
  action.timestamp = obs->timestamp;
  mrpt::obs::CActionRobotMovement2D::TMotionModelOptions motion;  // Gaussian model.
  action.computeFromOdometry(mrpt::poses::CPose2D(increment.x_m, increment.y_m, increment.yaw_rad),
                             motion);
  mrpt::obs::CActionCollection actions;
  actions.insert(action);
  mrpt::obs::CSensoryFrame frame;
  frame.insert(obs);

  mrpt::poses::CPose3D estimate;
  try {
    m.builder.processActionObservation(actions, frame);
    m.builder.getCurrentPoseEstimation()->getMean(estimate);
  } catch (const std::exception& e) {
    throw io::JobError("SLAM engine: " + first_line(e));
  }
  return m.first_odometry * Pose2{estimate.x(), estimate.y(), estimate.yaw()};
}

std::vector<MapPoint> IcpSlamEngine::map_points() const {
  const auto points =
      impl_->builder.getCurrentlyBuiltMetricMap()->mapByClass<mrpt::maps::CPointsMap>();
  std::vector<MapPoint> out;
  if (!points) return out;
  std::vector<float> xs, ys;
  points->getAllPoints(xs, ys);
  out.reserve(xs.size());
  for (std::size_t i = 0; i < xs.size(); ++i) {
    const Eigen::Vector2d p = impl_->first_odometry.apply({xs[i], ys[i]});
    out.push_back({p.x(), p.y()});
  }
  return out;
}

}  // namespace dispel::slam
