#pragma once
/// @file
/// Localisation in a known map: MRPT 2.5's particle filter (mrpt::slam::CMonteCarloLocalization2D,
/// the engine behind MRPT's `pf-localization` program) run in-process over the scans and odometry
/// of a ROS 1 bag, against an occupancy grid (a map_server map, such as one built by
/// run_icp_slam_full()). MRPT stays behind this header.

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

/// MRPT's particle-filter algorithms (mrpt::bayes::CParticleFilter::TParticleFilterAlgorithm)
/// that CMonteCarloLocalization2D implements.
enum class PfAlgorithm {
  kStandardProposal,  ///< SIR: particles drawn from the motion model, weighted by the scan.
  kAuxiliaryOptimal,  ///< Auxiliary PF with the optimal proposal (rejection sampling; slower).
};

/// The particle filter, its initial spread and its models.
struct ParticleFilterOptions {
  int particles = 500;  ///< Particle count (fixed).
  /// Seed of the filter's random numbers: the same seed, map and data give the same estimates.
  std::uint64_t seed = 1;
  PfAlgorithm algorithm = PfAlgorithm::kStandardProposal;
  /// Resample when the effective sample size falls below this fraction of the particles.
  double resample_below_ess = 0.5;

  /// Initial particles: Gaussian about the initial pose with these standard deviations.
  double initial_std_x_m = 0.3;
  double initial_std_y_m = 0.3;
  double initial_std_yaw_rad = 10.0 * kPi / 180.0;

  /// Motion model: MRPT's Gaussian odometry model. For an odometry increment of length d (m) and
  /// turn a (rad) between two scans, std of x and y = motion_std_xy_m + motion_std_xy_per_m * d +
  /// motion_std_xy_per_rad * |a|, std of yaw = motion_std_yaw_rad + motion_std_yaw_per_m * d +
  /// motion_std_yaw_per_rad * |a| (the defaults are MRPT's).
  double motion_std_xy_m = 0.01;
  double motion_std_yaw_rad = 0.2 * kPi / 180.0;
  double motion_std_xy_per_m = 0.01;
  double motion_std_xy_per_rad = 0.001 * 180.0 / kPi;
  double motion_std_yaw_per_m = 1.0 * kPi / 180.0;
  double motion_std_yaw_per_rad = 0.05;

  /// Scan likelihood: MRPT's likelihood field (Thrun): each valid beam's end point is scored by
  /// its distance to the nearest occupied cell.
  double likelihood_std_m = 0.2;           ///< Std of that distance (LF_stdHit).
  int likelihood_decimation = 4;           ///< Every n-th end point is scored (LF_decimation).
  double likelihood_max_distance_m = 0.5;  ///< Search radius for that cell (LF_maxCorrsDistance).

  /// @throws dispel::jobs::JobError naming the first bad value.
  void validate() const;
};

/// What to localise, where, and how.
struct LocalizationOptions {
  std::string input;  ///< A ROS 1 bag.
  /// sensor_msgs/LaserScan. Empty: /scan_filtered when the bag has it, else /scan.
  std::string scan_topic = "/scan";
  std::string odom_topic = "/odom";  ///< nav_msgs/Odometry: the motion input.
  std::string map_yaml;              ///< A map_server map, read when `map` is not set.
  std::optional<GridMap> map;        ///< The map itself (wins over map_yaml).
  /// The robot (base frame) in the map frame at the first scan used; when not set, the odometry
  /// pose there (odometry frame taken as the map frame).
  std::optional<Pose2> initial_pose;
  ParticleFilterOptions filter;
  /// How far beyond the first or last odometry message a scan's odometry may be taken from it.
  double odom_tolerance_s = 0.05;
};

/// Everything a run gives. The vectors have one entry per scan used.
struct LocalizationResult {
  /// The particles' weighted mean (circular for yaw) after each scan: the robot's base frame in
  /// the map frame.
  std::vector<eval::TrajectoryPoint> trajectory;
  /// The odometry at the same scans, interpolated at their stamps, in the odometry frame.
  std::vector<eval::TrajectoryPoint> odometry;
  std::vector<double> position_std_m;  ///< sqrt(var x + var y) of the particles.
  std::vector<double> yaw_std_rad;     ///< Std of the particles' yaw.
  std::int64_t scans = 0;              ///< Scans on the topic.
  std::int64_t scans_used = 0;         ///< Scans given to the filter.
  std::int64_t scans_no_odometry = 0;  ///< Skipped: no odometry at their stamp.
  std::int64_t scans_bad = 0;          ///< Skipped: no beams or a non-positive angle increment.
  std::int64_t beams_invalid = 0;      ///< Beams marked invalid (NaN, inf, out of limits).
  std::int64_t odometry_refused = 0;   ///< Odometry messages out of order or not finite.
  std::string scan_topic;              ///< The scan topic read.
};

/// Localises the robot of a bag in a known map: every scan with odometry at its stamp is
/// converted as run_icp_slam_full() converts it (invalid beams flagged invalid, so they are not
/// scored) and given, with the odometry increment since the previous scan
/// (mrpt::obs::CActionRobotMovement2D), to CMonteCarloLocalization2D through
/// mrpt::bayes::CParticleFilter.
/// @throws dispel::jobs::JobError with a one-line message (missing or bad bag, map or options, no
/// scan or odometry topic, no laser mount, no scan with odometry).
LocalizationResult run_pf_localization(const LocalizationOptions& options);

/// One pose estimate of the particle filter.
struct PoseEstimate {
  Pose2 pose;                   ///< The particles' weighted mean, in the map frame.
  double position_std_m = 0.0;  ///< sqrt(var x + var y) of the particles.
  double yaw_std_rad = 0.0;     ///< Std of the particles' yaw.
};

/// The particle filter itself, one scan at a time, for callers with their own data source.
/// MRPT's filter draws from MRPT's process-wide random generator; each localizer keeps its own
/// generator state and swaps it in for its calls (serialised among localizers), so its estimates
/// depend only on its seed, map and data.
class PfLocalizer {
 public:
  /// Particles drawn about @p initial_pose (the robot in the map frame).
  /// @throws dispel::jobs::JobError for an invalid map or options.
  PfLocalizer(const GridMap& map, const ParticleFilterOptions& options, const Pose2& initial_pose);
  ~PfLocalizer();
  PfLocalizer(const PfLocalizer&) = delete;
  PfLocalizer& operator=(const PfLocalizer&) = delete;

  /// Gives one scan with the robot's odometry pose at the scan's stamp (any fixed frame) and the
  /// laser's mount on the robot; returns the estimate after it. Returns nullopt (and does
  /// nothing) for a scan without beams or with a non-positive angle increment. @p invalid_beams,
  /// when given, is increased by the beams flagged invalid.
  std::optional<PoseEstimate> process(const LaserScan& scan, const Pose2& odometry,
                                      const Pose2& mount, std::int64_t* invalid_beams = nullptr);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dispel::slam
