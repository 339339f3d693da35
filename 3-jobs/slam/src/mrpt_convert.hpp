#pragma once
// Internal to dispel::slam: dispel's scans, odometry and grids as MRPT's types, shared by the
// ICP-SLAM engine and the particle filter. Only the files that use MRPT include this.

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>

#include <cstdint>
#include <exception>
#include <string>

#include "dispel/core/laser_scan.hpp"
#include "dispel/core/pose2.hpp"
#include "dispel/slam/grid_map.hpp"

namespace dispel::slam::detail {

/// MRPT's exceptions carry a call stack over many lines: the first line with text.
std::string first_line(const std::exception& e);

/// @p scan as MRPT's observation, with the laser at @p mount on the robot. MRPT's beams are
/// spread evenly and symmetrically about the sensor's x axis, so the scan's centre bearing goes
/// into the sensor pose. NaN, infinite, non-positive, below range_min and at or beyond range_max
/// beams are flagged invalid (and given range_max). Returns nullptr for a scan with fewer than two
/// beams, a non-positive angle increment or a non-finite stamp or angle; otherwise adds the
/// invalid beams to @p invalid_beams when given.
mrpt::obs::CObservation2DRangeScan::Ptr to_mrpt_scan(const LaserScan& scan, const Pose2& mount,
                                                     std::int64_t* invalid_beams);

/// Inserts @p scan, taken from @p robot, into @p grid. MRPT 2.5's grid insertion spreads the
/// beams by aperture / n where its points maps (and the likelihood field) use aperture / (n - 1):
/// the scan is given to the grid with aperture and centre bearing adjusted so that each beam is
/// inserted along its true bearing (otherwise a 270 degree scan of 360 beams is rotated by about
/// -0.4 degrees in the grid).
void insert_into_grid(const mrpt::obs::CObservation2DRangeScan& scan,
                      const mrpt::poses::CPose3D& robot, mrpt::maps::COccupancyGridMap2D& grid);

/// The odometry increment @p increment (robot frame) as a time-stamped
/// CActionRobotMovement2D with the Gaussian motion model @p model.
mrpt::obs::CActionCollection odometry_action(
    const Pose2& increment, mrpt::Clock::time_point stamp,
    const mrpt::obs::CActionRobotMovement2D::TMotionModelOptions& model = {});

/// @p map's cells (occupancy) as an MRPT grid in the grid's own frame: cell (0, 0) at (0, 0),
/// axes along the grid's. MRPT stores the probability of a cell being free.
mrpt::maps::COccupancyGridMap2D::Ptr to_mrpt_grid(const GridMap& map);

/// The observed part of @p grid (cells seen at least once, plus @p margin_cells around them) as
/// a GridMap in the same frame, quantised as map_saver saves it: occupied (>= 65 %) 100, free
/// (<= 25 %) 0, otherwise unknown. @p resolution_m is the grid's, exact (MRPT keeps a float).
GridMap from_mrpt_grid(const mrpt::maps::COccupancyGridMap2D& grid, double resolution_m,
                       int margin_cells);

}  // namespace dispel::slam::detail
