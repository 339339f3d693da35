#pragma once
/// @file
/// A scenario: the world, the robot and its path, the LiDAR, the odometry sensors and the moving
/// actors. Plain data with defaults; loading from YAML lives in dispel::io.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "dispel/core/pose2.hpp"
#include "dispel/sim/raycast.hpp"

namespace dispel::sim {

/// A rectangle (shelf, machine, cart body): centre, length along its yaw, width across.
struct Rectangle {
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  double length_m = 1.0;
  double width_m = 1.0;
  double yaw_rad = 0.0;
};

/// What makes the walls of a real building rough (drawn from the seed, applied to every wall):
/// the wall is cut into pieces, each set back or forward (recesses, pillars, panels, skirting),
/// joined by short steps; some pieces are glass (no return); doors are gaps with a recess behind;
/// furniture legs stand in front of it.
struct RoughWalls {
  double amplitude_m = 0.05;  ///< Each piece is offset by up to this much along the normal.
  double piece_min_m = 0.3;   ///< Length of a piece, drawn uniformly between these.
  double piece_max_m = 2.0;
  double doors_per_10m = 1.0;  ///< 0.9 m gaps with a 0.25 m deep recess.
  double legs_per_10m = 2.0;   ///< Pairs of furniture legs (2.5 cm radius) 0.15-0.6 m off the wall.
  double glass_share = 0.1;    ///< Share of pieces that are glass.
  /// 0: glass returns nothing. > 0: a glass piece returns the beams that meet it within this many
  /// degrees of its normal (a reflection straight back, as real glass and polished panels give)
  /// and lets the others through.
  double glass_returns_within_deg = 0.0;
  /// Low things (chair seats, boxes: by default 0.15-0.3 m across, 0.05-0.35 m off the wall) that a
  /// scan plane tilted up hits only from within a range (by default 0.8-2 m, drawn per thing); from
  /// farther the beams pass over them and see the wall behind. Real scan planes are not level: on a
  /// real robot (negative_2) such things were most of what the filter removed, some 0.5 m across
  /// and hit from within about 3 m.
  double low_things_per_10m = 0.0;
  double low_things_min_radius_m = 0.075;  ///< Radius drawn uniformly between these.
  double low_things_max_radius_m = 0.15;
  double low_things_min_seen_within_m = 0.8;  ///< Hit from within a range drawn between these.
  double low_things_max_seen_within_m = 2.0;
};

/// A row of shelving (a warehouse rack): uprights every bay and, in each bay with probability
/// fill, a box set back from the aisle by up to 0.3 m: a face with gaps through which the scanner
/// sees the next aisle.
struct ShelfRow {
  Eigen::Vector2d from = Eigen::Vector2d::Zero();
  Eigen::Vector2d to = Eigen::Vector2d::Zero();
  double depth_m = 1.0;
  double bay_m = 2.7;
  double fill = 0.7;
};

/// Small things standing about, drawn from the seed: posts, plants, bins, chair legs, each a
/// circle whose beams flicker (return_share: foliage, a wire basket, an open chair back return
/// some beams and let the others through, differently in every scan), placed keep_clear_m or more
/// from the robot's path and every actor's path. Real recordings are full of them; seen from afar
/// they are a few beams each.
struct Clutter {
  int count = 0;
  Eigen::Vector2d area_min = Eigen::Vector2d::Zero();
  Eigen::Vector2d area_max = Eigen::Vector2d::Zero();
  double min_radius_m = 0.02;  ///< Radius drawn uniformly between these.
  double max_radius_m = 0.15;
  double return_share = 0.6;  ///< Share of the beams reaching a thing that return from it.
  double keep_clear_m = 1.0;
};

/// Static structure.
struct StaticWorld {
  std::vector<Segment> walls;  ///< Walls and polyline pieces.
  std::vector<Rectangle> rectangles;
  std::vector<Circle> circles;
  std::vector<ShelfRow> shelves;
  /// When set, every wall is made rough (rectangles, circles and shelves stay as they are).
  std::optional<RoughWalls> rough_walls;
  Clutter clutter;
};

/// The thesis's lawnmower pattern: straight lanes along x joined by half-circle U-turns.
struct Lawnmower {
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  ///< Start of the first lane.
  double lane_length_m = 10.0;
  double lane_spacing_m = 2.0;  ///< Lanes advance along +y.
  int lanes = 4;
};

/// A time when someone or something stands still: from at_s seconds into the run, for for_s
/// seconds, wherever it is then (a robot brakes to a halt within its motors' limits).
struct Stop {
  double at_s = 0.0;
  double for_s = 0.0;
};

struct RobotConfig {
  Pose2 start;
  double speed_mps = 0.067;                ///< The thesis's robot.
  std::vector<Eigen::Vector2d> waypoints;  ///< Used when no lawnmower is given.
  bool loop = true;                        ///< Start over at the end of the path.
  std::optional<Lawnmower> lawnmower;
  double wheel_base_m = 0.5;
  Pose2 laser_mount{0.2, 0.0, 0.0};  ///< Laser in base_link.
  /// Stretches of the run the robot stands (a robot that waits for the person it follows).
  std::vector<Stop> stops;
};

struct LidarConfig {
  double range_max_m = 40.0;
  double fov_deg = 275.0;
  double resolution_deg = 0.17;
  double rate_hz = 20.0;
  /// Returns beyond this are dropped (the thesis cut the range to 5.5 m to emulate a
  /// feature-sparse hall); 0 keeps the full range.
  double range_limit_m = 0.0;
  /// Sectors [begin_deg, end_deg] in the laser frame that return nothing (the thesis's mirrors).
  std::vector<std::pair<double, double>> masked_sectors_deg;
  double range_noise_m = 0.01;  ///< Gaussian, standard deviation.
  /// The noise grows with range: standard deviation range_noise_m + range_noise_per_m * range.
  double range_noise_per_m = 0.0;
  /// And with incidence: multiplied by 1 + incidence_noise * (1 / cos(incidence) - 1), the cosine
  /// taken at least 0.1 (a grazing beam spreads over the surface).
  double incidence_noise = 0.0;
  /// Probability that a beam at a depth edge (a neighbour more than 0.2 m farther) returns a
  /// range between the near and the far surface (a mixed pixel).
  double mixed_pixels = 0.0;
  double dropout = 0.002;  ///< Probability that a beam returns nothing.
  /// Speckle: sporadic returns where nothing is in range, as a real scanner outdoors gives them
  /// (the ground or grass seen as the scanner pitches, a weak echo near its range limit). Each
  /// beam that returns nothing starts one with this probability: it and up to
  /// speckle_beams_max - 1 following beams that return nothing all return one range drawn in
  /// [speckle_range_m.first, speckle_range_m.second] (plus the range noise), in that scan only.
  /// Truth code static: it is background, not a moving thing. 0: none (no draws are made).
  double speckle = 0.0;
  std::pair<double, double> speckle_range_m{0.0, 0.0};
  int speckle_beams_max = 4;
  /// Reach that depends on the surface: this share of the static shapes (pieces of wall,
  /// furniture, trees, posts; drawn per shape from the seed) is dark and returns a beam only
  /// within dark_reach_m; farther, the beam returns nothing. A real scanner's range_max holds for
  /// bright targets: outdoors, person_following_outdoor_1's 5.6 m scanner returned from a surface
  /// at the edge of its view only from about 5.3 m on, as the robot drove towards it, so what the
  /// beams before saw as free (nothing returned) returned once the robot was near enough. 0:
  /// every surface returns up to range_max_m.
  double dark_share = 0.0;
  double dark_reach_m = 0.0;
  /// The ground, seen when the robot pitches: the scan plane is height_m above a flat floor, and
  /// the robot meets bumps_per_min bumps a minute (one drawn from the seed at a random time in
  /// each slot of 60 / bumps_per_min seconds). A bump tilts the scan plane for bump_s, as half a
  /// sine, by up to bump_tilt_deg (its size drawn uniformly), nose down, leaning to one side by a
  /// drawn share of that. A beam whose tilted line meets the floor nearer than what it hits (or
  /// within range_max_m where it hits nothing) returns the floor: a smooth arc across the view
  /// that moves with the robot, in the scans of the bump only. person_following_outdoor_1 shows
  /// it (scans 4986-4991: the whole view returns an arc at 2.2 m ahead to 3.6 m at its edges that
  /// comes and goes within 0.6 s). Truth code static: the floor does not move. 0: no bumps (no
  /// draws are made).
  double height_m = 0.0;
  double bumps_per_min = 0.0;
  double bump_tilt_deg = 0.0;
  double bump_s = 0.6;
  /// Beams are measured over the sweep: beam i at stamp + i * time_increment, where
  /// time_increment is one revolution (1 / rate_hz) divided by the beams a full turn would have;
  /// the robot moves during the scan. false: every beam at the stamp (time_increment 0).
  bool sweep = false;
};

struct SensorConfig {
  double rate_hz = 50.0;                  ///< Wheels, IMU and odometry.
  double wheel_noise_mps = 0.003;         ///< Gaussian on each wheel speed.
  double wheel_scale_error = 0.01;        ///< Both wheels read this much more (a worn tyre).
  double wheel_difference_error = 0.001;  ///< Right reads this much more, left less: heading drift.
  double slips_per_minute = 0.5;          ///< Events where one wheel reads 30% fast for 0.5 s.
  double imu_noise_radps = 0.003;         ///< Gaussian on the yaw rate.
  double imu_bias_walk_radps = 0.0002;    ///< Random walk of the bias per sqrt(second).
  double imu_vibration_radps = 0.005;     ///< 15 Hz vibration amplitude at 1 m/s.
};

enum class ActorKind { kPerson, kCart };

/// Someone or something that moves: along waypoints at a speed, pausing at each waypoint, or
/// standing still the whole run (no waypoints after the start).
struct Actor {
  ActorKind kind = ActorKind::kPerson;
  std::vector<Eigen::Vector2d> waypoints;  ///< The first is the start.
  double speed_mps = 1.0;
  double pause_s = 0.0;  ///< Standing time at each waypoint.
  bool loop = true;      ///< Walk the waypoints again from the start.
  double start_delay_s = 0.0;
  std::vector<Stop> stops;  ///< Stretches of the run it stands, wherever it is.
  double length_m = 1.2;    ///< Carts: footprint.
  double width_m = 0.8;
};

/// People generated from the seed: each walks between random points of the area, by default
/// round and round (back to its first point after the last), so that people keep coming and
/// going however long the run.
struct RandomPeople {
  int count = 0;
  Eigen::Vector2d area_min = Eigen::Vector2d::Zero();
  Eigen::Vector2d area_max = Eigen::Vector2d::Zero();
  double min_speed_mps = 0.5;
  double max_speed_mps = 1.5;
  double max_pause_s = 3.0;
  int waypoints = 6;
  /// false: each walks its waypoints once and then stands at the last.
  bool loop = true;
};

/// How a walking person's legs move (people are two legs; docs/simulator.md).
/// kSway: each leg swings up to 0.15 m ahead of and behind the walker over each stride
/// (1.4 m), never still. kPlanted: as people walk, each foot stands on the floor
/// for 60 % of a stride while the body passes over it (from 0.42 m ahead of the body to 0.42 m
/// behind), then swings forward at 2.5 times the walking speed.
enum class Gait { kSway, kPlanted };

struct Scenario {
  std::string name = "scenario";
  Gait gait = Gait::kSway;
  double duration_s = 60.0;
  /// Stamp of the first message (ROS bags cannot hold time 0).
  double start_time_s = 100.0;
  StaticWorld world;
  RobotConfig robot;
  LidarConfig lidar;
  SensorConfig sensors;
  std::vector<Actor> actors;
  RandomPeople random_people;

  /// Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

}  // namespace dispel::sim
