// dispel::slam: the engine's configuration (defaults overlaid with an MRPT-style .ini) and the run
// over a ROS 1 bag. No MRPT here: it lives in icp_slam_engine.cpp.

#include "dispel/slam/icp_slam.hpp"

#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/LaserScan.h>
#include <sys/stat.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <utility>

#include "dispel/core/pose_buffer.hpp"
#include "dispel/io/bag_topics.hpp"
#include "dispel/io/filter_job.hpp"
#include "dispel/io/frame_tree.hpp"
#include "dispel/io/ros_convert.hpp"

namespace dispel::slam {
namespace {

using io::JobError;

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

void check_input_file(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) throw JobError(path + ": " + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) throw JobError(path + ": not a regular file");
}

eval::TrajectoryPoint point(double t, const Pose2& p) { return {t, p.x_m, p.y_m, p.yaw_rad}; }

}  // namespace

std::string default_engine_config() { return engine_config(std::nullopt); }

std::string engine_config(const std::optional<std::string>& ini_path) {
  std::istringstream defaults_text(kDefaultConfig);
  Ini merged = parse_ini(defaults_text, "defaults");
  if (ini_path) {
    check_input_file(*ini_path);
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
  check_input_file(options.input);
  SlamResult result;
  result.engine_config = engine_config(options.engine_config_ini);
  IcpSlamEngine engine(result.engine_config);

  rosbag::Bag in;
  io::open_bag_for_reading(in, options.input);
  const io::BagTopics topics(in);
  SlamOptions o = options;
  if (o.scan_topic.empty()) {
    // What `dispel filter` writes, when it is there.
    o.scan_topic =
        topics.has("/scan_filtered", "sensor_msgs/LaserScan") ? "/scan_filtered" : "/scan";
  }
  result.scan_topic = o.scan_topic;
  if (!topics.has(o.scan_topic, "sensor_msgs/LaserScan")) {
    throw JobError(o.input + ": no sensor_msgs/LaserScan topic " + o.scan_topic +
                   " (LaserScan topics: " + topics.list("sensor_msgs/LaserScan") + ")");
  }
  if (!topics.has(o.odom_topic, "nav_msgs/Odometry")) {
    throw JobError(o.input + ": no nav_msgs/Odometry topic " + o.odom_topic +
                   " (Odometry topics: " + topics.list("nav_msgs/Odometry") + ")");
  }

  // First pass: odometry, the laser mount, the laser's frame.
  PoseBuffer odometry(o.odom_tolerance_s, 0.5);
  io::FrameTree mounts;
  std::string base_frame = "base_link";
  std::string odom_frame = "odom";
  std::string laser_frame;
  bool have_laser_frame = false;
  try {
    rosbag::View view(in, rosbag::TopicQuery({o.scan_topic, o.odom_topic, "/tf", "/tf_static"}));
    bool have_odom_frames = false;
    for (const rosbag::MessageInstance& m : view) {
      if (m.getTopic() == o.scan_topic) {
        if (have_laser_frame) continue;
        if (const auto scan = m.instantiate<sensor_msgs::LaserScan>()) {
          laser_frame = io::FrameTree::normalise(scan->header.frame_id);
          have_laser_frame = true;
        }
      } else if (m.getTopic() == o.odom_topic) {
        const auto odom = m.instantiate<nav_msgs::Odometry>();
        if (!odom) continue;
        if (!have_odom_frames) {
          if (!odom->child_frame_id.empty())
            base_frame = io::FrameTree::normalise(odom->child_frame_id);
          if (!odom->header.frame_id.empty())
            odom_frame = io::FrameTree::normalise(odom->header.frame_id);
          have_odom_frames = true;
        }
        if (!odometry.add(io::to_seconds(odom->header.stamp), io::from_ros(odom->pose.pose))) {
          ++result.odometry_refused;
        }
      } else if (const auto tf = m.instantiate<tf2_msgs::TFMessage>()) {
        for (const auto& t : tf->transforms) {
          const std::string parent = io::FrameTree::normalise(t.header.frame_id);
          const std::string child = io::FrameTree::normalise(t.child_frame_id);
          // Only fixed mounts: not the robot's motion in odom or map.
          if (parent == odom_frame || child == odom_frame || parent == "map" || child == "map") {
            continue;
          }
          mounts.set(parent, child, io::from_ros(t.transform));
        }
      }
    }
  } catch (...) {
    io::rethrow_as_recording_error(o.input);
  }
  if (!have_laser_frame) throw JobError(o.input + ": no scans on " + o.scan_topic);
  if (odometry.empty()) throw JobError(o.input + ": no usable odometry on " + o.odom_topic);
  Pose2 mount;
  if (!laser_frame.empty() && laser_frame != base_frame) {
    const auto found = mounts.lookup(base_frame, laser_frame);
    if (!found) {
      throw JobError(o.input + ": no transform from " + base_frame + " to " + laser_frame +
                     " in /tf_static or /tf; record the sensor mount");
    }
    mount = *found;
  }

  // Second pass: the scans, in order.
  try {
    rosbag::View view(in, rosbag::TopicQuery(o.scan_topic));
    for (const rosbag::MessageInstance& m : view) {
      const auto msg = m.instantiate<sensor_msgs::LaserScan>();
      if (!msg) continue;
      ++result.scans;
      const LaserScan scan = io::from_ros(*msg);
      Pose2 odom_pose;
      if (odometry.lookup(scan.stamp_s, odom_pose) != PoseLookup::kOk) {
        ++result.scans_no_odometry;
        continue;
      }
      const std::optional<Pose2> estimate =
          engine.process(scan, odom_pose, mount, &result.beams_invalid);
      if (!estimate) {
        ++result.scans_bad;
        continue;
      }
      ++result.scans_used;
      result.trajectory.push_back(point(scan.stamp_s, *estimate));
      result.odometry.push_back(point(scan.stamp_s, odom_pose));
    }
  } catch (...) {
    io::rethrow_as_recording_error(o.input);
  }
  if (result.scans_used == 0) {
    throw JobError(o.input + ": no scan on " + o.scan_topic + " has odometry on " + o.odom_topic +
                   " at its stamp");
  }
  result.map_points = engine.map_points();
  return result;
}

std::vector<eval::TrajectoryPoint> run_icp_slam(const SlamOptions& options) {
  return run_icp_slam_full(options).trajectory;
}

}  // namespace dispel::slam
