// Internal to dispel::slam: dispel's scans, odometry and grids as MRPT's types.

#include "mrpt_convert.hpp"

#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPose3D.h>

#include <algorithm>
#include <cmath>

namespace dispel::slam::detail {

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

mrpt::obs::CObservation2DRangeScan::Ptr to_mrpt_scan(const LaserScan& scan, const Pose2& mount,
                                                     std::int64_t* invalid_beams) {
  const std::size_t n = scan.size();
  if (n < 2 || !(scan.angle_increment_rad > 0.0) || !std::isfinite(scan.angle_increment_rad) ||
      !std::isfinite(scan.angle_min_rad) || !std::isfinite(scan.stamp_s)) {
    return nullptr;
  }
  // MRPT's beam i is at -aperture/2 + i * aperture / (n - 1). A ROS scan need not be symmetric,
  // so its centre bearing goes into the sensor pose.
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
  return obs;
}

void insert_into_grid(const mrpt::obs::CObservation2DRangeScan& scan,
                      const mrpt::poses::CPose3D& robot, mrpt::maps::COccupancyGridMap2D& grid) {
  const std::size_t n = scan.getScanSize();
  if (n < 2) return;
  // The grid puts beam i at yaw' -+ aperture'/2 +- i * aperture'/n (+- for right to left); it
  // belongs at yaw -+ aperture/2 +- i * aperture/(n - 1).
  mrpt::obs::CObservation2DRangeScan adjusted = scan;
  const double step = static_cast<double>(scan.aperture) / static_cast<double>(n - 1);
  adjusted.aperture = static_cast<float>(step * static_cast<double>(n));
  const mrpt::poses::CPose3D& s = scan.sensorPose;
  adjusted.sensorPose = mrpt::poses::CPose3D(
      s.x(), s.y(), s.z(), wrap_angle(s.yaw() + (scan.rightToLeft ? 0.5 : -0.5) * step), s.pitch(),
      s.roll());
  adjusted.insertObservationInto(grid, robot);
}

mrpt::obs::CActionCollection odometry_action(
    const Pose2& increment, mrpt::Clock::time_point stamp,
    const mrpt::obs::CActionRobotMovement2D::TMotionModelOptions& model) {
  mrpt::obs::CActionRobotMovement2D action;
  action.timestamp = stamp;
  action.computeFromOdometry(mrpt::poses::CPose2D(increment.x_m, increment.y_m, increment.yaw_rad),
                             model);
  mrpt::obs::CActionCollection actions;
  actions.insert(action);
  return actions;
}

mrpt::maps::COccupancyGridMap2D::Ptr to_mrpt_grid(const GridMap& map) {
  const auto res = static_cast<float>(map.resolution_m);
  auto grid = mrpt::maps::COccupancyGridMap2D::Create(
      0.0F, static_cast<float>(map.width) * res, 0.0F, static_cast<float>(map.height) * res, res);
  // MRPT's size comes from rounding the extent over the resolution: it must be the map's.
  const int cols = std::min(map.width, static_cast<int>(grid->getSizeX()));
  const int rows = std::min(map.height, static_cast<int>(grid->getSizeY()));
  for (int row = 0; row < rows; ++row) {
    for (int col = 0; col < cols; ++col) {
      const std::int8_t c = map.at(col, row);
      grid->setCell(col, row, c < 0 ? 0.5F : 1.0F - 0.01F * static_cast<float>(c));
    }
  }
  return grid;
}

GridMap from_mrpt_grid(const mrpt::maps::COccupancyGridMap2D& grid, double resolution_m,
                       int margin_cells) {
  const int nx = static_cast<int>(grid.getSizeX());
  const int ny = static_cast<int>(grid.getSizeY());
  // An unobserved cell holds log-odds 0 (probability 0.5).
  const auto observed = [&](int x, int y) { return grid.getRow(y)[x] != 0; };
  int x0 = nx, x1 = -1, y0 = ny, y1 = -1;
  for (int y = 0; y < ny; ++y) {
    for (int x = 0; x < nx; ++x) {
      if (!observed(x, y)) continue;
      x0 = std::min(x0, x);
      x1 = std::max(x1, x);
      y0 = std::min(y0, y);
      y1 = std::max(y1, y);
    }
  }
  GridMap map;
  map.resolution_m = resolution_m;  // MRPT keeps it as a float.
  if (x1 < 0) return map;
  x0 = std::max(0, x0 - margin_cells);
  y0 = std::max(0, y0 - margin_cells);
  x1 = std::min(nx - 1, x1 + margin_cells);
  y1 = std::min(ny - 1, y1 + margin_cells);
  map.origin = {grid.getXMin() + x0 * resolution_m, grid.getYMin() + y0 * resolution_m, 0.0};
  map.width = x1 - x0 + 1;
  map.height = y1 - y0 + 1;
  map.cells.reserve(static_cast<std::size_t>(map.width) * static_cast<std::size_t>(map.height));
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      const long percent = observed(x, y) ? std::lround(100.0 * (1.0 - grid.getCell(x, y))) : -1;
      map.cells.push_back(percent < 0     ? kUnknownCell
                          : percent >= 65 ? kOccupiedCell
                          : percent <= 25 ? kFreeCell
                                          : kUnknownCell);
    }
  }
  return map;
}

}  // namespace dispel::slam::detail
