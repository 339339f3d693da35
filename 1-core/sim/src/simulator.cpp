#include "dispel/sim/simulator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>

#include "dispel/core/invalid_field.hpp"

namespace dispel::sim {
namespace {

constexpr double kDeg = kPi / 180.0;
constexpr double kStep = 0.01;                   // Physics step, seconds.
constexpr double kRobotClearance_m = 0.6;        // People keep this far from the robot's centre.
constexpr double kMaxAcceleration = 0.5;         // m/s^2, the robot's.
constexpr double kMaxAngularAcceleration = 1.5;  // rad/s^2.
constexpr double kMaxTurnRate = 0.6;             // rad/s, the robot's.
// The robot rounds a corner (a waypoint where its path turns by more than kCornerTurn_rad) at no
// more than kMaxTurnRate * kCornerRadius_m, 0.3 m/s, braking for it in time: at 1.5 m/s and its
// full turn rate it would swing 2.5 m wide, through the wall of a 2.2 m corridor.
constexpr double kCornerRadius_m = 0.5;
constexpr double kCornerTurn_rad = 20.0 * kPi / 180.0;
constexpr double kLookahead_m = 1.0;  // The robot steers for a point this far ahead on its leg.
constexpr std::uint64_t kDarkDraw = 0x6461726b;  // "dark": the draw of which surfaces are dark.
// The draws of a bump (LidarConfig::bumps_per_min): its time in its slot, its size, its lean.
constexpr std::uint64_t kBumpTimeDraw = 0x62756d70;
constexpr std::uint64_t kBumpSizeDraw = 0x62756d71;
constexpr std::uint64_t kBumpLeanDraw = 0x62756d72;
constexpr std::uint64_t kFloorNoiseDraw = 0x666c6f6f;  // "floo": the floor's range noise.

constexpr auto reject = reject_field;

// The path a robot or actor follows: waypoints in order, optionally looping.
class PathFollower {
 public:
  PathFollower(std::vector<Eigen::Vector2d> points, bool loop)
      : points_(std::move(points)), loop_(loop) {}
  bool done() const { return points_.empty() || (!loop_ && next_ >= points_.size()); }
  const Eigen::Vector2d& target() const { return points_[next_ % points_.size()]; }
  // The waypoint after the target, or null at the end of a path that does not loop.
  const Eigen::Vector2d* after_target() const {
    if (done() || points_.size() < 2 || (!loop_ && next_ + 1 >= points_.size())) return nullptr;
    return &points_[(next_ + 1) % points_.size()];
  }
  // Moves on when @p position is within @p reach of the target. Returns true on arrival.
  bool advance_if_reached(const Eigen::Vector2d& position, double reach) {
    if (done() || (position - target()).norm() > reach) return false;
    ++next_;
    if (loop_ && next_ >= points_.size()) next_ = 0;
    return true;
  }

 private:
  std::vector<Eigen::Vector2d> points_;
  bool loop_;
  std::size_t next_ = 0;
};

// Lanes along +x (alternating direction) joined by half circles of diameter lane_spacing.
std::vector<Eigen::Vector2d> lawnmower_path(const Lawnmower& l) {
  std::vector<Eigen::Vector2d> p;
  const double r = 0.5 * l.lane_spacing_m;
  for (int lane = 0; lane < l.lanes; ++lane) {
    const double y = l.origin.y() + lane * l.lane_spacing_m;
    const bool forward = lane % 2 == 0;
    const double x0 = forward ? l.origin.x() : l.origin.x() + l.lane_length_m;
    const double x1 = forward ? l.origin.x() + l.lane_length_m : l.origin.x();
    for (int k = 0; k <= 10; ++k) p.emplace_back(x0 + (x1 - x0) * k / 10.0, y);
    if (lane + 1 == l.lanes) break;
    // U-turn around (x1, y + r).
    for (int k = 1; k < 12; ++k) {
      const double a = -kPi / 2.0 + kPi * k / 12.0;
      const double side = forward ? 1.0 : -1.0;
      p.emplace_back(x1 + side * r * std::cos(a), y + r + r * std::sin(a));
    }
  }
  // Back to the start along the reverse order, so a loop never jumps.
  const std::size_t n = p.size();
  for (std::size_t k = n - 1; k-- > 1;) p.push_back(p[k]);
  return p;
}

struct ActorState {
  Actor spec;
  PathFollower path;
  Eigen::Vector2d position;
  double heading = 0.0;
  double pause_left = 0.0;
  double delay_left = 0.0;
  double gait_phase = 0.0;
  bool moving = false;
};

// Gait::kPlanted: how far a foot is ahead of the body at gait phase @p phase (2 pi a stride of
// kStride_m): standing on the floor for kStance of the stride, from kStance / 2 of a stride ahead
// to as far behind, then swinging forward.
constexpr double kStride_m = 1.4;
constexpr double kStance = 0.6;
double planted_foot_ahead(double phase) {
  const double u = phase / (2.0 * kPi) - std::floor(phase / (2.0 * kPi));  // In [0, 1).
  const double reach = 0.5 * kStance * kStride_m;
  if (u < kStance) return reach - u * kStride_m;
  return -reach + (u - kStance) / (1.0 - kStance) * 2.0 * reach;
}

// The motion over dt at speed v and turn rate w, exactly along the arc.
Pose2 arc_motion(double v, double w, double dt) {
  if (std::abs(w) < 1e-9) return {v * dt, 0.0, 0.0};
  return {v / w * std::sin(w * dt), v / w * (1.0 - std::cos(w * dt)), w * dt};
}

// Wheel speeds and IMU from true motion, with the errors of the scenario.
class OdometrySensors {
 public:
  OdometrySensors(const SensorConfig& c, double wheel_base, std::mt19937_64& rng)
      : c_(c), wheel_base_(wheel_base), rng_(rng) {}

  void measure(double t, double dt, double v, double w, SensorSample& s) {
    std::normal_distribution<double> n01(0.0, 1.0);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double left = v - 0.5 * w * wheel_base_;
    const double right = v + 0.5 * w * wheel_base_;
    if (slip_left_ <= 0.0 && u(rng_) < c_.slips_per_minute / 60.0 * dt) {
      slip_left_ = 0.5;
      slip_wheel_ = u(rng_) < 0.5 ? 0 : 1;
    }
    double slip_l = 1.0, slip_r = 1.0;
    if (slip_left_ > 0.0) {
      (slip_wheel_ == 0 ? slip_l : slip_r) = 1.3;
      slip_left_ -= dt;
    }
    s.wheel_left_mps = left * (1.0 + c_.wheel_scale_error - c_.wheel_difference_error) * slip_l +
                       c_.wheel_noise_mps * n01(rng_);
    s.wheel_right_mps = right * (1.0 + c_.wheel_scale_error + c_.wheel_difference_error) * slip_r +
                        c_.wheel_noise_mps * n01(rng_);
    bias_ += c_.imu_bias_walk_radps * std::sqrt(dt) * n01(rng_);
    s.imu_yaw_rate_radps = w + bias_ + c_.imu_noise_radps * n01(rng_) +
                           c_.imu_vibration_radps * std::abs(v) * std::sin(2.0 * kPi * 15.0 * t);
    // Dead reckoning from the measured wheels (exact arc per step).
    const double vm = 0.5 * (s.wheel_left_mps + s.wheel_right_mps);
    const double wm = (s.wheel_right_mps - s.wheel_left_mps) / wheel_base_;
    odom_ = odom_ * arc_motion(vm, wm, dt);
    s.odom_pose = odom_;
    s.odom_v_mps = vm;
    s.odom_w_radps = wm;
  }

  void start_at(const Pose2& p) { odom_ = p; }

 private:
  SensorConfig c_;
  double wheel_base_;
  std::mt19937_64& rng_;
  double bias_ = 0.0;
  double slip_left_ = 0.0;
  int slip_wheel_ = 0;
  Pose2 odom_;
};

// Distance from p to the segment from a to b (to a when they coincide).
double distance_to_segment(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                           const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double t =
      ab.squaredNorm() > 0.0 ? std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

// Distance from p to the path through @p points (to the point itself when there is one).
double distance_to_path(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& points,
                        bool closed) {
  double best = std::numeric_limits<double>::infinity();
  const std::size_t n = points.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d& b = i + 1 < n ? points[i + 1] : (closed ? points[0] : points[i]);
    best = std::min(best, distance_to_segment(p, points[i], b));
  }
  return best;
}

// How far a walker's legs reach either side of the line it walks (ActorState: 0.1 m, and a leg's
// radius of 0.06 m), and the least gap it leaves when it passes something.
constexpr double kPersonReach_m = 0.16;
constexpr double kPassingGap_m = 0.05;

// How far an actor reaches either side of its path: a person's legs, half a vehicle's width.
double actor_reach(const Actor& actor) {
  return actor.kind == ActorKind::kPerson ? kPersonReach_m : 0.5 * actor.width_m;
}

// Whether a circle at @p center of @p radius leaves every actor's path room to pass: people and
// carts go past furniture, not through it.
bool clear_of_actors(const Eigen::Vector2d& center, double radius,
                     const std::vector<Actor>& actors) {
  for (const Actor& a : actors) {
    if (distance_to_path(center, a.waypoints, a.loop) < radius + actor_reach(a) + kPassingGap_m) {
      return false;
    }
  }
  return true;
}

// Walls as a real building has them (RoughWalls): pieces set back or forward, joined by steps;
// glass pieces left out; doors as gaps with a recess; pairs of furniture legs in front, and low
// things, where no actor's path runs through them (drawn all the same, so the rest of the walls
// do not depend on the actors).
void add_rough_wall(const Segment& wall, const RoughWalls& rw, const std::vector<Actor>& actors,
                    std::mt19937_64& rng, World& out) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const Eigen::Vector2d ab = wall.b - wall.a;
  const double length = ab.norm();
  if (!(length > 1e-9)) return;
  const Eigen::Vector2d d = ab / length;
  const Eigen::Vector2d n(-d.y(), d.x());
  const auto at = [&](double s, double offset) -> Eigen::Vector2d {
    return wall.a + s * d + offset * n;
  };
  double s = 0.0, previous_offset = 0.0;
  bool previous_solid = false;
  while (s < length - 1e-9) {
    const double piece =
        std::min(length - s, rw.piece_min_m + u01(rng) * (rw.piece_max_m - rw.piece_min_m));
    if (u01(rng) < rw.doors_per_10m * piece / 10.0 && piece >= 1.0) {
      // A door: a gap of 0.9 m with a recess 0.25 m deep on one side.
      const double side = u01(rng) < 0.5 ? -1.0 : 1.0;
      const double b0 = s + 0.5 * (piece - 0.9), b1 = b0 + 0.9;
      if (previous_solid && std::abs(previous_offset) > 1e-9)
        out.segments.push_back({at(s, previous_offset), at(s, 0.0)});
      out.segments.push_back({at(s, 0.0), at(b0, 0.0)});
      out.segments.push_back({at(b0, 0.0), at(b0, 0.25 * side)});
      out.segments.push_back({at(b0, 0.25 * side), at(b1, 0.25 * side)});
      out.segments.push_back({at(b1, 0.25 * side), at(b1, 0.0)});
      out.segments.push_back({at(b1, 0.0), at(s + piece, 0.0)});
      previous_offset = 0.0;
      previous_solid = true;
    } else if (u01(rng) < rw.glass_share) {
      // Glass: the scanner sees through it and gets nothing back, or (glass_returns_within_deg)
      // only the beams that meet it nearly square.
      if (rw.glass_returns_within_deg > 0.0) {
        out.segments.push_back(
            {at(s, 0.0), at(s + piece, 0.0), rw.glass_returns_within_deg * kPi / 180.0});
      }
      previous_solid = false;
    } else {
      const double offset = (2.0 * u01(rng) - 1.0) * rw.amplitude_m;
      if (previous_solid && std::abs(offset - previous_offset) > 1e-9)
        out.segments.push_back({at(s, previous_offset), at(s, offset)});
      out.segments.push_back({at(s, offset), at(s + piece, offset)});
      previous_offset = offset;
      previous_solid = true;
    }
    if (u01(rng) < rw.legs_per_10m * piece / 10.0) {
      const double side = u01(rng) < 0.5 ? -1.0 : 1.0;
      const double along = s + u01(rng) * piece;
      const double off = side * (0.15 + u01(rng) * 0.45);
      const Circle first{at(along, off), 0.025};
      const Circle second{at(std::min(length, along + 0.5), off), 0.025};
      if (clear_of_actors(first.center, first.radius_m, actors) &&
          clear_of_actors(second.center, second.radius_m, actors)) {
        out.circles.push_back(first);
        out.circles.push_back(second);
      }
    }
    if (rw.low_things_per_10m > 0.0 && u01(rng) < rw.low_things_per_10m * piece / 10.0) {
      const double side = u01(rng) < 0.5 ? -1.0 : 1.0;
      const double along = s + u01(rng) * piece;
      const double radius = rw.low_things_min_radius_m +
                            u01(rng) * (rw.low_things_max_radius_m - rw.low_things_min_radius_m);
      const double off =
          side * (radius + 0.05 + u01(rng) * 0.3);  // Against the wall, as furniture.
      const Circle thing{
          at(along, off), radius,
          rw.low_things_min_seen_within_m +
              u01(rng) * (rw.low_things_max_seen_within_m - rw.low_things_min_seen_within_m)};
      if (clear_of_actors(thing.center, thing.radius_m, actors)) out.circles.push_back(thing);
    }
    s += piece;
  }
}

// Clutter: count things placed at random in the area, each keep_clear_m (plus its radius) from
// the robot's path and every actor's; a place tried 100 times without success is left empty.
void add_clutter(const Clutter& clutter, const std::vector<Eigen::Vector2d>& robot_points,
                 const std::vector<Actor>& actors, std::mt19937_64& rng, World& out) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  for (int k = 0; k < clutter.count; ++k) {
    const double radius =
        clutter.min_radius_m + u01(rng) * (clutter.max_radius_m - clutter.min_radius_m);
    for (int attempt = 0; attempt < 100; ++attempt) {
      const Eigen::Vector2d p(
          clutter.area_min.x() + u01(rng) * (clutter.area_max.x() - clutter.area_min.x()),
          clutter.area_min.y() + u01(rng) * (clutter.area_max.y() - clutter.area_min.y()));
      const double clear = clutter.keep_clear_m + radius;
      bool ok = distance_to_path(p, robot_points, true) >= clear;
      for (std::size_t a = 0; ok && a < actors.size(); ++a) {
        ok = distance_to_path(p, actors[a].waypoints, actors[a].loop) >= clear;
      }
      if (!ok) continue;
      Circle c{p, radius};
      c.return_share = clutter.return_share;
      out.circles.push_back(c);
      break;
    }
  }
}

// A rack (ShelfRow): uprights at every bay, a box in each bay with probability fill.
void add_shelf_row(const ShelfRow& row, std::mt19937_64& rng, World& out) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const Eigen::Vector2d ab = row.to - row.from;
  const double length = ab.norm();
  if (!(length > 1e-9)) return;
  const Eigen::Vector2d d = ab / length;
  const Eigen::Vector2d n(-d.y(), d.x());
  const double yaw = std::atan2(d.y(), d.x());
  const int bays = std::max(1, static_cast<int>(std::lround(length / row.bay_m)));
  const double bay = length / bays;
  for (int k = 0; k <= bays; ++k) {
    for (const double side : {0.0, row.depth_m}) {
      const Rectangle upright{row.from + k * bay * d + side * n, 0.1, 0.1, yaw};
      for (const Segment& e : rectangle_edges(upright)) out.segments.push_back(e);
    }
    if (k == bays || u01(rng) >= row.fill) continue;
    const double inset = 0.05 + u01(rng) * 0.3;
    const double box_length = bay * (0.5 + 0.4 * u01(rng));
    const double box_depth = std::max(0.1, row.depth_m - 2.0 * inset);
    const Rectangle box{row.from + (k + 0.5) * bay * d + 0.5 * row.depth_m * n, box_length,
                        box_depth, yaw};
    for (const Segment& e : rectangle_edges(box)) out.segments.push_back(e);
  }
}

// The outward normal of the shape a beam hit, for the incidence of the beam.
double incidence_cosine(const World& world, std::int32_t id, const Eigen::Vector2d& origin,
                        const Eigen::Vector2d& direction, double range) {
  const auto segments = static_cast<std::int32_t>(world.segments.size());
  if (id < segments) {
    const double c = incidence_cosine(world.segments[static_cast<std::size_t>(id)], direction);
    return std::isnan(c) ? 1.0 : std::max(0.1, c);
  }
  const Circle& c = world.circles[static_cast<std::size_t>(id - segments)];
  const Eigen::Vector2d normal = origin + range * direction - c.center;
  const double norm = normal.norm();
  if (!(norm > 0.0)) return 1.0;
  return std::max(0.1, std::abs(normal.dot(direction)) / norm);
}

// Any run: a finite duration > 0 whose stamps a bag can hold (32-bit seconds). @p field names the
// duration (the scenario's duration_s or the command line's --duration).
void check_duration(const Scenario& s, double duration_s, const std::string& field) {
  if (!(duration_s > 0.0 && std::isfinite(duration_s))) reject(field, duration_s, "finite and > 0");
  if (!(s.start_time_s + duration_s < 4294967295.0)) {
    reject(field, duration_s,
           "such that start_time_s + duration_s < 2^32 s (a bag's stamps are 32-bit seconds)");
  }
}

// The held form of simulate() keeps the whole run in memory: per scan its ranges, truth and
// actor per beam, per sensor sample one SensorSample. A run that would hold more than
// kMaxHeldRunBytes is refused before any work, naming @p field and the longest duration that
// fits. (The streamed form holds nothing of the run and has no such bound.)
constexpr double kMaxHeldRunBytes = 4.0 * 1024 * 1024 * 1024;

void check_held_run_size(const Scenario& s, double duration_s, const std::string& field) {
  const double beams = static_cast<double>(lidar_geometry(s.lidar).beam_count);
  const double per_scan =
      beams * static_cast<double>(sizeof(float) + sizeof(Truth) + sizeof(std::int32_t)) +
      static_cast<double>(sizeof(ScanFrame));
  const double per_second =
      s.lidar.rate_hz * per_scan + s.sensors.rate_hz * static_cast<double>(sizeof(SensorSample));
  const double longest = kMaxHeldRunBytes / per_second;
  if (duration_s > longest) {
    std::ostringstream rule;
    rule << "at most " << static_cast<long long>(std::floor(longest))
         << " s for this scanner and rates (the run is held in memory, at most 4 GiB)";
    reject(field, duration_s, rule.str().c_str());
  }
}

void check_stops(const std::vector<Stop>& stops, const std::string& field) {
  for (std::size_t i = 0; i < stops.size(); ++i) {
    const std::string at = field + ".stops[" + std::to_string(i) + "]";
    if (!(stops[i].at_s >= 0.0 && std::isfinite(stops[i].at_s)))
      reject(at + ".at_s", stops[i].at_s, "finite and >= 0");
    if (!(stops[i].for_s > 0.0 && std::isfinite(stops[i].for_s)))
      reject(at + ".for_s", stops[i].for_s, "finite and > 0");
  }
}

// Whether @p stops hold whoever has them still at @p t_s seconds into the run.
bool stopped_at(const std::vector<Stop>& stops, double t_s) {
  return std::any_of(stops.begin(), stops.end(),
                     [t_s](const Stop& s) { return t_s >= s.at_s && t_s < s.at_s + s.for_s; });
}

}  // namespace

void Scenario::validate() const {
  if (!(duration_s > 0.0)) reject("duration_s", duration_s, "> 0");
  if (!(start_time_s > 0.0)) reject("start_time_s", start_time_s, "> 0");
  if (!(robot.wheel_base_m > 0.0)) reject("robot.wheel_base_m", robot.wheel_base_m, "> 0");
  if (!(robot.speed_mps >= 0.0)) reject("robot.speed_mps", robot.speed_mps, ">= 0");
  check_stops(robot.stops, "robot");
  if (!(lidar.range_max_m > 0.0)) reject("lidar.range_max_m", lidar.range_max_m, "> 0");
  if (!(lidar.fov_deg > 0.0 && lidar.fov_deg <= 360.0))
    reject("lidar.fov_deg", lidar.fov_deg, "in (0, 360]");
  if (!(lidar.resolution_deg > 0.0)) reject("lidar.resolution_deg", lidar.resolution_deg, "> 0");
  if (lidar.fov_deg / lidar.resolution_deg > 2e6) {
    reject("lidar.resolution_deg", lidar.resolution_deg, "coarse enough for at most 2e6 beams");
  }
  if (!(lidar.rate_hz > 0.0 && lidar.rate_hz <= 100.0))
    reject("lidar.rate_hz", lidar.rate_hz, "in (0, 100]");
  if (!(lidar.range_limit_m >= 0.0)) reject("lidar.range_limit_m", lidar.range_limit_m, ">= 0");
  if (!(lidar.range_noise_m >= 0.0)) reject("lidar.range_noise_m", lidar.range_noise_m, ">= 0");
  if (!(lidar.range_noise_per_m >= 0.0 && lidar.range_noise_per_m <= 1.0))
    reject("lidar.range_noise_per_m", lidar.range_noise_per_m, "in [0, 1]");
  if (!(lidar.incidence_noise >= 0.0 && lidar.incidence_noise <= 10.0))
    reject("lidar.incidence_noise", lidar.incidence_noise, "in [0, 10]");
  if (!(lidar.mixed_pixels >= 0.0 && lidar.mixed_pixels <= 1.0))
    reject("lidar.mixed_pixels", lidar.mixed_pixels, "in [0, 1]");
  if (!(lidar.speckle >= 0.0 && lidar.speckle < 1.0))
    reject("lidar.speckle", lidar.speckle, "in [0, 1)");
  if (lidar.speckle > 0.0) {
    const auto [near_m, far_m] = lidar.speckle_range_m;
    if (!(near_m > 0.0 && near_m <= lidar.range_max_m))
      reject("lidar.speckle_range_m[0]", near_m, "in (0, lidar.range_max_m]");
    if (!(far_m >= near_m && far_m <= lidar.range_max_m))
      reject("lidar.speckle_range_m[1]", far_m, "in [speckle_range_m[0], lidar.range_max_m]");
    if (!(lidar.speckle_beams_max >= 1 && lidar.speckle_beams_max <= 64))
      reject("lidar.speckle_beams_max", lidar.speckle_beams_max, "in [1, 64]");
  }
  if (!(lidar.dark_share >= 0.0 && lidar.dark_share <= 1.0))
    reject("lidar.dark_share", lidar.dark_share, "in [0, 1]");
  if (lidar.dark_share > 0.0 &&
      !(lidar.dark_reach_m > 0.0 && lidar.dark_reach_m <= lidar.range_max_m))
    reject("lidar.dark_reach_m", lidar.dark_reach_m, "in (0, lidar.range_max_m]");
  if (!(lidar.bumps_per_min >= 0.0 && lidar.bumps_per_min <= 60.0))
    reject("lidar.bumps_per_min", lidar.bumps_per_min, "in [0, 60]");
  if (lidar.bumps_per_min > 0.0) {
    if (!(lidar.height_m > 0.0 && lidar.height_m <= 5.0))
      reject("lidar.height_m", lidar.height_m, "in (0, 5] with bumps");
    if (!(lidar.bump_tilt_deg > 0.0 && lidar.bump_tilt_deg <= 30.0))
      reject("lidar.bump_tilt_deg", lidar.bump_tilt_deg, "in (0, 30] with bumps");
    if (!(lidar.bump_s > 0.0 && lidar.bump_s <= 60.0 / lidar.bumps_per_min))
      reject("lidar.bump_s", lidar.bump_s, "in (0, 60 / bumps_per_min]");
  }
  if (world.rough_walls) {
    const RoughWalls& w = *world.rough_walls;
    if (!(w.amplitude_m >= 0.0 && w.amplitude_m <= 1.0))
      reject("world.rough_walls.amplitude_m", w.amplitude_m, "in [0, 1]");
    if (!(w.piece_min_m >= 0.05)) reject("world.rough_walls.piece_min_m", w.piece_min_m, ">= 0.05");
    if (!(w.piece_max_m >= w.piece_min_m && w.piece_max_m <= 100.0))
      reject("world.rough_walls.piece_max_m", w.piece_max_m, "in [piece_min_m, 100]");
    if (!(w.doors_per_10m >= 0.0 && w.doors_per_10m <= 10.0))
      reject("world.rough_walls.doors_per_10m", w.doors_per_10m, "in [0, 10]");
    if (!(w.legs_per_10m >= 0.0 && w.legs_per_10m <= 20.0))
      reject("world.rough_walls.legs_per_10m", w.legs_per_10m, "in [0, 20]");
    if (!(w.glass_share >= 0.0 && w.glass_share < 1.0))
      reject("world.rough_walls.glass_share", w.glass_share, "in [0, 1)");
    if (!(w.glass_returns_within_deg >= 0.0 && w.glass_returns_within_deg < 90.0))
      reject("world.rough_walls.glass_returns_within_deg", w.glass_returns_within_deg,
             "in [0, 90)");
    if (!(w.low_things_per_10m >= 0.0 && w.low_things_per_10m <= 20.0))
      reject("world.rough_walls.low_things_per_10m", w.low_things_per_10m, "in [0, 20]");
    // A pair [min, max]: the value named is min when it is the one out of bounds, else max.
    const auto check_pair = [](const char* key, double min, double max, double limit,
                               const char* rule) {
      if (!(min > 0.0)) reject(key, min, rule);
      if (!(max >= min && max <= limit)) reject(key, max, rule);
    };
    check_pair("world.rough_walls.low_things_radius_m", w.low_things_min_radius_m,
               w.low_things_max_radius_m, 2.0, "0 < min <= max <= 2");
    check_pair("world.rough_walls.low_things_seen_within_m", w.low_things_min_seen_within_m,
               w.low_things_max_seen_within_m, 100.0, "0 < min <= max <= 100");
  }
  const Clutter& clutter = world.clutter;
  if (clutter.count < 0 || clutter.count > 100000)
    reject("world.clutter.count", clutter.count, "in [0, 100000]");
  if (clutter.count > 0) {
    if (!(clutter.area_max.array() > clutter.area_min.array()).all() ||
        !((clutter.area_max - clutter.area_min).norm() <= 10000.0)) {
      throw std::invalid_argument(
          "world.clutter.area must have max > min in x and y, at most 10 km apart");
    }
    if (!(clutter.min_radius_m > 0.0 && clutter.min_radius_m <= clutter.max_radius_m &&
          clutter.max_radius_m <= 2.0)) {
      reject("world.clutter.radius_m", clutter.max_radius_m, "0 < min <= max <= 2");
    }
    if (!(clutter.return_share > 0.0 && clutter.return_share <= 1.0))
      reject("world.clutter.return_share", clutter.return_share, "in (0, 1]");
    if (!(clutter.keep_clear_m >= 0.0 && clutter.keep_clear_m <= 100.0))
      reject("world.clutter.keep_clear_m", clutter.keep_clear_m, "in [0, 100]");
  }
  for (std::size_t i = 0; i < world.shelves.size(); ++i) {
    const ShelfRow& r = world.shelves[i];
    const std::string field = "world.shelves[" + std::to_string(i) + "]";
    if (!(r.depth_m >= 0.2 && r.depth_m <= 10.0))
      reject(field + ".depth_m", r.depth_m, "in [0.2, 10]");
    if (!(r.bay_m >= 0.5 && r.bay_m <= 20.0)) reject(field + ".bay_m", r.bay_m, "in [0.5, 20]");
    if (!(r.fill >= 0.0 && r.fill <= 1.0)) reject(field + ".fill", r.fill, "in [0, 1]");
    if (!((r.to - r.from).norm() <= 1000.0))
      reject(field + ".to", (r.to - r.from).norm(), "at most 1000 m from .from");
  }
  if (!(lidar.dropout >= 0.0 && lidar.dropout < 1.0))
    reject("lidar.dropout", lidar.dropout, "in [0, 1)");
  if (!(sensors.rate_hz > 0.0 && sensors.rate_hz <= 100.0))
    reject("sensors.rate_hz", sensors.rate_hz, "in (0, 100]");
  if (robot.lawnmower) {
    const Lawnmower& l = *robot.lawnmower;
    if (l.lanes < 1 || l.lanes > 10000) reject("robot.lawnmower.lanes", l.lanes, "in [1, 10000]");
    if (!(l.lane_length_m > 0.0 && l.lane_length_m <= 10000.0))
      reject("robot.lawnmower.lane_length_m", l.lane_length_m, "in (0, 10000]");
    if (!(l.lane_spacing_m > 0.0 && l.lane_spacing_m <= 1000.0))
      reject("robot.lawnmower.lane_spacing_m", l.lane_spacing_m, "in (0, 1000]");
  }
  for (std::size_t i = 0; i < actors.size(); ++i) {
    const Actor& a = actors[i];
    const std::string field = "actors[" + std::to_string(i) + "]";
    if (a.waypoints.empty()) throw std::invalid_argument(field + " needs at least a start point");
    if (!(a.speed_mps >= 0.0 && a.speed_mps <= 10.0))
      reject(field + ".speed_mps", a.speed_mps, "in [0, 10]");
    if (!(a.pause_s >= 0.0)) reject(field + ".pause_s", a.pause_s, ">= 0");
    check_stops(a.stops, field);
  }
  // Bounds on what the run is made of: each person is ray-cast for every beam of every scan,
  // each waypoint and lane is held in memory.
  constexpr double kMaxPeople = 10000, kMaxWaypoints = 100000;
  if (static_cast<double>(actors.size()) > kMaxPeople) {
    reject("actors", static_cast<double>(actors.size()), "at most 10000 actors");
  }
  for (std::size_t i = 0; i < actors.size(); ++i) {
    if (static_cast<double>(actors[i].waypoints.size()) > kMaxWaypoints) {
      reject("actors[" + std::to_string(i) + "].waypoints",
             static_cast<double>(actors[i].waypoints.size()), "at most 100000 waypoints");
    }
  }
  if (static_cast<double>(robot.waypoints.size()) > kMaxWaypoints) {
    reject("robot.waypoints", static_cast<double>(robot.waypoints.size()),
           "at most 100000 waypoints");
  }
  if (random_people.count < 0) reject("random_people.count", random_people.count, ">= 0");
  if (random_people.count > kMaxPeople)
    reject("random_people.count", random_people.count, "at most 10000");
  if (random_people.waypoints < 0 || random_people.waypoints > kMaxWaypoints)
    reject("random_people.waypoints", random_people.waypoints, "in [0, 100000]");
  if (static_cast<double>(actors.size()) + random_people.count > kMaxPeople) {
    reject("random_people.count", random_people.count, "at most 10000 people with the actors");
  }
  check_duration(*this, duration_s, "duration_s");
  if (random_people.count > 0 &&
      !(random_people.area_max.array() > random_people.area_min.array()).all()) {
    throw std::invalid_argument("random_people.area must have max > min in x and y");
  }
}

ScanGeometry lidar_geometry(const LidarConfig& lidar) {
  const auto n = static_cast<std::int32_t>(std::lround(lidar.fov_deg / lidar.resolution_deg)) +
                 (lidar.fov_deg >= 360.0 ? 0 : 1);
  const double increment = lidar.fov_deg * kDeg / (lidar.fov_deg >= 360.0 ? n : n - 1);
  // A scanner whose range is cut reports the cut as its maximum range.
  const double range_max = lidar.range_limit_m > 0.0
                               ? std::min(lidar.range_limit_m, lidar.range_max_m)
                               : lidar.range_max_m;
  return {-0.5 * lidar.fov_deg * kDeg, increment, n, 0.05F, static_cast<float>(range_max)};
}

std::vector<Segment> rectangle_edges(const Rectangle& r) {
  const Eigen::Vector2d ax(std::cos(r.yaw_rad), std::sin(r.yaw_rad));
  const Eigen::Vector2d ay(-ax.y(), ax.x());
  const Eigen::Vector2d a = r.center + 0.5 * r.length_m * ax + 0.5 * r.width_m * ay;
  const Eigen::Vector2d b = r.center - 0.5 * r.length_m * ax + 0.5 * r.width_m * ay;
  const Eigen::Vector2d c = r.center - 0.5 * r.length_m * ax - 0.5 * r.width_m * ay;
  const Eigen::Vector2d d = r.center + 0.5 * r.length_m * ax - 0.5 * r.width_m * ay;
  return {{a, b}, {b, c}, {c, d}, {d, a}};
}

namespace {

// Distance between the segments ab and cd (0 when they cross).
double segments_distance(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                         const Eigen::Vector2d& c, const Eigen::Vector2d& d) {
  const auto cross = [](const Eigen::Vector2d& u, const Eigen::Vector2d& v) {
    return u.x() * v.y() - u.y() * v.x();
  };
  const double d1 = cross(b - a, c - a), d2 = cross(b - a, d - a);
  const double d3 = cross(d - c, a - c), d4 = cross(d - c, b - c);
  if (((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0)) &&
      ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))) {
    return 0.0;
  }
  return std::min({distance_to_segment(a, c, d), distance_to_segment(b, c, d),
                   distance_to_segment(c, a, b), distance_to_segment(d, a, b)});
}

// A scripted actor walks or drives past the walls, rectangles and circles of the world, not
// through them: refused, naming the actor and the obstacle, when its path (back to its start if it
// loops) comes nearer to one than the actor reaches: a person's legs 0.16 m either side of the
// path; a vehicle half its width, each leg of its path lengthened at both ends so that its nose
// reaches half its length beyond a waypoint (its tail as far behind).
void check_actor_paths(const Scenario& scenario) {
  for (std::size_t i = 0; i < scenario.actors.size(); ++i) {
    const Actor& actor = scenario.actors[i];
    const bool person = actor.kind == ActorKind::kPerson;
    const double reach = actor_reach(actor);
    const double overhang = person ? 0.0 : std::max(0.0, 0.5 * (actor.length_m - actor.width_m));
    std::vector<Eigen::Vector2d> points = actor.waypoints;
    if (actor.loop && points.size() > 1) points.push_back(points.front());
    if (points.size() == 1) points.push_back(points.front());
    const auto refuse = [&](const char* what, const Eigen::Vector2d& at, double distance) {
      std::ostringstream m;
      m.setf(std::ios::fixed);
      m.precision(2);
      m << "actors[" << i << "] (a " << (person ? "person" : "vehicle") << ") goes through the "
        << what << " at (" << at.x() << ", " << at.y() << "): its path passes " << distance
        << " m from it, and it reaches " << reach
        << " m either side of its path (move its waypoints or the " << what << ")";
      throw std::invalid_argument(m.str());
    };
    for (std::size_t k = 0; k + 1 < points.size(); ++k) {
      const Eigen::Vector2d along = points[k + 1] - points[k];
      const Eigen::Vector2d ahead = along.norm() > 0.0
                                        ? Eigen::Vector2d(overhang * along.normalized())
                                        : Eigen::Vector2d::Zero();
      const Eigen::Vector2d p = points[k] - ahead;
      const Eigen::Vector2d q = points[k + 1] + ahead;
      for (const Segment& wall : scenario.world.walls) {
        const double d = segments_distance(p, q, wall.a, wall.b);
        if (d < reach) refuse("wall", 0.5 * (wall.a + wall.b), d);
      }
      for (const Rectangle& r : scenario.world.rectangles) {
        for (const Segment& e : rectangle_edges(r)) {
          const double d = segments_distance(p, q, e.a, e.b);
          if (d < reach) refuse("rectangle", r.center, d);
        }
      }
      for (const Circle& c : scenario.world.circles) {
        const double d = std::max(0.0, distance_to_segment(c.center, p, q) - c.radius_m);
        if (d < reach) refuse("circle", c.center, d);
      }
    }
  }
}

}  // namespace

SimulationOutput simulate(const Scenario& scenario, std::uint64_t seed, double duration_s) {
  scenario.validate();
  const bool given = !(duration_s <= 0.0);  // NaN too: refused below.
  const double duration = given ? duration_s : scenario.duration_s;
  const std::string field = given ? "--duration" : "duration_s";
  check_duration(scenario, duration, field);
  check_held_run_size(scenario, duration, field);
  SimulationOutput out;
  SimulationSink sink;
  sink.scan = [&out](ScanFrame&& frame) { out.scans.push_back(std::move(frame)); };
  sink.sensor = [&out](const SensorSample& sample) { out.sensors.push_back(sample); };
  out.actor_count = simulate(scenario, seed, duration_s, sink);
  return out;
}

double run_duration(const Scenario& scenario, double duration_s) {
  scenario.validate();
  check_actor_paths(scenario);
  const bool given = !(duration_s <= 0.0);  // NaN too: refused.
  if (!given) return scenario.duration_s;
  check_duration(scenario, duration_s, "--duration");
  return duration_s;
}

std::int32_t simulate(const Scenario& scenario, std::uint64_t seed, double duration_s,
                      const SimulationSink& sink) {
  const double duration = run_duration(scenario, duration_s);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  std::uniform_real_distribution<double> u01(0.0, 1.0);

  // Actors: scripted, then generated from the seed.
  std::vector<ActorState> actors;
  std::vector<Actor> specs = scenario.actors;
  const RandomPeople& rp = scenario.random_people;
  // People walk around pillars and machines, not through them: a leg of a path must keep 0.5 m
  // from every static circle and rectangle (taken as its circumscribed circle).
  std::vector<std::pair<Eigen::Vector2d, double>> obstacles;
  for (const Circle& c : scenario.world.circles) obstacles.emplace_back(c.center, c.radius_m + 0.5);
  for (const Rectangle& r : scenario.world.rectangles) {
    obstacles.emplace_back(r.center, 0.5 * std::hypot(r.length_m, r.width_m) + 0.5);
  }
  const auto clear_path = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    for (const auto& [c, r] : obstacles) {
      if (distance_to_segment(c, a, b) < r) return false;
    }
    return true;
  };
  const auto random_point = [&]() {
    return Eigen::Vector2d(rp.area_min.x() + u01(rng) * (rp.area_max.x() - rp.area_min.x()),
                           rp.area_min.y() + u01(rng) * (rp.area_max.y() - rp.area_min.y()));
  };
  for (int p = 0; p < rp.count; ++p) {
    Actor a;
    for (int w = 0; w < std::max(2, rp.waypoints); ++w) {
      Eigen::Vector2d next = random_point();
      for (int attempt = 0; attempt < 100; ++attempt) {
        const bool ok =
            a.waypoints.empty() ? clear_path(next, next) : clear_path(a.waypoints.back(), next);
        if (ok) break;
        next = random_point();
      }
      a.waypoints.push_back(next);
    }
    a.speed_mps = rp.min_speed_mps + u01(rng) * (rp.max_speed_mps - rp.min_speed_mps);
    a.pause_s = u01(rng) * rp.max_pause_s;
    a.loop = rp.loop;
    specs.push_back(a);
  }
  for (const Actor& a : specs) {
    std::vector<Eigen::Vector2d> rest(a.waypoints.begin() + 1, a.waypoints.end());
    if (a.loop && !rest.empty()) rest.push_back(a.waypoints.front());
    ActorState s{a,
                 PathFollower(rest, a.loop),
                 a.waypoints.front(),
                 0.0,
                 0.0,
                 a.start_delay_s,
                 u01(rng) * 2.0 * kPi,
                 false};
    actors.push_back(std::move(s));
  }

  // The robot's path.
  std::vector<Eigen::Vector2d> robot_points = scenario.robot.lawnmower
                                                  ? lawnmower_path(*scenario.robot.lawnmower)
                                                  : scenario.robot.waypoints;
  PathFollower robot_path(robot_points, scenario.robot.loop);
  Pose2 pose = scenario.robot.start;
  Eigen::Vector2d leg_from = pose.translation();  // Where the robot's current leg starts.

  // Static shapes once. Rough walls and shelves are drawn from a generator of their own, so that
  // a scenario without them gets the same noise as before they existed.
  World base;
  std::mt19937_64 world_rng(seed ^ 0x5eed5eed5eedULL);
  if (scenario.world.rough_walls) {
    for (const Segment& wall : scenario.world.walls)
      add_rough_wall(wall, *scenario.world.rough_walls, specs, world_rng, base);
  } else {
    base.segments = scenario.world.walls;
  }
  for (const ShelfRow& row : scenario.world.shelves) add_shelf_row(row, world_rng, base);
  for (const Rectangle& r : scenario.world.rectangles) {
    for (const Segment& s : rectangle_edges(r)) base.segments.push_back(s);
  }
  base.circles.insert(base.circles.end(), scenario.world.circles.begin(),
                      scenario.world.circles.end());
  {
    std::vector<Eigen::Vector2d> robot_route = robot_points;  // From where the robot starts.
    robot_route.insert(robot_route.begin(), scenario.robot.start.translation());
    add_clutter(scenario.world.clutter, robot_route, specs, world_rng, base);
  }
  // What the robot must never drive through: the walls as drawn (rough walls' pieces have gaps
  // for glass), rectangles and the lines of the shelf rows.
  std::vector<Segment> solid = scenario.world.walls;
  for (const Rectangle& r : scenario.world.rectangles) {
    for (const Segment& s : rectangle_edges(r)) solid.push_back(s);
  }
  for (const ShelfRow& row : scenario.world.shelves) solid.push_back({row.from, row.to});
  const auto static_segments = static_cast<std::int32_t>(base.segments.size());
  const auto static_circles = static_cast<std::int32_t>(base.circles.size());

  const LidarConfig& lidar = scenario.lidar;
  const ScanGeometry geometry = lidar_geometry(lidar);
  std::vector<char> masked(static_cast<std::size_t>(geometry.beam_count), 0);
  for (std::int32_t i = 0; i < geometry.beam_count; ++i) {
    const double b = (geometry.angle_min_rad + i * geometry.angle_increment_rad) / kDeg;
    for (const auto& [lo, hi] : lidar.masked_sectors_deg) {
      if (b >= lo && b <= hi) masked[static_cast<std::size_t>(i)] = 1;
    }
  }

  const auto actor_count = static_cast<std::int32_t>(actors.size());
  OdometrySensors sensors(scenario.sensors, scenario.robot.wheel_base_m, rng);
  sensors.start_at(pose);
  const auto steps = static_cast<std::int64_t>(std::floor(duration / kStep + 1e-9));
  const auto sensor_every =
      std::max<std::int64_t>(1, std::lround(1.0 / (scenario.sensors.rate_hz * kStep)));
  const auto scan_every = std::max<std::int64_t>(1, std::lround(1.0 / (lidar.rate_hz * kStep)));
  double v = 0.0, w = 0.0;

  // The sweep: beam i is measured at i * time_increment after the stamp, from where the laser is
  // then (the robot's motion over that time at its current speed and turn rate).
  const double time_increment = lidar.sweep ? lidar.resolution_deg / (360.0 * lidar.rate_hz) : 0.0;
  const auto beam_pose = [&](const Pose2& robot, double vv, double ww, double dt) {
    if (dt <= 0.0) return robot * scenario.robot.laser_mount;
    return robot * arc_motion(vv, ww, dt) * scenario.robot.laser_mount;
  };
  // Casts the scan, in blocks of beams that share one laser pose (8 beams: 1.5 mm apart at
  // 1.5 m/s and 0.17 degrees at 20 Hz).
  const auto cast_scan = [&](const World& world, const Pose2& robot, double vv, double ww,
                             LaserScan& scan, std::vector<std::int32_t>& hit) {
    scan = raycast(world, robot * scenario.robot.laser_mount, geometry, &hit);
    if (time_increment <= 0.0) return;
    constexpr std::int32_t kBlock = 8;
    std::vector<std::int32_t> block_hit;
    for (std::int32_t b0 = 0; b0 < geometry.beam_count; b0 += kBlock) {
      ScanGeometry g = geometry;
      g.angle_min_rad = geometry.angle_min_rad + b0 * geometry.angle_increment_rad;
      g.beam_count = std::min(kBlock, geometry.beam_count - b0);
      const double dt = (b0 + 0.5 * (g.beam_count - 1)) * time_increment;
      const LaserScan part = raycast(world, beam_pose(robot, vv, ww, dt), g, &block_hit);
      for (std::int32_t k = 0; k < g.beam_count; ++k) {
        scan.ranges_m[static_cast<std::size_t>(b0 + k)] =
            part.ranges_m[static_cast<std::size_t>(k)];
        hit[static_cast<std::size_t>(b0 + k)] = block_hit[static_cast<std::size_t>(k)];
      }
    }
  };
  // Mixed pixels: the beam at a depth edge, on the near side, returns a range between.
  const auto add_mixed_pixels = [&](LaserScan& scan, const std::vector<std::int32_t>& hit) {
    if (!(lidar.mixed_pixels > 0.0)) return;
    const std::vector<float> ideal = scan.ranges_m;
    for (std::size_t i = 0; i < ideal.size(); ++i) {
      if (hit[i] < 0) continue;
      for (const std::size_t j : {i - 1, i + 1}) {
        if (j >= ideal.size() || hit[j] < 0 || !(ideal[j] > ideal[i] + 0.2F)) continue;
        if (u01(rng) < lidar.mixed_pixels) {
          scan.ranges_m[i] = ideal[i] + static_cast<float>(u01(rng)) * (ideal[j] - ideal[i]);
          break;
        }
      }
    }
  };

  // Whether static shape @p id (raycast's numbering) is drawn dark (LidarConfig::dark_share).
  const auto dark = [&](std::int32_t id) {
    return lidar.dark_share > 0.0 &&
           unit_draw(seed, static_cast<std::uint64_t>(id), kDarkDraw) < lidar.dark_share;
  };

  // The scan plane's tilt at time t (LidarConfig::bumps_per_min): nose down (pitch) and to the
  // left side down (roll), radians; zero between bumps.
  const auto tilt = [&](double t) -> std::pair<double, double> {
    if (!(lidar.bumps_per_min > 0.0)) return {0.0, 0.0};
    const double slot_s = 60.0 / lidar.bumps_per_min;
    const double at = t - scenario.start_time_s;
    const auto slot = static_cast<std::int64_t>(std::floor(at / slot_s));
    for (std::int64_t k = slot; k >= slot - 1 && k >= 0; --k) {
      const auto key = static_cast<std::uint64_t>(k);
      const double start = (static_cast<double>(k) +
                            unit_draw(seed, key, kBumpTimeDraw) * (1.0 - lidar.bump_s / slot_s)) *
                           slot_s;
      const double phase = (at - start) / lidar.bump_s;
      if (phase < 0.0 || phase > 1.0) continue;
      const double size =
          unit_draw(seed, key, kBumpSizeDraw) * lidar.bump_tilt_deg * kDeg * std::sin(kPi * phase);
      const double lean = 2.0 * unit_draw(seed, key, kBumpLeanDraw) - 1.0;
      return {size, lean * size};
    }
    return {0.0, 0.0};
  };
  // Where beam i of a scan taken at t, at bearing @p bearing_rad in the laser frame, meets the
  // floor (infinity where it does not descend).
  const double mount_yaw = scenario.robot.laser_mount.yaw_rad;
  const auto floor_range = [&](double t, double bearing_rad) {
    const auto [pitch, roll] = tilt(t);
    const double phi = mount_yaw + bearing_rad;
    const double descent = std::tan(pitch) * std::cos(phi) + std::tan(roll) * std::sin(phi);
    return descent > 1e-9 ? lidar.height_m / descent : std::numeric_limits<double>::infinity();
  };

  // The floor where a tilted beam meets it nearer than what it returned (or within reach where it
  // returned nothing), after every other draw of the scan: its noise is hashed, not drawn, so that
  // the rest of the run is as it would be without bumps.
  const auto add_floor = [&](ScanFrame& frame, double t, std::int64_t step) {
    if (!(lidar.bumps_per_min > 0.0)) return;
    const double reach = lidar.range_limit_m > 0.0
                             ? std::min(lidar.range_limit_m, lidar.range_max_m)
                             : lidar.range_max_m;
    for (std::size_t i = 0; i < frame.truth.size(); ++i) {
      if (masked[i] != 0) continue;
      const double g =
          floor_range(t + static_cast<double>(i) * time_increment, frame.scan.bearing_rad(i));
      float& r = frame.scan.ranges_m[i];
      if (!(g <= reach && g >= geometry.range_min_m) ||
          (frame.truth[i] != Truth::kNoReturn && !(g < r))) {
        continue;
      }
      const auto key = (static_cast<std::uint64_t>(step) << 20) + i;
      const double u1 = std::max(unit_draw(seed, key, kFloorNoiseDraw), 1e-12);
      const double u2 = unit_draw(seed, key, kFloorNoiseDraw + 1);
      const double normal = std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
      r = static_cast<float>(g + (lidar.range_noise_m + lidar.range_noise_per_m * g) * normal);
      frame.truth[i] = Truth::kStatic;
      frame.actor[i] = 0;
    }
  };

  // Speckle: runs of beams that reached nothing in range return one range in the band (see
  // LidarConfig::speckle).
  const auto add_speckle = [&](ScanFrame& frame, const std::vector<std::int32_t>& hit) {
    if (!(lidar.speckle > 0.0)) return;
    const auto open = [&](std::size_t i) {
      return masked[i] == 0 && hit[i] < 0 && frame.truth[i] == Truth::kNoReturn;
    };
    const std::size_t n = frame.truth.size();
    for (std::size_t i = 0; i < n; ++i) {
      if (!open(i) || !(u01(rng) < lidar.speckle)) continue;
      const auto [near_m, far_m] = lidar.speckle_range_m;
      const double range = near_m + u01(rng) * (far_m - near_m);
      const double sigma = lidar.range_noise_m + lidar.range_noise_per_m * range;
      const std::size_t end = std::min(
          n, i + 1 +
                 static_cast<std::size_t>(u01(rng) * static_cast<double>(lidar.speckle_beams_max)));
      std::size_t j = i;
      for (; j < end && open(j); ++j) {
        frame.scan.ranges_m[j] = static_cast<float>(
            std::max(static_cast<double>(geometry.range_min_m), range + sigma * n01(rng)));
        frame.truth[j] = Truth::kStatic;
      }
      i = j;  // The beam after a run returns nothing, as it did (the loop moves past it).
    }
  };

  for (std::int64_t step = 0; step <= steps; ++step) {
    const double t = scenario.start_time_s + static_cast<double>(step) * kStep;
    // Sensors and scans see the state at t; then the world moves on by one step.
    // The sample is measured before the scan is cast (the order the noise is drawn in) and
    // handed on after it: at the same instant the scan comes first.
    const bool sample_now = step % sensor_every == 0;
    SensorSample sample;
    if (sample_now) {
      sample.stamp_s = t;
      sample.true_pose = pose;
      sample.true_v_mps = v;
      sample.true_w_radps = w;
      sensors.measure(t, static_cast<double>(sensor_every) * kStep, v, w, sample);
    }
    if (step % scan_every == 0) {
      World world = base;
      world.flicker_seed = seed * 0x9e3779b97f4a7c15ULL + static_cast<std::uint64_t>(step);
      std::vector<std::int32_t> actor_of_segment, actor_of_circle;
      for (std::size_t a = 0; a < actors.size(); ++a) {
        const ActorState& s = actors[a];
        const Eigen::Vector2d fwd(std::cos(s.heading), std::sin(s.heading));
        const Eigen::Vector2d left(-fwd.y(), fwd.x());
        if (s.spec.kind == ActorKind::kPerson) {
          const bool planted = scenario.gait == Gait::kPlanted;
          const double ahead_a =
              planted ? planted_foot_ahead(s.gait_phase) : 0.15 * std::sin(s.gait_phase);
          const double ahead_b = planted ? planted_foot_ahead(s.gait_phase + kPi) : -ahead_a;
          world.circles.push_back({s.position + ahead_a * fwd + 0.1 * left, 0.06});
          world.circles.push_back({s.position + ahead_b * fwd - 0.1 * left, 0.06});
          actor_of_circle.insert(actor_of_circle.end(), 2, static_cast<std::int32_t>(a));
        } else {
          for (const Segment& e :
               rectangle_edges({s.position, s.spec.length_m, s.spec.width_m, s.heading})) {
            world.segments.push_back(e);
            actor_of_segment.push_back(static_cast<std::int32_t>(a));
          }
        }
      }
      // Cart edges come after the static segments; shift circle ids accordingly.
      const auto segment_count = static_cast<std::int32_t>(world.segments.size());
      ScanFrame frame;
      frame.base_pose = pose;
      std::vector<std::int32_t> hit;
      cast_scan(world, pose, v, w, frame.scan, hit);
      frame.scan.stamp_s = t;
      frame.scan.time_increment_s = time_increment;
      add_mixed_pixels(frame.scan, hit);
      frame.truth.assign(hit.size(), Truth::kNoReturn);
      frame.actor.assign(hit.size(), 0);
      for (std::size_t i = 0; i < hit.size(); ++i) {
        float& r = frame.scan.ranges_m[i];
        if (masked[i] != 0) {
          r = std::numeric_limits<float>::quiet_NaN();
          continue;
        }
        const bool beyond_limit = lidar.range_limit_m > 0.0 && r > lidar.range_limit_m;
        // Nearer than the scanner's minimum range (someone touching it) is no return either.
        const bool too_close = r < geometry.range_min_m;
        if (hit[i] < 0 || beyond_limit || too_close || u01(rng) < lidar.dropout) {
          r = std::numeric_limits<float>::infinity();
          continue;
        }
        double sigma = lidar.range_noise_m + lidar.range_noise_per_m * r;
        if (lidar.incidence_noise > 0.0) {
          const double bearing = frame.scan.bearing_rad(i);
          const Pose2 laser = beam_pose(pose, v, w, static_cast<double>(i) * time_increment);
          const Eigen::Vector2d dir(std::cos(laser.yaw_rad + bearing),
                                    std::sin(laser.yaw_rad + bearing));
          const double c = incidence_cosine(world, hit[i], laser.translation(), dir, r);
          sigma *= 1.0 + lidar.incidence_noise * (1.0 / c - 1.0);
        }
        r += static_cast<float>(sigma * n01(rng));
        if (r < geometry.range_min_m) {  // Noise cannot make a return nearer than the minimum.
          r = std::numeric_limits<float>::infinity();
          continue;
        }
        std::int32_t actor = -1;
        const std::int32_t id = hit[i];
        if (id >= static_segments && id < segment_count) {
          actor = actor_of_segment[static_cast<std::size_t>(id - static_segments)];
        } else if (id >= segment_count + static_circles) {
          actor = actor_of_circle[static_cast<std::size_t>(id - segment_count - static_circles)];
        }
        if (actor < 0 && r > lidar.dark_reach_m && dark(id)) {
          // A dark surface beyond its reach returns nothing. Its draws were made all the same, so
          // that every other beam is as it would be without dark surfaces.
          r = std::numeric_limits<float>::infinity();
        } else if (actor < 0) {
          frame.truth[i] = Truth::kStatic;
        } else {
          frame.truth[i] =
              actors[static_cast<std::size_t>(actor)].moving ? Truth::kMoving : Truth::kStill;
          frame.actor[i] = actor + 1;
        }
      }
      add_floor(frame, t, step);
      add_speckle(frame, hit);
      if (sink.scan) sink.scan(std::move(frame));
    }
    if (sample_now && sink.sensor) sink.sensor(sample);

    // Robot: follow the leg from the last waypoint to the next (pure pursuit of a point
    // kLookahead_m ahead on it), slow down while turning and before corners, and turn in
    // kCornerRadius_m before a corner; its motors change speed and turn rate at most
    // kMaxAcceleration and kMaxAngularAcceleration.
    double v_cmd = 0.0, w_cmd = 0.0;
    const auto corner_at_target = [&] {
      const Eigen::Vector2d* after = robot_path.after_target();
      if (after == nullptr) return false;
      const Eigen::Vector2d in = robot_path.target() - leg_from;
      const Eigen::Vector2d out = *after - robot_path.target();
      return std::abs(wrap_angle(std::atan2(out.y(), out.x()) - std::atan2(in.y(), in.x()))) >
             kCornerTurn_rad;
    };
    const double run_s = t - scenario.start_time_s;
    if (!robot_path.done() && !stopped_at(scenario.robot.stops, run_s)) {
      const Eigen::Vector2d reached = robot_path.target();
      bool corner = corner_at_target();
      if (robot_path.advance_if_reached(pose.translation(), corner ? kCornerRadius_m : 0.15)) {
        leg_from = reached;
        corner = corner_at_target();
      }
      if (!robot_path.done()) {
        const Eigen::Vector2d to = robot_path.target() - pose.translation();
        const Eigen::Vector2d leg = robot_path.target() - leg_from;
        Eigen::Vector2d aim = robot_path.target();
        const double leg_length = leg.norm();
        if (leg_length > 1e-9) {
          const Eigen::Vector2d along = leg / leg_length;
          const double at = std::max(0.0, along.dot(pose.translation() - leg_from)) + kLookahead_m;
          if (at < leg_length) aim = leg_from + at * along;
        }
        const Eigen::Vector2d to_aim = aim - pose.translation();
        const double err = wrap_angle(std::atan2(to_aim.y(), to_aim.x()) - pose.yaw_rad);
        w_cmd = std::clamp(2.0 * err, -kMaxTurnRate, kMaxTurnRate);
        v_cmd = scenario.robot.speed_mps * std::max(0.0, std::cos(err));
        if (corner) {
          const double v_corner = kMaxTurnRate * kCornerRadius_m;
          const double braking = std::max(0.0, to.norm() - kCornerRadius_m);
          v_cmd =
              std::min(v_cmd, std::sqrt(v_corner * v_corner + 2.0 * kMaxAcceleration * braking));
        }
      }
    }
    v += std::clamp(v_cmd - v, -kMaxAcceleration * kStep, kMaxAcceleration * kStep);
    w += std::clamp(w_cmd - w, -kMaxAngularAcceleration * kStep, kMaxAngularAcceleration * kStep);
    const Eigen::Vector2d was = pose.translation();
    pose = pose * Pose2{v * kStep, 0.0, w * kStep};
    const Eigen::Vector2d moved = pose.translation() - was;
    const double moved_m = moved.norm();
    for (const Segment& wall : solid) {
      if (!(moved_m > 0.0 && ray_distance(wall, was, moved / moved_m) <= moved_m)) continue;
      std::ostringstream m;
      m.setf(std::ios::fixed);
      m.precision(2);
      m << "the robot drove through a wall at " << static_cast<double>(step + 1) * kStep
        << " s into the run, at (" << pose.x_m << ", " << pose.y_m
        << "): its path turns too sharply for robot.speed_mps " << scenario.robot.speed_mps
        << ", or runs through the wall (move its waypoints)";
      throw std::invalid_argument(m.str());
    }

    // Actors.
    for (ActorState& s : actors) {
      s.moving = false;
      if (s.delay_left > 0.0) {
        s.delay_left -= kStep;
        continue;
      }
      if (s.pause_left > 0.0) {
        s.pause_left -= kStep;
        continue;
      }
      if (stopped_at(s.spec.stops, run_s)) continue;
      if (s.path.done() || s.spec.speed_mps <= 0.0) continue;
      const Eigen::Vector2d to = s.path.target() - s.position;
      const double d = to.norm();
      const double stepd = s.spec.speed_mps * kStep;
      Eigen::Vector2d stride = to * std::min(1.0, stepd / std::max(d, 1e-9));
      // People do not walk into the robot: they step aside from it when it comes nearer than
      // kRobotClearance_m and walk around it (along the circle) when their way leads through it.
      const Eigen::Vector2d from_robot = s.position - pose.translation();
      const double dr = from_robot.norm();
      if (dr < kRobotClearance_m) {
        stride = stepd * (dr > 1e-9 ? Eigen::Vector2d(from_robot / dr)
                                    : Eigen::Vector2d(std::cos(s.heading), std::sin(s.heading)));
      } else if ((from_robot + stride).norm() < kRobotClearance_m) {
        Eigen::Vector2d around(-from_robot.y() / dr, from_robot.x() / dr);
        if (around.dot(stride) < 0.0) around = -around;
        stride = stepd * around;
      }
      if (stride.norm() > 1e-12) s.heading = std::atan2(stride.y(), stride.x());
      s.position += stride;
      s.moving = true;
      s.gait_phase += 2.0 * kPi * stepd / kStride_m;  // Two steps.
      if (s.path.advance_if_reached(s.position, 1e-6)) s.pause_left = s.spec.pause_s;
    }
  }
  return actor_count;
}

}  // namespace dispel::sim
