#include "dispel/io/odom_job.hpp"

#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/JointState.h>
#include <sensor_msgs/NavSatFix.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include "dispel/io/atomic_file.hpp"
#include "dispel/io/bag_topics.hpp"
#include "dispel/io/config_yaml.hpp"
#include "dispel/io/filter_job.hpp"
#include "dispel/io/ros_convert.hpp"

namespace dispel::io {
namespace {

// ------------------------------------------------------------------------------------------
// CSV.

// A CSV file with a header: the values of the named columns, row by row, with line numbers.
struct CsvColumns {
  std::vector<std::vector<double>> rows;  // In the order of the requested columns.
  std::vector<int> lines;
};

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) {
    const auto b = cell.find_first_not_of(" \t\r");
    const auto e = cell.find_last_not_of(" \t\r");
    out.push_back(b == std::string::npos ? "" : cell.substr(b, e - b + 1));
  }
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

CsvColumns read_csv(const std::string& path, const std::vector<std::string>& wanted) {
  std::ifstream in(path);
  if (!in) throw JobError(path + ": cannot open the file");
  std::string line;
  int number = 0;
  std::vector<std::string> header;
  while (header.empty() && std::getline(in, line)) {
    ++number;
    if (line.find_first_not_of(" \t\r") != std::string::npos) header = split(line);
  }
  std::string expected;
  for (const auto& w : wanted) expected += (expected.empty() ? "" : ",") + w;
  std::vector<std::size_t> index;
  for (const auto& w : wanted) {
    const auto it = std::find(header.begin(), header.end(), w);
    if (it == header.end()) {
      throw JobError(path + ": the header must name the columns " + expected + " (line " +
                     std::to_string(number) + ": '" + line + "')");
    }
    index.push_back(static_cast<std::size_t>(it - header.begin()));
  }
  CsvColumns out;
  while (std::getline(in, line)) {
    ++number;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const auto cells = split(line);
    if (cells.size() != header.size()) {
      throw JobError(path + ":" + std::to_string(number) + ": " + std::to_string(header.size()) +
                     " values expected, got " + std::to_string(cells.size()));
    }
    std::vector<double> row;
    for (std::size_t i : index) {
      const std::string& c = cells[i];
      std::size_t used = 0;
      double v = 0.0;
      try {
        v = std::stod(c, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (c.empty() || used != c.size()) {
        throw JobError(path + ":" + std::to_string(number) + ": " + header[i] + " '" + c +
                       "' is not a number");
      }
      row.push_back(v);
    }
    out.rows.push_back(std::move(row));
    out.lines.push_back(number);
  }
  return out;
}

// ------------------------------------------------------------------------------------------
// Measurements.

struct Measurement {
  double t_s;
  bool imu;
  double a;  // Wheels: v_left; IMU: yaw rate.
  double b;  // Wheels: v_right.
};

// Sorts one source's measurements by time, counting those that came earlier than their
// predecessor.
void sort_by_time(std::vector<Measurement>& m, OdomJobStats& stats) {
  for (std::size_t i = 1; i < m.size(); ++i) {
    if (m[i].t_s < m[i - 1].t_s) ++stats.stamps_out_of_order;
  }
  std::stable_sort(m.begin(), m.end(),
                   [](const Measurement& x, const Measurement& y) { return x.t_s < y.t_s; });
}

struct Inputs {
  std::vector<Measurement> wheels, imu;
  std::vector<eval::TrajectoryPoint> truth;
};

Inputs read_bag(const OdomJobOptions& o, const OdometrySettings& settings, OdomJobStats& stats) {
  rosbag::Bag bag;
  open_bag_for_reading(bag, o.input);
  const BagTopics topics(bag);
  const auto list = join_topics;
  const auto joint_topics = topics.of_type("sensor_msgs/JointState");
  const auto odom_topics = topics.of_type("nav_msgs/Odometry");
  std::string wheel_topic = o.wheel_topic;
  if (wheel_topic.empty()) {
    if (topics.has("/wheels")) {
      wheel_topic = "/wheels";
    } else if (joint_topics.size() == 1) {
      wheel_topic = joint_topics.front();
    } else if (joint_topics.empty() && odom_topics.size() == 1) {
      wheel_topic = odom_topics.front();
    } else {
      throw JobError(o.input + ": which topic holds the wheel speeds? (JointState topics: " +
                     list(joint_topics) + "; Odometry topics: " + list(odom_topics) +
                     "); choose one with --wheel-topic");
    }
  }
  const bool wheels_from_odometry = topics.has(wheel_topic, "nav_msgs/Odometry");
  if (!wheels_from_odometry && !topics.has(wheel_topic, "sensor_msgs/JointState")) {
    throw JobError(o.input + ": no sensor_msgs/JointState or nav_msgs/Odometry topic " +
                   wheel_topic + " (JointState topics: " + list(joint_topics) +
                   "; Odometry topics: " + list(odom_topics) + ")");
  }
  std::string imu_topic = o.imu_topic;
  const auto imu_topics = topics.of_type("sensor_msgs/Imu");
  if (imu_topic.empty()) {
    if (imu_topics.size() == 1) imu_topic = imu_topics.front();
    if (imu_topics.size() > 1) {
      throw JobError(o.input + ": several IMU topics (" + list(imu_topics) +
                     "); choose one with --imu-topic, or --imu-topic none");
    }
  } else if (imu_topic != "none" && !topics.has(imu_topic, "sensor_msgs/Imu")) {
    throw JobError(o.input + ": no sensor_msgs/Imu topic " + imu_topic +
                   " (Imu topics: " + list(imu_topics) + ")");
  }
  if (imu_topic == "none") imu_topic.clear();
  const bool truth_is_gps = topics.has(o.truth_topic, "sensor_msgs/NavSatFix");
  if (!o.truth_csv.empty() && !truth_is_gps && !topics.has(o.truth_topic, "nav_msgs/Odometry")) {
    throw JobError(o.input + ": no nav_msgs/Odometry or sensor_msgs/NavSatFix topic " +
                   o.truth_topic + " for --truth-csv (Odometry topics: " + list(odom_topics) +
                   "; NavSatFix topics: " + topics.list("sensor_msgs/NavSatFix") + ")");
  }
  stats.wheel_source = wheel_topic;
  stats.imu_source = imu_topic;

  Inputs in;
  const double b = settings.filter.track_width_m;
  bool have_origin = false;
  double lat0 = 0.0, lon0 = 0.0;
  try {
    std::vector<std::string> wanted{wheel_topic};
    if (!imu_topic.empty()) wanted.push_back(imu_topic);
    if (!o.truth_csv.empty()) wanted.push_back(o.truth_topic);
    rosbag::View view(bag, rosbag::TopicQuery(wanted));
    for (const rosbag::MessageInstance& m : view) {
      const std::string& topic = m.getTopic();
      if (topic == wheel_topic) {
        ++stats.wheel_messages;
        if (wheels_from_odometry) {
          const auto od = m.instantiate<nav_msgs::Odometry>();
          if (!od) continue;
          const WheelSpeeds w = wheel_speeds_from_ros(*od, b, m.getTime());
          in.wheels.push_back({w.t_s, false, w.left_mps, w.right_mps});
        } else {
          const auto js = m.instantiate<sensor_msgs::JointState>();
          if (!js) continue;
          const auto w = wheel_speeds_from_ros(*js, settings, m.getTime());
          if (!w) {
            ++stats.malformed;
            continue;
          }
          in.wheels.push_back({w->t_s, false, w->left_mps, w->right_mps});
        }
      }
      if (topic == imu_topic) {
        ++stats.imu_messages;
        if (const auto imu = m.instantiate<sensor_msgs::Imu>()) {
          in.imu.push_back({stamp_or(imu->header.stamp, m.getTime()), true,
                            yaw_rate_from_ros(*imu, settings), 0.0});
        }
      }
      if (!o.truth_csv.empty() && topic == o.truth_topic && truth_is_gps) {
        const auto fix = m.instantiate<sensor_msgs::NavSatFix>();
        if (fix && fix->status.status >= sensor_msgs::NavSatStatus::STATUS_FIX &&
            std::isfinite(fix->latitude) && std::isfinite(fix->longitude)) {
          // East and north in metres from the first fix (a local tangent plane; fine over
          // kilometres). GPS has no heading: yaw NaN.
          if (!have_origin) {
            lat0 = fix->latitude;
            lon0 = fix->longitude;
            have_origin = true;
          }
          constexpr double kEarthRadius_m = 6378137.0, kDeg = 3.14159265358979323846 / 180.0;
          in.truth.push_back(
              {stamp_or(fix->header.stamp, m.getTime()),
               kEarthRadius_m * (fix->longitude - lon0) * kDeg * std::cos(lat0 * kDeg),
               kEarthRadius_m * (fix->latitude - lat0) * kDeg,
               std::numeric_limits<double>::quiet_NaN()});
        }
      } else if (!o.truth_csv.empty() && topic == o.truth_topic) {
        if (const auto od = m.instantiate<nav_msgs::Odometry>()) {
          in.truth.push_back({stamp_or(od->header.stamp, m.getTime()), od->pose.pose.position.x,
                              od->pose.pose.position.y, yaw_of(od->pose.pose.orientation)});
        }
      }
    }
  } catch (...) {
    rethrow_as_recording_error(o.input);
  }
  return in;
}

Inputs read_csvs(const OdomJobOptions& o, OdomJobStats& stats) {
  Inputs in;
  const CsvColumns w = read_csv(o.wheels_csv, {"t", "v_left", "v_right"});
  for (const auto& r : w.rows) in.wheels.push_back({r[0], false, r[1], r[2]});
  stats.wheel_source = o.wheels_csv;
  stats.wheel_messages = static_cast<std::int64_t>(w.rows.size());
  if (!o.imu_csv.empty()) {
    const CsvColumns i = read_csv(o.imu_csv, {"t", "yaw_rate"});
    for (const auto& r : i.rows) in.imu.push_back({r[0], true, r[1], 0.0});
    stats.imu_source = o.imu_csv;
    stats.imu_messages = static_cast<std::int64_t>(i.rows.size());
  }
  return in;
}

// ------------------------------------------------------------------------------------------
// Output.

void write_row(std::FILE* f, const OdometryEstimate& e) {
  std::fprintf(f, "%.9f,%.9g,%.9g,%.9g,%.9g,%.9g,%.6g,%.6g,%.6g,%.6g,%.6g\n", e.t_s, e.x_m, e.y_m,
               e.yaw_rad, e.v_mps, e.omega_radps, e.x_variance_m2, e.y_variance_m2,
               e.yaw_variance_rad2, e.v_variance_m2ps2, e.omega_variance_rad2ps2);
}

struct CsvOut {
  explicit CsvOut(const std::string& path) : file(path) {
    f = std::fopen(file.temp_path().c_str(), "w");
    if (f == nullptr) throw JobError(path + ": cannot write the file");
  }
  ~CsvOut() {
    if (f != nullptr) std::fclose(f);
  }
  void commit(const std::string& path) {
    const bool ok = std::fflush(f) == 0 && std::ferror(f) == 0;
    std::fclose(f);
    f = nullptr;
    if (!ok) throw JobError(path + ": writing failed");
    file.commit();
  }
  AtomicFile file;
  std::FILE* f = nullptr;
};

}  // namespace

OdomJobStats run_odom_job(const OdomJobOptions& o) {
  if (o.input.empty() == o.wheels_csv.empty()) {
    throw JobError("give either a bag or --wheels-csv (not both)");
  }
  if (!o.imu_csv.empty() && o.wheels_csv.empty()) {
    throw JobError("--imu-csv needs --wheels-csv");
  }
  OdometrySettings settings;
  if (o.config_path) settings = load_odometry_settings(*o.config_path);
  bool dead_reckoning = false;
  if (o.model) {
    if (*o.model == "ct") {
      settings.filter.model = OdometryModel::kCt;
    } else if (*o.model == "ct_euler") {
      settings.filter.model = OdometryModel::kCtEuler;
    } else if (*o.model == "omni") {
      settings.filter.model = OdometryModel::kOmni;
    } else if (*o.model == "dead_reckoning") {
      dead_reckoning = true;
    } else {
      throw JobError("--model must be one of ct, ct_euler, omni, dead_reckoning, got '" + *o.model +
                     "'");
    }
  }
  OdomJobStats stats;
  stats.model = dead_reckoning ? "dead_reckoning" : odometry_model_name(settings.filter.model);
  stats.track_width_m = settings.filter.track_width_m;
  Inputs in = o.input.empty() ? read_csvs(o, stats) : read_bag(o, settings, stats);
  if (in.wheels.empty()) throw JobError(stats.wheel_source + ": no wheel speeds");
  sort_by_time(in.wheels, stats);
  sort_by_time(in.imu, stats);
  if (dead_reckoning) in.imu.clear();  // The wheels alone.
  std::vector<Measurement> all;
  all.reserve(in.wheels.size() + in.imu.size());
  std::merge(in.wheels.begin(), in.wheels.end(), in.imu.begin(), in.imu.end(),
             std::back_inserter(all),
             [](const Measurement& x, const Measurement& y) { return x.t_s < y.t_s; });

  CsvOut out(o.output);
  std::fprintf(out.f, "t,x,y,yaw,v,omega,var_x,var_y,var_yaw,var_v,var_omega\n");
  double last_written = -std::numeric_limits<double>::infinity();
  const auto emit = [&](const OdometryEstimate& e, std::size_t i) {
    // One row per time stamp, after every measurement at that time.
    if (i + 1 < all.size() && all[i + 1].t_s == all[i].t_s) return;
    if (!(e.t_s > last_written)) return;
    write_row(out.f, e);
    last_written = e.t_s;
    ++stats.rows;
  };
  if (dead_reckoning) {
    WheelOdometry odometry(settings.filter.track_width_m);
    for (std::size_t i = 0; i < all.size(); ++i) {
      if (odometry.add_wheels(all[i].t_s, all[i].a, all[i].b) == OdometryEvent::kAccepted) {
        emit(odometry.estimate(), i);
      }
    }
    stats.counters.wheels = odometry.counters();
    stats.final_estimate = odometry.estimate();
  } else {
    OdometryFusion fusion(settings.filter);
    for (std::size_t i = 0; i < all.size(); ++i) {
      const Measurement& m = all[i];
      const OdometryEvent event =
          m.imu ? fusion.add_imu(m.t_s, m.a) : fusion.add_wheels(m.t_s, m.a, m.b);
      if (event == OdometryEvent::kAccepted || event == OdometryEvent::kGated ||
          event == OdometryEvent::kGateOverridden) {
        emit(fusion.estimate(), i);
      }
    }
    stats.counters = fusion.counters();
    stats.final_estimate = fusion.estimate();
  }
  if (stats.rows == 0) throw JobError(stats.wheel_source + ": no usable wheel speeds");

  if (!o.truth_csv.empty()) {
    write_trajectory_csv(o.truth_csv, in.truth);
    stats.truth_rows = static_cast<std::int64_t>(in.truth.size());
  }
  out.commit(o.output);
  return stats;
}

void write_trajectory_csv(const std::string& path,
                          const std::vector<eval::TrajectoryPoint>& trajectory) {
  CsvOut out(path);
  std::fprintf(out.f, "t,x,y,yaw\n");
  for (const auto& p : trajectory) {
    std::fprintf(out.f, "%.9f,%.9g,%.9g,%.9g\n", p.t_s, p.x_m, p.y_m, p.yaw_rad);
  }
  out.commit(path);
}

std::vector<eval::TrajectoryPoint> read_trajectory_csv(const std::string& path) {
  const CsvColumns c = read_csv(path, {"t", "x", "y", "yaw"});
  std::vector<eval::TrajectoryPoint> out;
  out.reserve(c.rows.size());
  for (const auto& r : c.rows) out.push_back({r[0], r[1], r[2], r[3]});
  return out;
}

}  // namespace dispel::io
