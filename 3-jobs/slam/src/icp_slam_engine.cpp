// The MRPT side of dispel::slam: CMetricMapBuilderICP fed one scan and one odometry increment at a
// time. The only file that includes MRPT.

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/core/Clock.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/maps/CPointsMap.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/poses/CPose3DPDF.h>
#include <mrpt/slam/CMetricMapBuilderICP.h>

#include <cmath>
#include <exception>
#include <string>

#include "dispel/jobs/job.hpp"
#include "dispel/slam/icp_slam.hpp"
#include "mrpt_convert.hpp"

namespace dispel::slam {
namespace {

using detail::first_line;

bool finite_non_negative(double v) { return std::isfinite(v) && v >= 0.0; }

// Valid beams the first scan given to the engine needs (its map starts from it).
constexpr std::int64_t kMinBeamsToStart = 30;

}  // namespace

struct IcpSlamEngine::Impl {
  mrpt::slam::CMetricMapBuilderICP builder;
  std::int64_t min_valid_beams = 0;  // [dispel] min_valid_beams: fewer are not matched.
  bool started = false;
  Pose2 first_odometry;  // The engine's frame is the robot at the first scan.
  Pose2 last_odometry;   // At the last scan given to the engine.
  Pose2 last_estimate;   // The engine's estimate then, in its frame.
};

IcpSlamEngine::IcpSlamEngine(const std::string& config) : impl_(std::make_unique<Impl>()) {
  auto& b = impl_->builder;
  b.setVerbosityLevel(mrpt::system::LVL_ERROR);
  try {
    const mrpt::config::CConfigFileMemory ini(config);
    b.ICP_options.loadFromConfigFile(ini, "MappingApplication");
    b.ICP_params.loadFromConfigFile(ini, "ICP");
    impl_->min_valid_beams = ini.read_int("dispel", "min_valid_beams", 0);
  } catch (const std::exception& e) {
    throw jobs::JobError("SLAM engine configuration: " + first_line(e));
  }
  if (impl_->min_valid_beams < 0) {
    throw jobs::JobError("SLAM engine configuration: [dispel] min_valid_beams must be >= 0");
  }
  const auto& o = b.ICP_options;
  if (!finite_non_negative(o.insertionLinDistance) ||
      !finite_non_negative(o.insertionAngDistance) ||
      !finite_non_negative(o.localizationLinDistance) ||
      !finite_non_negative(o.localizationAngDistance) || !std::isfinite(o.minICPgoodnessToAccept)) {
    throw jobs::JobError(
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
    throw jobs::JobError("SLAM engine configuration: " + first_line(e));
  }
  if (!b.getCurrentlyBuiltMetricMap()->mapByClass<mrpt::maps::CPointsMap>()) {
    throw jobs::JobError(
        "SLAM engine configuration: no points map (set pointsMap_count=1 in "
        "[MappingApplication]); ICP-SLAM matches against one");
  }
}

IcpSlamEngine::~IcpSlamEngine() = default;

std::optional<Pose2> IcpSlamEngine::process(const LaserScan& scan, const Pose2& odometry,
                                            const Pose2& mount, std::int64_t* invalid_beams) {
  std::int64_t invalid = 0;
  const auto obs = detail::to_mrpt_scan(scan, mount, &invalid);
  if (invalid_beams != nullptr) *invalid_beams += invalid;
  if (!obs) return std::nullopt;
  Impl& m = *impl_;

  // The engine's first scan becomes its map, and MRPT's ICP-SLAM does not recover from an empty
  // one (no match is ever accepted, so it follows odometry to the end). A filter that removes
  // every object until it has seen it still (presumption of guilt) gives exactly that: the
  // engine starts with the first scan that has enough valid beams; until then, odometry.
  const auto valid = static_cast<std::int64_t>(scan.ranges_m.size()) - invalid;
  if (!m.started && valid < kMinBeamsToStart) return odometry;
  // Too few beams to be matched: MRPT's ICP-SLAM accepts a match of a dozen points, and a dozen
  // wrong or ambiguous ones (a pillar, a walker kept) pull the pose by metres. The odometry
  // carries the pose through such a scan; the engine does not see it.
  if (m.started && valid < m.min_valid_beams) {
    return m.first_odometry * (m.last_estimate * (m.last_odometry.inverse() * odometry));
  }

  Pose2 increment;
  if (!m.started) {
    m.first_odometry = odometry;
    m.started = true;
  } else {
    increment = m.last_odometry.inverse() * odometry;
  }
  m.last_odometry = odometry;

  mrpt::obs::CActionCollection actions =
      detail::odometry_action(increment, obs->timestamp);  // Gaussian model.
  mrpt::obs::CSensoryFrame frame;
  frame.insert(obs);

  mrpt::poses::CPose3D estimate;
  try {
    m.builder.processActionObservation(actions, frame);
    m.builder.getCurrentPoseEstimation()->getMean(estimate);
  } catch (const std::exception& e) {
    throw jobs::JobError("SLAM engine: " + first_line(e));
  }
  m.last_estimate = Pose2{estimate.x(), estimate.y(), estimate.yaw()};
  return m.first_odometry * m.last_estimate;
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

GridMap IcpSlamEngine::grid_map(double resolution_m) const {
  if (!(resolution_m > 0.0) || !std::isfinite(resolution_m)) {
    throw jobs::JobError("map resolution " + std::to_string(resolution_m) +
                         " m: must be a positive number of metres per cell");
  }
  const auto res = static_cast<float>(resolution_m);
  mrpt::maps::COccupancyGridMap2D grid(-1.0F, 1.0F, -1.0F, 1.0F, res);
  // Removed beams must never clear cells.
  grid.insertionOptions.considerInvalidRangesAsFreeSpace = false;
  mrpt::maps::CSimpleMap keyframes;
  impl_->builder.getCurrentlyBuiltMap(keyframes);
  for (const auto& keyframe : keyframes) {
    if (!keyframe.pose || !keyframe.sf) continue;
    const mrpt::poses::CPose3D p = keyframe.pose->getMeanVal();
    const Pose2 robot = impl_->first_odometry * Pose2{p.x(), p.y(), p.yaw()};
    const mrpt::poses::CPose3D pose(robot.x_m, robot.y_m, 0.0, robot.yaw_rad, 0.0, 0.0);
    for (const auto& obs : *keyframe.sf) {
      if (const auto* scan = dynamic_cast<const mrpt::obs::CObservation2DRangeScan*>(obs.get())) {
        detail::insert_into_grid(*scan, pose, grid);
      }
    }
  }
  return detail::from_mrpt_grid(grid, resolution_m, 2);
}

}  // namespace dispel::slam
