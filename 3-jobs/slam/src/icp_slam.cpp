// dispel::slam: the engine's configuration (defaults overlaid with an MRPT-style .ini) and the run
// over a ROS 1 bag. No MRPT here: it lives in icp_slam_engine.cpp.

#include "dispel/slam/icp_slam.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <utility>

#include "dispel/core/pose_buffer.hpp"
#include "dispel/jobs/job.hpp"
#include "slam_input.hpp"

namespace dispel::slam {
namespace {

using jobs::JobError;

// The defaults, for a 2D LiDAR of a few hundred to a few thousand beams at 10-40 Hz on a robot
// below 1 m/s: ICP against the points map at every scan (localization distances 0), a new
// keyframe every 0.5 m or 20 degrees, icp-slam's classic ICP otherwise.
constexpr const char* kDefaultConfig = R"ini([MappingApplication]
localizationLinDistance = 0
localizationAngDistance = 0
insertionLinDistance = 0.5
insertionAngDistance = 20
minICPgoodnessToAccept = 0.4
matchAgainstTheGrid = false
occupancyGrid_count = 0
gasGrid_count = 0
landmarksMap_count = 0
beaconMap_count = 0
pointsMap_count = 1
likelihoodMapSelection = -1

[MappingApplication_pointsMap_00_insertOpts]
minDistBetweenLaserPoints = 0.02
fuseWithExisting = false
isPlanarMap = true

[ICP]
ICP_algorithm = icpClassic
maxIterations = 80
minAbsStep_trans = 1e-6
minAbsStep_rot = 1e-6
thresholdDist = 0.3
thresholdAng_DEG = 5
ALFA = 0.8
smallestThresholdDist = 0.05
onlyClosestCorrespondences = true
onlyUniqueRobust = true
corresponding_points_decimation = 1

[dispel]
min_valid_beams = 120
)ini";

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

// An ini file as MRPT reads it: [section], key = value, comments from '#', ';' or '//'.
struct Ini {
  std::vector<std::string> sections;  // In order of appearance.
  std::map<std::string, std::vector<std::pair<std::string, std::string>>> keys;

  std::string* find(const std::string& section, const std::string& key) {
    for (auto& [k, v] : keys[section]) {
      if (lower(k) == lower(key)) return &v;
    }
    return nullptr;
  }
  void set(const std::string& section, const std::string& key, const std::string& value) {
    if (keys.count(section) == 0) sections.push_back(section);
    if (std::string* v = find(section, key)) {
      *v = value;
    } else {
      keys[section].emplace_back(key, value);
    }
  }
  std::string text() const {
    std::string out;
    for (const auto& s : sections) {
      out += "[" + s + "]\n";
      for (const auto& [k, v] : keys.at(s)) out += k + " = " + v + "\n";
      out += "\n";
    }
    return out;
  }
};

std::string strip_comment(const std::string& line) {
  std::size_t cut = line.size();
  for (const char* marker : {"//", "#", ";"}) cut = std::min(cut, line.find(marker));
  return line.substr(0, cut);
}

Ini parse_ini(std::istream& in, const std::string& name) {
  Ini ini;
  std::string section, line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const std::string t = trim(strip_comment(line));
    if (t.empty()) continue;
    if (t.front() == '[') {
      if (t.back() != ']' || t.size() < 3) {
        throw JobError(name + ":" + std::to_string(number) + ": not a [section] header");
      }
      section = trim(t.substr(1, t.size() - 2));
      if (ini.keys.count(section) == 0) {
        ini.sections.push_back(section);
        ini.keys[section];
      }
      continue;
    }
    const auto eq = t.find('=');
    if (eq == std::string::npos || trim(t.substr(0, eq)).empty()) {
      throw JobError(name + ":" + std::to_string(number) + ": not 'key = value': " + t);
    }
    if (section.empty()) {
      throw JobError(name + ":" + std::to_string(number) + ": key outside any [section]");
    }
    ini.set(section, trim(t.substr(0, eq)), trim(t.substr(eq + 1)));
  }
  return ini;
}

bool is_number(const std::string& s) {
  if (s.empty()) return false;
  char* end = nullptr;
  std::strtod(s.c_str(), &end);
  return end != s.c_str() && trim(end).empty();
}

bool is_bool(const std::string& s) {
  const std::string l = lower(s);
  return l == "true" || l == "false" || l == "0" || l == "1" || l == "yes" || l == "no";
}

eval::TrajectoryPoint point(double t, const Pose2& p) { return {t, p.x_m, p.y_m, p.yaw_rad}; }

}  // namespace

std::string default_engine_config() { return engine_config(std::nullopt); }

std::string engine_config(const std::optional<std::string>& ini_path) {
  std::istringstream defaults_text(kDefaultConfig);
  Ini merged = parse_ini(defaults_text, "defaults");
  if (ini_path) {
    jobs::check_input_file(*ini_path);
    std::ifstream file(*ini_path);
    if (!file) throw JobError(*ini_path + ": cannot read");
    const Ini user = parse_ini(file, *ini_path);
    Ini defaults = merged;
    for (const auto& s : user.sections) {
      for (const auto& [k, v] : user.keys.at(s)) {
        if (const std::string* d = defaults.find(s, k)) {
          if (is_bool(*d) && !is_number(*d) && !is_bool(v)) {
            throw JobError(*ini_path + ": [" + s + "] " + k + " = " + v +
                           ": expected true or false");
          }
          if (is_number(*d) && !is_number(v) && !(is_bool(*d) && is_bool(v))) {
            throw JobError(*ini_path + ": [" + s + "] " + k + " = " + v + ": expected a number");
          }
        }
        merged.set(s, k, v);
      }
    }
  }
  // Removed beams must never clear cells of an occupancy grid.
  const std::string* grids = merged.find("MappingApplication", "occupancyGrid_count");
  const int grid_count = grids != nullptr && is_number(*grids) ? std::atoi(grids->c_str()) : 0;
  for (int i = 0; i < grid_count && i < 100; ++i) {
    char section[64];
    std::snprintf(section, sizeof section, "MappingApplication_occupancyGrid_%02d_insertOpts", i);
    merged.set(section, "considerInvalidRangesAsFreeSpace", "false");
  }
  return merged.text();
}

SlamResult run_icp_slam_full(const SlamOptions& options) {
  jobs::check_input_file(options.input);
  if (!(options.map_resolution_m > 0.0) || !std::isfinite(options.map_resolution_m)) {
    throw JobError("map_resolution_m = " + std::to_string(options.map_resolution_m) +
                   ": must be a positive number of metres per cell");
  }
  SlamResult result;
  result.engine_config = engine_config(options.engine_config_ini);
  IcpSlamEngine engine(result.engine_config);

  detail::SlamInput in = detail::open_slam_input(options.input, options.scan_topic,
                                                 options.odom_topic, options.odom_tolerance_s);
  const io::RecordingMotion& motion = in.motion;
  result.odometry_refused = motion.poses_refused;
  result.scan_topic = motion.scan_topic;
  SlamOptions o = options;
  o.scan_topic = motion.scan_topic;

  detail::for_each_scan(in, [&](const LaserScan& scan) {
    ++result.scans;
    Pose2 odom_pose;
    if (motion.base_poses.lookup(scan.stamp_s, odom_pose) != PoseLookup::kOk) {
      ++result.scans_no_odometry;
      return;
    }
    const std::optional<Pose2> estimate =
        engine.process(scan, odom_pose, motion.mount, &result.beams_invalid);
    if (!estimate) {
      ++result.scans_bad;
      return;
    }
    ++result.scans_used;
    result.trajectory.push_back(point(scan.stamp_s, *estimate));
    result.odometry.push_back(point(scan.stamp_s, odom_pose));
  });
  if (result.scans_used == 0) {
    throw JobError(o.input + ": no scan on " + o.scan_topic + " has odometry on " + o.odom_topic +
                   " at its stamp");
  }
  result.map_points = engine.map_points();
  result.grid = engine.grid_map(o.map_resolution_m);
  return result;
}

std::vector<eval::TrajectoryPoint> run_icp_slam(const SlamOptions& options) {
  return run_icp_slam_full(options).trajectory;
}

}  // namespace dispel::slam
