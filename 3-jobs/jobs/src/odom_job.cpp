#include "dispel/jobs/odom_job.hpp"

#include <cmath>
#include <limits>
#include <optional>
#include <vector>

#include "dispel/io/config_yaml.hpp"
#include "dispel/io/csv.hpp"
#include "dispel/io/odometry_inputs.hpp"
#include "dispel/io/text.hpp"
#include "dispel/pipeline/odometry_runner.hpp"

namespace dispel::jobs {
namespace {

using io::MessageKind;

// Which topics of a recording hold the wheels, the IMU and the truth.
struct Sources {
  std::string wheels;
  bool wheels_from_odometry = false;
  std::string imu;  // Empty: none.
  bool truth_is_gps = false;
};

Sources choose_topics(const OdomJobOptions& o, const io::Topics& topics) {
  const auto joint_topics = topics.of_kind(MessageKind::kJointState);
  const auto odom_topics = topics.of_kind(MessageKind::kOdometry);
  const auto list = io::join_names;
  Sources s;
  s.wheels = o.wheel_topic;
  if (s.wheels.empty()) {
    if (topics.has("/wheels")) {
      s.wheels = "/wheels";
    } else if (joint_topics.size() == 1) {
      s.wheels = joint_topics.front();
    } else if (joint_topics.empty() && odom_topics.size() == 1) {
      s.wheels = odom_topics.front();
    } else {
      throw JobError(o.input + ": which topic holds the wheel speeds? (JointState topics: " +
                     list(joint_topics) + "; Odometry topics: " + list(odom_topics) +
                     "); choose one with --wheel-topic");
    }
  }
  s.wheels_from_odometry = topics.has(s.wheels, MessageKind::kOdometry);
  if (!s.wheels_from_odometry && !topics.has(s.wheels, MessageKind::kJointState)) {
    throw JobError(o.input + ": no sensor_msgs/JointState or nav_msgs/Odometry topic " + s.wheels +
                   " (JointState topics: " + list(joint_topics) +
                   "; Odometry topics: " + list(odom_topics) + ")");
  }
  s.imu = o.imu_topic;
  const auto imu_topics = topics.of_kind(MessageKind::kImu);
  if (s.imu.empty()) {
    if (imu_topics.size() == 1) s.imu = imu_topics.front();
    if (imu_topics.size() > 1) {
      throw JobError(o.input + ": several IMU topics (" + list(imu_topics) +
                     "); choose one with --imu-topic, or --imu-topic none");
    }
  } else if (s.imu != "none" && !topics.has(s.imu, MessageKind::kImu)) {
    throw JobError(o.input + ": no sensor_msgs/Imu topic " + s.imu +
                   " (Imu topics: " + list(imu_topics) + ")");
  }
  if (s.imu == "none") s.imu.clear();
  s.truth_is_gps = topics.has(o.truth_topic, MessageKind::kNavSatFix);
  if (!o.truth_csv.empty() && !s.truth_is_gps &&
      !topics.has(o.truth_topic, MessageKind::kOdometry)) {
    throw JobError(o.input + ": no nav_msgs/Odometry or sensor_msgs/NavSatFix topic " +
                   o.truth_topic + " for --truth-csv (Odometry topics: " + list(odom_topics) +
                   "; NavSatFix topics: " + topics.list(MessageKind::kNavSatFix) + ")");
  }
  return s;
}

// East and north in metres from the first fix (a local tangent plane; fine over kilometres).
// GPS has no heading: yaw NaN.
class GpsTrack {
 public:
  void add(const io::NavSatFixMessage& fix, const io::Stamp& received,
           std::vector<eval::TrajectoryPoint>& out) {
    if (fix.status < 0 || !std::isfinite(fix.latitude_deg) || !std::isfinite(fix.longitude_deg)) {
      return;
    }
    if (!have_origin_) {
      lat0_ = fix.latitude_deg;
      lon0_ = fix.longitude_deg;
      have_origin_ = true;
    }
    constexpr double kEarthRadius_m = 6378137.0, kDeg = 3.14159265358979323846 / 180.0;
    out.push_back({io::stamp_or(fix.header.stamp, received),
                   kEarthRadius_m * (fix.longitude_deg - lon0_) * kDeg * std::cos(lat0_ * kDeg),
                   kEarthRadius_m * (fix.latitude_deg - lat0_) * kDeg,
                   std::numeric_limits<double>::quiet_NaN()});
  }

 private:
  bool have_origin_ = false;
  double lat0_ = 0.0, lon0_ = 0.0;
};

// Reads the bag's wheels, IMU and truth into the runner (and the truth into @p truth); returns the
// number of wheel measurements.
std::int64_t read_bag(const OdomJobOptions& o, const io::OdometrySettings& settings,
                      pipeline::OdometryRunner& runner, OdomJobStats& stats,
                      std::vector<eval::TrajectoryPoint>& truth) {
  const std::unique_ptr<io::RecordingReader> in = open_recording(o.input);
  const Sources s = choose_topics(o, in->topics());
  stats.wheel_source = s.wheels;
  stats.imu_source = s.imu;
  const double b = settings.filter.track_width_m;
  GpsTrack gps;
  std::int64_t wheels = 0;
  std::vector<std::string> wanted{s.wheels};
  if (!s.imu.empty()) wanted.push_back(s.imu);
  if (!o.truth_csv.empty()) wanted.push_back(o.truth_topic);
  as_job([&] {
    in->read(wanted, [&](const io::RecordedMessage& m) {
      const std::string& topic = m.topic();
      if (topic == s.wheels) {
        ++stats.wheel_messages;
        std::optional<io::WheelSpeeds> w;
        if (s.wheels_from_odometry) {
          if (const auto od = m.odometry()) w = io::wheel_speeds(*od, b, m.time());
        } else if (const auto js = m.joint_state()) {
          w = io::wheel_speeds(*js, settings, m.time());
          if (!w) ++stats.malformed;
        }
        if (w) {
          runner.add_wheels(w->t_s, w->left_mps, w->right_mps);
          ++wheels;
        }
      }
      if (topic == s.imu) {
        ++stats.imu_messages;
        if (const auto imu = m.imu()) {
          runner.add_imu(io::stamp_or(imu->header.stamp, m.time()), io::yaw_rate(*imu, settings));
        }
      }
      if (o.truth_csv.empty() || topic != o.truth_topic) return;
      if (s.truth_is_gps) {
        if (const auto fix = m.nav_sat_fix()) gps.add(*fix, m.time(), truth);
      } else if (const auto od = m.odometry()) {
        truth.push_back({io::stamp_or(od->header.stamp, m.time()), od->pose.x_m, od->pose.y_m,
                         od->pose.yaw_rad});
      }
    });
  });
  return wheels;
}

std::int64_t read_csvs(const OdomJobOptions& o, pipeline::OdometryRunner& runner,
                       OdomJobStats& stats) {
  return as_job([&] {
    const io::CsvColumns w = io::read_csv(o.wheels_csv, {"t", "v_left", "v_right"});
    for (const auto& r : w.rows) runner.add_wheels(r[0], r[1], r[2]);
    stats.wheel_source = o.wheels_csv;
    stats.wheel_messages = static_cast<std::int64_t>(w.rows.size());
    if (o.imu_csv.empty()) return stats.wheel_messages;
    const io::CsvColumns i = io::read_csv(o.imu_csv, {"t", "yaw_rate"});
    for (const auto& r : i.rows) runner.add_imu(r[0], r[1]);
    stats.imu_source = o.imu_csv;
    stats.imu_messages = static_cast<std::int64_t>(i.rows.size());
    return stats.wheel_messages;
  });
}

void write_row(io::CsvWriter& out, const OdometryEstimate& e) {
  out.printf("%.9f,%.9g,%.9g,%.9g,%.9g,%.9g,%.6g,%.6g,%.6g,%.6g,%.6g\n", e.t_s, e.x_m, e.y_m,
             e.yaw_rad, e.v_mps, e.omega_radps, e.x_variance_m2, e.y_variance_m2,
             e.yaw_variance_rad2, e.v_variance_m2ps2, e.omega_variance_rad2ps2);
}

}  // namespace

OdomJobStats run_odom_job(const OdomJobOptions& o) {
  if (o.input.empty() == o.wheels_csv.empty()) {
    throw JobError("give either a bag or --wheels-csv (not both)");
  }
  if (!o.imu_csv.empty() && o.wheels_csv.empty()) {
    throw JobError("--imu-csv needs --wheels-csv");
  }
  io::OdometrySettings settings;
  if (o.config_path) settings = as_job([&] { return io::load_odometry_settings(*o.config_path); });
  pipeline::OdometryEngine engine = pipeline::OdometryEngine::kFusion;
  if (o.model) {
    if (*o.model == "ct") {
      settings.filter.model = OdometryModel::kCt;
    } else if (*o.model == "ct_euler") {
      settings.filter.model = OdometryModel::kCtEuler;
    } else if (*o.model == "omni") {
      settings.filter.model = OdometryModel::kOmni;
    } else if (*o.model == "dead_reckoning") {
      engine = pipeline::OdometryEngine::kDeadReckoning;
    } else {
      throw JobError("--model must be one of ct, ct_euler, omni, dead_reckoning, got '" + *o.model +
                     "'");
    }
  }
  OdomJobStats stats;
  stats.model = engine == pipeline::OdometryEngine::kDeadReckoning
                    ? "dead_reckoning"
                    : odometry_model_name(settings.filter.model);
  stats.track_width_m = settings.filter.track_width_m;
  // The whole recording is sorted by stamp: an infinite reordering window, one flush.
  pipeline::OdometryRunner runner = as_job([&] {
    return pipeline::OdometryRunner(settings.filter, std::numeric_limits<double>::infinity(),
                                    engine);
  });
  std::vector<eval::TrajectoryPoint> truth;
  const std::int64_t wheels =
      o.input.empty() ? read_csvs(o, runner, stats) : read_bag(o, settings, runner, stats, truth);
  if (wheels == 0) throw JobError(stats.wheel_source + ": no wheel speeds");
  stats.stamps_out_of_order = runner.arrived_out_of_order();

  as_job([&] {
    io::CsvWriter out(o.output);
    out.line("t,x,y,yaw,v,omega,var_x,var_y,var_yaw,var_v,var_omega");
    for (const OdometryEstimate& e : runner.release(true)) {
      write_row(out, e);
      ++stats.rows;
    }
    stats.counters = runner.counters();
    stats.final_estimate = runner.estimate();
    if (stats.rows == 0) throw JobError(stats.wheel_source + ": no usable wheel speeds");
    // Both files written and closed before either appears: a write error leaves neither.
    std::optional<io::CsvWriter> truth_out;
    if (!o.truth_csv.empty()) {
      truth_out.emplace(o.truth_csv);
      io::write_trajectory(*truth_out, truth);
      stats.truth_rows = static_cast<std::int64_t>(truth.size());
      truth_out->close();
    }
    out.close();
    out.commit();
    if (truth_out) truth_out->commit();
  });
  return stats;
}

}  // namespace dispel::jobs
