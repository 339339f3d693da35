#pragma once
/// @file
/// SLAM through a real engine: MRPT 2.5's ICP-based SLAM (mrpt::slam::CMetricMapBuilderICP, the
/// engine behind MRPT's `icp-slam` program) run in-process over the scans and odometry of a ROS 1
/// bag. MRPT stays behind this header: users of dispel::slam do not see it.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "dispel/core/laser_scan.hpp"
#include "dispel/core/pose2.hpp"
#include "dispel/eval/trajectory_error.hpp"
#include "dispel/slam/grid_map.hpp"

namespace dispel::slam {

/// What to run the engine on, and how.
struct SlamOptions {
  std::string input;  ///< A ROS 1 bag.
  /// sensor_msgs/LaserScan. Empty: /scan_filtered (what `dispel filter` writes) when the bag
  /// has it, else /scan.
  std::string scan_topic = "/scan";
  std::string odom_topic = "/odom";              ///< nav_msgs/Odometry: the motion input.
  std::optional<std::string> engine_config_ini;  ///< MRPT-style .ini over the defaults.
  /// How far beyond the first or last odometry message a scan's odometry may be taken from it.
  double odom_tolerance_s = 0.05;
  /// Cell edge of SlamResult::grid (m, > 0).
  double map_resolution_m = 0.05;
};

/// A point of the engine's final map, in the odometry frame.
struct MapPoint {
  double x_m = 0.0;
  double y_m = 0.0;
};

/// Everything a run gives.
struct SlamResult {
  /// The engine's estimate of the robot (base frame) at each scan used, in the odometry frame
  /// (the engine's map frame moved so that it coincides with odometry at the first scan).
  std::vector<eval::TrajectoryPoint> trajectory;
  /// The odometry at the same scans, interpolated at their stamps.
  std::vector<eval::TrajectoryPoint> odometry;
  /// The final points map (the first points map of the engine's multi-metric map).
  std::vector<MapPoint> map_points;
  /// The occupancy grid of the run, in the odometry frame (see IcpSlamEngine::grid_map()): the
  /// map to localise in later (write_map_yaml()).
  GridMap grid;
  std::int64_t scans = 0;              ///< Scans on the topic.
  std::int64_t scans_used = 0;         ///< Scans given to the engine.
  std::int64_t scans_no_odometry = 0;  ///< Skipped: no odometry at their stamp.
  std::int64_t scans_bad = 0;          ///< Skipped: no beams or a non-positive angle increment.
  std::int64_t beams_invalid = 0;      ///< Beams marked invalid (NaN, inf, out of limits).
  std::int64_t odometry_refused = 0;   ///< Odometry messages out of order or not finite.
  std::string engine_config;           ///< The engine configuration used (ini text).
  std::string scan_topic;              ///< The scan topic read.
};

/// The engine's default configuration for a 2D LiDAR, as MRPT ini text (sections
/// [MappingApplication], [MappingApplication_pointsMap_00_insertOpts] and [ICP], named as MRPT's
/// icp-slam names them).
std::string default_engine_config();

/// The defaults overlaid with @p ini_path (each key of the file replaces the default; keys the
/// engine does not know, such as icp-slam's rawlog_file, are ignored), with every occupancy grid's
/// considerInvalidRangesAsFreeSpace forced to false so removed beams never clear map cells.
/// @throws dispel::jobs::JobError for an unreadable file, a line that is not `key = value`, or a
/// non-numeric value for a numeric setting.
std::string engine_config(const std::optional<std::string>& ini_path);

/// Runs the engine over the bag: every scan with odometry at its stamp is converted to an
/// mrpt::obs::CObservation2DRangeScan (sensor pose = the laser mount from /tf_static or /tf; NaN,
/// infinite and out-of-limit beams flagged invalid, so they never enter the map) and given with
/// the odometry increment since the previous scan (mrpt::obs::CActionRobotMovement2D).
/// @throws dispel::jobs::JobError with a one-line message (missing file, not a bag, no scan or
/// odometry topic, no laser mount, bad engine configuration, map_resolution_m not > 0).
SlamResult run_icp_slam_full(const SlamOptions& options);

/// The estimated robot trajectory only (see run_icp_slam_full()).
std::vector<eval::TrajectoryPoint> run_icp_slam(const SlamOptions& options);

/// The engine itself, one scan at a time, for callers with their own data source.
class IcpSlamEngine {
 public:
  /// @param config ini text (see engine_config()). @throws dispel::jobs::JobError
  explicit IcpSlamEngine(const std::string& config);
  ~IcpSlamEngine();
  IcpSlamEngine(const IcpSlamEngine&) = delete;
  IcpSlamEngine& operator=(const IcpSlamEngine&) = delete;

  /// Gives one scan with the robot's odometry pose at the scan's stamp and the laser's mount on
  /// the robot; returns the engine's estimate of the robot pose in the odometry frame.
  /// Returns nullopt (and does nothing) for a scan without beams or with a non-positive angle
  /// increment. @p invalid_beams, when given, is increased by the beams flagged invalid.
  /// The engine starts (its map begins) with the first scan that has at least 30 valid beams;
  /// before it, the estimate is @p odometry (a filter with presumption of guilt removes every
  /// object of the first scans, and MRPT's ICP-SLAM never recovers from an empty first map).
  /// After it, a scan with fewer valid beams than the configuration's [dispel] min_valid_beams
  /// (120 by default) is not matched: the estimate follows the odometry from the last scan that
  /// was.
  std::optional<Pose2> process(const LaserScan& scan, const Pose2& odometry, const Pose2& mount,
                               std::int64_t* invalid_beams = nullptr);

  /// The points of the engine's points map, in the odometry frame.
  std::vector<MapPoint> map_points() const;

  /// An occupancy grid (MRPT's COccupancyGridMap2D, default insertion options) of the keyframe
  /// scans inserted at the engine's keyframe poses, in the odometry frame, axis-aligned, cropped
  /// to the observed cells plus 2 cells, quantised as map_saver saves maps (occupied >= 65 %,
  /// free <= 25 %, otherwise unknown). Invalid beams are not free space: they change no cell.
  /// @param resolution_m cell edge (m). @throws dispel::jobs::JobError unless it is > 0.
  GridMap grid_map(double resolution_m) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dispel::slam
