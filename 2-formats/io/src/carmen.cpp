#include "dispel/io/carmen.hpp"

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "dispel/core/pose2.hpp"
#include "dispel/io/errors.hpp"
#include "dispel/io/text.hpp"

namespace dispel::io {
namespace {

constexpr double kPiValue = 3.14159265358979323846;

// A stamp that cannot be represented: the whole log is refused, never wrapped or clamped.
class StampError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

constexpr double kMaxStamp_s = 4294967295.0;

struct Fields {
  std::vector<std::string> words;
  std::size_t next = 1;

  double number(const char* what) {
    if (next >= words.size()) throw std::runtime_error(std::string("missing ") + what);
    const std::string& w = words[next++];
    std::size_t used = 0;
    double v = 0.0;
    try {
      v = std::stod(w, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != w.size() || used == 0) {
      throw std::runtime_error(std::string(what) + " is not a number: " + quote(w));
    }
    return v;
  }
  std::int64_t count(const char* what, std::size_t max) {
    const double v = number(what);
    if (v < 0 || v != std::floor(v) || v > static_cast<double>(max)) {
      throw std::runtime_error(std::string(what) +
                               " is not a valid count: " + quote(words[next - 1]));
    }
    return static_cast<std::int64_t>(v);
  }
  void skip(std::size_t n) { next += n; }
  // A time stamp: finite, not negative, below 2^32 - 1 s (what a ROS time holds).
  double stamp(const char* what) {
    const double v = number(what);
    if (!(v >= 0.0 && v < kMaxStamp_s)) {
      throw StampError(std::string(what) + " " + quote(words[next - 1]) +
                       " is not a time a recording can hold (0 to 4294967295 s)");
    }
    return v;
  }
};

void read_ranges(Fields& f, std::int64_t n, LaserScan& scan) {
  scan.ranges_m.resize(static_cast<std::size_t>(n));
  for (auto& r : scan.ranges_m) r = static_cast<float>(f.number("range"));
}

CarmenScan parse_old_laser(Fields& f, bool rear, float max_range) {
  CarmenScan out;
  out.kind = rear ? "RLASER" : "FLASER";
  const std::int64_t n = f.count("number of readings", f.words.size());
  if (n < 2) throw std::runtime_error("fewer than 2 readings");
  LaserScan& s = out.scan;
  read_ranges(f, n, s);
  s.angle_increment_rad = kPiValue / static_cast<double>(n - 1);
  s.angle_min_rad = -kPiValue / 2.0;
  s.range_min_m = 0.001F;
  s.range_max_m = max_range - 0.001F;
  const double x = f.number("x");
  const double y = f.number("y");
  const double theta = f.number("theta");
  f.skip(3);  // Odometry pose of the robot.
  s.stamp_s = f.stamp("ipc_timestamp");
  out.laser_pose = {x, y, wrap_angle(theta + (rear ? kPiValue : 0.0))};
  return out;
}

CarmenScan parse_robot_laser(Fields& f) {
  CarmenScan out;
  out.kind = "ROBOTLASER1";
  f.skip(1);  // laser_type
  LaserScan& s = out.scan;
  s.angle_min_rad = f.number("start_angle");
  const double fov = f.number("field_of_view");
  s.angle_increment_rad = f.number("angular_resolution");
  s.range_max_m = static_cast<float>(f.number("maximum_range"));
  s.range_min_m = 0.001F;
  f.skip(2);  // accuracy, remission_mode
  const std::int64_t n = f.count("number of readings", f.words.size());
  read_ranges(f, n, s);
  if (n >= 2 && !(s.angle_increment_rad > 0.0)) {
    s.angle_increment_rad = fov / static_cast<double>(n - 1);
  }
  const std::int64_t m = f.count("number of remissions", f.words.size());
  f.skip(static_cast<std::size_t>(m));
  const double x = f.number("laser_x");
  const double y = f.number("laser_y");
  const double theta = f.number("laser_theta");
  f.skip(8);  // robot pose, tv, rv, safety distances, turn axis
  s.stamp_s = f.stamp("ipc_timestamp");
  out.laser_pose = {x, y, wrap_angle(theta)};
  return out;
}

}  // namespace

CarmenLog parse_carmen_log(std::istream& in, const std::string& origin, float old_max_range_m) {
  CarmenLog log;
  std::string line;
  while (std::getline(in, line)) {
    ++log.lines;
    std::istringstream words(line);
    Fields f;
    for (std::string w; words >> w;) f.words.push_back(w);
    if (f.words.empty() || f.words[0][0] == '#') {
      ++log.ignored_lines;
      continue;
    }
    const std::string& type = f.words[0];
    try {
      if (type == "FLASER" || type == "RLASER") {
        log.scans.push_back(parse_old_laser(f, type == "RLASER", old_max_range_m));
      } else if (type == "ROBOTLASER1") {
        log.scans.push_back(parse_robot_laser(f));
      } else if (type == "ODOM") {
        const double x = f.number("x");
        const double y = f.number("y");
        const double theta = f.number("theta");
        f.skip(3);
        log.odometry.push_back({f.stamp("ipc_timestamp"), {x, y, wrap_angle(theta)}});
      } else {
        ++log.ignored_lines;
      }
    } catch (const StampError& e) {
      throw InputError(one_line(origin + ": line " + std::to_string(log.lines) + " (" + type +
                                "): " + e.what()));
    } catch (const std::exception& e) {
      ++log.malformed_lines;
      if (log.first_malformed.empty()) {
        log.first_malformed = "line " + std::to_string(log.lines) + " (" + type + "): " + e.what();
      }
    }
  }
  if (log.scans.empty()) {
    throw InputError(one_line(
        origin + ": no FLASER, RLASER or ROBOTLASER1 line" +
        (log.first_malformed.empty() ? std::string() : "; first bad " + log.first_malformed)));
  }
  return log;
}

CarmenLog read_carmen_log(const std::string& path, float old_max_range_m) {
  std::ifstream in(path);
  if (!in) throw InputError(one_line(path + ": cannot open the file"));
  return parse_carmen_log(in, path, old_max_range_m);
}

}  // namespace dispel::io
