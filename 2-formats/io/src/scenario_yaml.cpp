#include "dispel/io/scenario_yaml.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <set>

#include "dispel/io/text.hpp"

namespace dispel::io {
namespace {

class Reader {
 public:
  explicit Reader(std::string origin) : origin_(std::move(origin)) {}

  [[noreturn]] void fail(const std::string& message) const {
    throw ConfigError(one_line(origin_ + ": " + message));
  }

  void keys(const YAML::Node& n, const std::string& path,
            const std::set<std::string>& allowed) const {
    if (!n.IsMap()) fail((path.empty() ? std::string("the file") : path) + " must be a mapping");
    std::set<std::string> seen;
    for (const auto& item : n) {
      const auto k = item.first.as<std::string>();
      const std::string key = path.empty() ? k : path + "." + k;
      if (allowed.count(k) == 0) fail("unknown key " + quote(key));
      if (!seen.insert(k).second) fail("key " + quote(key) + " is given twice");
    }
  }
  double number(const YAML::Node& n, const std::string& path) const {
    if (!n.IsScalar()) fail(path + " must be a number");
    double v = 0.0;
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      fail(path + " must be a number, got " + quote(n.Scalar()));
    }
    if (!std::isfinite(v)) fail(path + " must be a finite number, got " + quote(n.Scalar()));
    return v;
  }
  int integer(const YAML::Node& n, const std::string& path) const {
    if (!n.IsScalar()) fail(path + " must be an integer");
    try {
      return n.as<int>();
    } catch (const YAML::Exception&) {
      fail(path + " must be an integer, got " + quote(n.Scalar()));
    }
  }
  bool boolean(const YAML::Node& n, const std::string& path) const {
    try {
      return n.as<bool>();
    } catch (const YAML::Exception&) {
      fail(path + " must be true or false");
    }
  }
  std::vector<double> numbers(const YAML::Node& n, const std::string& path,
                              std::size_t count) const {
    if (!n.IsSequence() || n.size() != count) {
      fail(path + " must be a list of " + std::to_string(count) + " numbers");
    }
    std::vector<double> v;
    for (std::size_t i = 0; i < count; ++i)
      v.push_back(number(n[i], path + "[" + std::to_string(i) + "]"));
    return v;
  }
  Eigen::Vector2d point(const YAML::Node& n, const std::string& path) const {
    const auto v = numbers(n, path, 2);
    return {v[0], v[1]};
  }
  std::vector<Eigen::Vector2d> points(const YAML::Node& n, const std::string& path) const {
    if (!n.IsSequence()) fail(path + " must be a list of [x, y] points");
    std::vector<Eigen::Vector2d> out;
    for (std::size_t i = 0; i < n.size(); ++i)
      out.push_back(point(n[i], path + "[" + std::to_string(i) + "]"));
    return out;
  }

 private:
  std::string origin_;
};

// A pair [low, high] of key @p key of @p n (at @p path), if given, into @p low and @p high: an
// area's corners (4 numbers) or a range (2).
void read_pair(const Reader& r, const YAML::Node& n, const char* key, const std::string& path,
               double* low, double* high, std::size_t count) {
  if (!n[key]) return;
  const auto v = r.numbers(n[key], path + "." + key, count);
  for (std::size_t i = 0; i < count / 2; ++i) {
    low[i] = v[i];
    high[i] = v[count / 2 + i];
  }
}

void read_world(const Reader& r, const YAML::Node& n, sim::StaticWorld& w) {
  r.keys(n, "world",
         {"walls", "polylines", "rectangles", "circles", "shelves", "rough_walls", "clutter"});
  if (n["clutter"]) {
    const YAML::Node& e = n["clutter"];
    sim::Clutter& c = w.clutter;
    r.keys(e, "world.clutter", {"count", "area", "radius_m", "return_share", "keep_clear_m"});
    if (e["count"]) c.count = r.integer(e["count"], "world.clutter.count");
    read_pair(r, e, "area", "world.clutter", c.area_min.data(), c.area_max.data(), 4);
    read_pair(r, e, "radius_m", "world.clutter", &c.min_radius_m, &c.max_radius_m, 2);
    if (e["return_share"])
      c.return_share = r.number(e["return_share"], "world.clutter.return_share");
    if (e["keep_clear_m"])
      c.keep_clear_m = r.number(e["keep_clear_m"], "world.clutter.keep_clear_m");
  }
  if (n["rough_walls"]) {
    const YAML::Node& e = n["rough_walls"];
    r.keys(e, "world.rough_walls",
           {"amplitude_m", "piece_min_m", "piece_max_m", "doors_per_10m", "legs_per_10m",
            "glass_share", "glass_returns_within_deg", "low_things_per_10m", "low_things_radius_m",
            "low_things_seen_within_m"});
    sim::RoughWalls rw;
    read_pair(r, e, "low_things_radius_m", "world.rough_walls", &rw.low_things_min_radius_m,
              &rw.low_things_max_radius_m, 2);
    read_pair(r, e, "low_things_seen_within_m", "world.rough_walls",
              &rw.low_things_min_seen_within_m, &rw.low_things_max_seen_within_m, 2);
    const std::pair<const char*, double*> fields[] = {
        {"amplitude_m", &rw.amplitude_m},
        {"piece_min_m", &rw.piece_min_m},
        {"piece_max_m", &rw.piece_max_m},
        {"doors_per_10m", &rw.doors_per_10m},
        {"legs_per_10m", &rw.legs_per_10m},
        {"glass_share", &rw.glass_share},
        {"glass_returns_within_deg", &rw.glass_returns_within_deg},
        {"low_things_per_10m", &rw.low_things_per_10m}};
    for (const auto& [key, field] : fields) {
      if (e[key]) *field = r.number(e[key], std::string("world.rough_walls.") + key);
    }
    w.rough_walls = rw;
  }
  if (n["shelves"]) {
    if (!n["shelves"].IsSequence()) r.fail("world.shelves must be a list");
    for (std::size_t i = 0; i < n["shelves"].size(); ++i) {
      const std::string path = "world.shelves[" + std::to_string(i) + "]";
      const YAML::Node& e = n["shelves"][i];
      r.keys(e, path, {"from", "to", "depth_m", "bay_m", "fill"});
      sim::ShelfRow row;
      row.from = r.point(e["from"], path + ".from");
      row.to = r.point(e["to"], path + ".to");
      if (e["depth_m"]) row.depth_m = r.number(e["depth_m"], path + ".depth_m");
      if (e["bay_m"]) row.bay_m = r.number(e["bay_m"], path + ".bay_m");
      if (e["fill"]) row.fill = r.number(e["fill"], path + ".fill");
      w.shelves.push_back(row);
    }
  }
  if (n["walls"]) {
    for (std::size_t i = 0; i < n["walls"].size(); ++i) {
      const auto v = r.numbers(n["walls"][i], "world.walls[" + std::to_string(i) + "]", 4);
      w.walls.push_back({{v[0], v[1]}, {v[2], v[3]}});
    }
  }
  if (n["polylines"]) {
    for (std::size_t i = 0; i < n["polylines"].size(); ++i) {
      const auto p = r.points(n["polylines"][i], "world.polylines[" + std::to_string(i) + "]");
      for (std::size_t k = 1; k < p.size(); ++k) w.walls.push_back({p[k - 1], p[k]});
    }
  }
  if (n["rectangles"]) {
    for (std::size_t i = 0; i < n["rectangles"].size(); ++i) {
      const std::string path = "world.rectangles[" + std::to_string(i) + "]";
      const YAML::Node& e = n["rectangles"][i];
      r.keys(e, path, {"center", "size", "yaw_deg"});
      const auto size = r.numbers(e["size"], path + ".size", 2);
      w.rectangles.push_back(
          {r.point(e["center"], path + ".center"), size[0], size[1],
           e["yaw_deg"] ? r.number(e["yaw_deg"], path + ".yaw_deg") * kPi / 180.0 : 0.0});
    }
  }
  if (n["circles"]) {
    for (std::size_t i = 0; i < n["circles"].size(); ++i) {
      const std::string path = "world.circles[" + std::to_string(i) + "]";
      const YAML::Node& e = n["circles"][i];
      r.keys(e, path, {"center", "radius_m"});
      w.circles.push_back(
          {r.point(e["center"], path + ".center"), r.number(e["radius_m"], path + ".radius_m")});
    }
  }
}

// [[at_s, for_s], ...]
std::vector<sim::Stop> read_stops(const Reader& r, const YAML::Node& n, const std::string& path) {
  if (!n.IsSequence()) r.fail(path + " must be a list of [at_s, for_s]");
  std::vector<sim::Stop> stops;
  for (std::size_t i = 0; i < n.size(); ++i) {
    const auto v = r.numbers(n[i], path + "[" + std::to_string(i) + "]", 2);
    stops.push_back({v[0], v[1]});
  }
  return stops;
}

void read_robot(const Reader& r, const YAML::Node& n, sim::RobotConfig& robot) {
  r.keys(n, "robot",
         {"start", "speed_mps", "waypoints", "loop", "lawnmower", "wheel_base_m", "laser_mount",
          "stops"});
  if (n["start"]) {
    const auto s = r.numbers(n["start"], "robot.start", 3);
    robot.start = {s[0], s[1], s[2] * kPi / 180.0};
  }
  if (n["speed_mps"]) robot.speed_mps = r.number(n["speed_mps"], "robot.speed_mps");
  if (n["waypoints"]) robot.waypoints = r.points(n["waypoints"], "robot.waypoints");
  if (n["loop"]) robot.loop = r.boolean(n["loop"], "robot.loop");
  if (n["wheel_base_m"]) robot.wheel_base_m = r.number(n["wheel_base_m"], "robot.wheel_base_m");
  if (n["stops"]) robot.stops = read_stops(r, n["stops"], "robot.stops");
  if (n["laser_mount"]) {
    const auto m = r.numbers(n["laser_mount"], "robot.laser_mount", 3);
    robot.laser_mount = {m[0], m[1], m[2] * kPi / 180.0};
  }
  if (n["lawnmower"]) {
    const YAML::Node& l = n["lawnmower"];
    r.keys(l, "robot.lawnmower", {"origin", "lane_length_m", "lane_spacing_m", "lanes"});
    sim::Lawnmower lm;
    if (l["origin"]) lm.origin = r.point(l["origin"], "robot.lawnmower.origin");
    if (l["lane_length_m"])
      lm.lane_length_m = r.number(l["lane_length_m"], "robot.lawnmower.lane_length_m");
    if (l["lane_spacing_m"])
      lm.lane_spacing_m = r.number(l["lane_spacing_m"], "robot.lawnmower.lane_spacing_m");
    if (l["lanes"]) lm.lanes = r.integer(l["lanes"], "robot.lawnmower.lanes");
    robot.lawnmower = lm;
  }
}

void read_lidar(const Reader& r, const YAML::Node& n, sim::LidarConfig& l) {
  r.keys(n, "lidar", {"range_max_m",   "fov_deg",           "resolution_deg",
                      "rate_hz",       "range_limit_m",     "masked_sectors_deg",
                      "range_noise_m", "range_noise_per_m", "incidence_noise",
                      "mixed_pixels",  "dropout",           "sweep",
                      "speckle",       "speckle_range_m",   "speckle_beams_max",
                      "dark_share",    "dark_reach_m",      "height_m",
                      "bumps_per_min", "bump_tilt_deg",     "bump_s"});
  if (n["range_noise_per_m"])
    l.range_noise_per_m = r.number(n["range_noise_per_m"], "lidar.range_noise_per_m");
  if (n["incidence_noise"])
    l.incidence_noise = r.number(n["incidence_noise"], "lidar.incidence_noise");
  if (n["mixed_pixels"]) l.mixed_pixels = r.number(n["mixed_pixels"], "lidar.mixed_pixels");
  if (n["sweep"]) l.sweep = r.boolean(n["sweep"], "lidar.sweep");
  if (n["range_max_m"]) l.range_max_m = r.number(n["range_max_m"], "lidar.range_max_m");
  if (n["fov_deg"]) l.fov_deg = r.number(n["fov_deg"], "lidar.fov_deg");
  if (n["resolution_deg"]) l.resolution_deg = r.number(n["resolution_deg"], "lidar.resolution_deg");
  if (n["rate_hz"]) l.rate_hz = r.number(n["rate_hz"], "lidar.rate_hz");
  if (n["range_limit_m"]) l.range_limit_m = r.number(n["range_limit_m"], "lidar.range_limit_m");
  if (n["range_noise_m"]) l.range_noise_m = r.number(n["range_noise_m"], "lidar.range_noise_m");
  if (n["dropout"]) l.dropout = r.number(n["dropout"], "lidar.dropout");
  if (n["speckle"]) l.speckle = r.number(n["speckle"], "lidar.speckle");
  if (n["speckle_range_m"]) {
    const auto v = r.numbers(n["speckle_range_m"], "lidar.speckle_range_m", 2);
    l.speckle_range_m = {v[0], v[1]};
  }
  if (n["speckle_beams_max"])
    l.speckle_beams_max = r.integer(n["speckle_beams_max"], "lidar.speckle_beams_max");
  if (n["dark_share"]) l.dark_share = r.number(n["dark_share"], "lidar.dark_share");
  if (n["dark_reach_m"]) l.dark_reach_m = r.number(n["dark_reach_m"], "lidar.dark_reach_m");
  if (n["height_m"]) l.height_m = r.number(n["height_m"], "lidar.height_m");
  if (n["bumps_per_min"]) l.bumps_per_min = r.number(n["bumps_per_min"], "lidar.bumps_per_min");
  if (n["bump_tilt_deg"]) l.bump_tilt_deg = r.number(n["bump_tilt_deg"], "lidar.bump_tilt_deg");
  if (n["bump_s"]) l.bump_s = r.number(n["bump_s"], "lidar.bump_s");
  if (n["masked_sectors_deg"]) {
    const YAML::Node& m = n["masked_sectors_deg"];
    if (!m.IsSequence()) r.fail("lidar.masked_sectors_deg must be a list of [begin_deg, end_deg]");
    for (std::size_t i = 0; i < m.size(); ++i) {
      const auto v = r.numbers(m[i], "lidar.masked_sectors_deg[" + std::to_string(i) + "]", 2);
      l.masked_sectors_deg.emplace_back(v[0], v[1]);
    }
  }
}

void read_sensors(const Reader& r, const YAML::Node& n, sim::SensorConfig& s) {
  r.keys(n, "sensors",
         {"rate_hz", "wheel_noise_mps", "wheel_scale_error", "wheel_difference_error",
          "slips_per_minute", "imu_noise_radps", "imu_bias_walk_radps", "imu_vibration_radps"});
  const std::pair<const char*, double*> fields[] = {
      {"rate_hz", &s.rate_hz},
      {"wheel_noise_mps", &s.wheel_noise_mps},
      {"wheel_scale_error", &s.wheel_scale_error},
      {"wheel_difference_error", &s.wheel_difference_error},
      {"slips_per_minute", &s.slips_per_minute},
      {"imu_noise_radps", &s.imu_noise_radps},
      {"imu_bias_walk_radps", &s.imu_bias_walk_radps},
      {"imu_vibration_radps", &s.imu_vibration_radps}};
  for (const auto& [key, field] : fields) {
    if (n[key]) *field = r.number(n[key], std::string("sensors.") + key);
  }
}

void read_actors(const Reader& r, const YAML::Node& n, std::vector<sim::Actor>& actors) {
  if (!n.IsSequence()) r.fail("actors must be a list");
  for (std::size_t i = 0; i < n.size(); ++i) {
    const std::string path = "actors[" + std::to_string(i) + "]";
    const YAML::Node& e = n[i];
    r.keys(e, path,
           {"type", "waypoints", "standing", "speed_mps", "pause_s", "loop", "start_delay_s",
            "stops", "size"});
    sim::Actor a;
    const std::string type = e["type"] ? e["type"].as<std::string>() : "person";
    if (type == "cart" || type == "forklift") {
      a.kind = sim::ActorKind::kCart;
    } else if (type != "person") {
      r.fail(path + ".type must be person, cart or forklift, got " + quote(type));
    }
    if (e["standing"]) {
      a.waypoints = {r.point(e["standing"], path + ".standing")};
      a.speed_mps = 0.0;
    } else if (e["waypoints"]) {
      a.waypoints = r.points(e["waypoints"], path + ".waypoints");
    } else {
      r.fail(path + " needs waypoints or standing");
    }
    if (e["speed_mps"]) a.speed_mps = r.number(e["speed_mps"], path + ".speed_mps");
    if (e["pause_s"]) a.pause_s = r.number(e["pause_s"], path + ".pause_s");
    if (e["loop"]) a.loop = r.boolean(e["loop"], path + ".loop");
    if (e["start_delay_s"]) a.start_delay_s = r.number(e["start_delay_s"], path + ".start_delay_s");
    if (e["stops"]) a.stops = read_stops(r, e["stops"], path + ".stops");
    if (e["size"]) {
      const auto s = r.numbers(e["size"], path + ".size", 2);
      a.length_m = s[0];
      a.width_m = s[1];
    }
    actors.push_back(a);
  }
}

void read_random_people(const Reader& r, const YAML::Node& n, sim::RandomPeople& p) {
  r.keys(n, "random_people", {"count", "area", "speed_mps", "max_pause_s", "waypoints", "loop"});
  if (n["count"]) p.count = r.integer(n["count"], "random_people.count");
  read_pair(r, n, "area", "random_people", p.area_min.data(), p.area_max.data(), 4);
  read_pair(r, n, "speed_mps", "random_people", &p.min_speed_mps, &p.max_speed_mps, 2);
  if (n["max_pause_s"]) p.max_pause_s = r.number(n["max_pause_s"], "random_people.max_pause_s");
  if (n["waypoints"]) p.waypoints = r.integer(n["waypoints"], "random_people.waypoints");
  if (n["loop"]) p.loop = r.boolean(n["loop"], "random_people.loop");
}

}  // namespace

sim::Scenario parse_scenario(const std::string& yaml_text, const std::string& origin) {
  const Reader r(origin);
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    r.fail(std::string("not valid YAML: ") + e.what());
  }
  if (root.IsNull()) r.fail("the scenario file is empty");
  sim::Scenario s;
  try {
    r.keys(root, "",
           {"name", "duration_s", "gait", "world", "robot", "lidar", "sensors", "actors",
            "random_people"});
    if (root["name"]) s.name = root["name"].as<std::string>();
    if (root["duration_s"]) s.duration_s = r.number(root["duration_s"], "duration_s");
    if (root["gait"]) {
      const std::string gait = root["gait"].as<std::string>();
      if (gait != "sway" && gait != "planted") {
        r.fail("gait must be sway or planted, got " + quote(gait));
      }
      s.gait = gait == "planted" ? sim::Gait::kPlanted : sim::Gait::kSway;
    }
    if (root["world"]) read_world(r, root["world"], s.world);
    if (root["robot"]) read_robot(r, root["robot"], s.robot);
    if (root["lidar"]) read_lidar(r, root["lidar"], s.lidar);
    if (root["sensors"]) read_sensors(r, root["sensors"], s.sensors);
    if (root["actors"]) read_actors(r, root["actors"], s.actors);
    if (root["random_people"]) read_random_people(r, root["random_people"], s.random_people);
    s.validate();
  } catch (const ConfigError&) {
    throw;
  } catch (const std::exception& e) {
    r.fail(e.what());
  }
  return s;
}

sim::Scenario load_scenario(const std::string& path) {
  return parse_scenario(read_regular_file(path, "scenario file"), path);
}

}  // namespace dispel::io
