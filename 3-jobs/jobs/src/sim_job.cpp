#include "dispel/jobs/sim_job.hpp"

#include <sys/statvfs.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <optional>
#include <utility>

#include "dispel/io/text.hpp"

namespace dispel::jobs {

SimulationWriter::SimulationWriter(const sim::Scenario& scenario, const std::string& path)
    : scan_time_s_(static_cast<float>(1.0 / scenario.lidar.rate_hz)),
      out_(create_recording(path, writes_sqlite3(path) ? Compression::kNone : Compression::kLz4)) {
  as_job([&] {
    // The first scan and sample of a run are stamped with the scenario's start time.
    const io::Stamp start = io::Stamp::from_seconds(scenario.start_time_s);
    out_->write("/tf_static", start,
                io::TransformsMessage{{{start, "base_link", "laser", scenario.robot.laser_mount}}});
  });
}

SimulationWriter::~SimulationWriter() = default;

void SimulationWriter::scan(const sim::ScanFrame& f) {
  as_job([&] {
    io::ScanMessage msg = io::scan_message(f.scan, "laser");
    msg.scan_time = scan_time_s_;
    out_->write("/scan", msg.header.stamp, msg);
    msg.scan.intensities.resize(f.truth.size());
    for (std::size_t i = 0; i < f.truth.size(); ++i) {
      msg.scan.intensities[i] = static_cast<float>(f.truth[i]);
    }
    out_->write("/scan_truth", msg.header.stamp, msg);
    for (std::size_t i = 0; i < f.actor.size(); ++i) {
      msg.scan.intensities[i] = static_cast<float>(f.actor[i]);
    }
    out_->write("/scan_truth_actor", msg.header.stamp, msg);
  });
}

void SimulationWriter::sensor(const sim::SensorSample& s) {
  as_job([&] {
    const io::Stamp t = io::Stamp::from_seconds(s.stamp_s);
    out_->write("/odom", t,
                io::odometry_message(s.stamp_s, "odom", "base_link", s.odom_pose, s.odom_v_mps,
                                     s.odom_w_radps));
    out_->write("/ground_truth", t,
                io::odometry_message(s.stamp_s, "map", "base_link", s.true_pose, s.true_v_mps,
                                     s.true_w_radps));
    io::JointStateMessage wheels;
    wheels.header.stamp = t;
    wheels.names = {"left_wheel", "right_wheel"};
    wheels.velocities = {s.wheel_left_mps, s.wheel_right_mps};
    out_->write("/wheels", t, wheels);
    io::ImuMessage imu;
    imu.header.stamp = t;
    imu.header.frame_id = "base_link";
    imu.angular_velocity_radps.z() = s.imu_yaw_rate_radps;
    out_->write("/imu", t, imu);
  });
}

void SimulationWriter::finish() {
  as_job([&] { out_->finish(); });
}

void write_simulation(const sim::SimulationOutput& run, const sim::Scenario& scenario,
                      const std::string& path, const std::atomic<bool>* cancel) {
  check_cancelled(cancel);
  SimulationWriter out(scenario, path);
  // The two lists merged in time order, as the stream comes: at the same instant the scan first.
  std::size_t next_scan = 0;
  const auto write_scans_until = [&](double t) {
    for (; next_scan < run.scans.size() && run.scans[next_scan].scan.stamp_s <= t; ++next_scan) {
      out.scan(run.scans[next_scan]);
    }
  };
  for (const sim::SensorSample& s : run.sensors) {
    check_cancelled(cancel);
    write_scans_until(s.stamp_s);
    out.sensor(s);
  }
  write_scans_until(std::numeric_limits<double>::infinity());
  out.finish();
}

namespace {

// The serialized size of each message (ROS 1) plus its record in the bag (the record's header:
// op, conn, time, lengths) and its index entry.
constexpr double kRecordBytes = 52.0;
// /scan: header with "laser" (21), seven floats (28), ranges (4 + 4 per beam), no intensities
// (4); /scan_truth and /scan_truth_actor with intensities (4 + 4 per beam).
constexpr double kScanFixedBytes = 3.0 * (57.0 + kRecordBytes);
constexpr double kScanPerBeamBytes = 4.0 + 8.0 + 8.0;
// /odom and /ground_truth (about 712 each: header, child frame, pose, twist, two covariances of
// 36 doubles), /wheels (77), /imu (321).
constexpr double kSampleBytes = 713.0 + 712.0 + 77.0 + 321.0 + 4.0 * kRecordBytes;
// What LZ4 leaves of the estimated bytes, measured as file size / estimate on 60 s bags that
// dispel sim wrote (seed 1, December 2; docs/simulator.md, "Bounds"): warehouse_forklift 0.204
// (1618 beams, 40 m: walls everywhere), soak 0.183, office_corridors 0.168, thesis_hall 0.041 and
// empty_hall 0.030 (the range cut to 5.5 m: most beams return nothing, which compresses well).
// The largest: the estimate is an upper bound, up to 7 times too high for a scenario whose beams
// mostly return nothing.
constexpr double kLz4Factor = 0.21;

std::string size_text(double bytes) {
  const char* units[] = {"bytes", "kB", "MB", "GB", "TB", "PB", "EB"};
  int u = 0;
  while (bytes >= 1000.0 && u < 6) {
    bytes /= 1000.0;
    ++u;
  }
  char text[64];
  std::snprintf(text, sizeof text, u == 0 ? "%.0f %s" : "%.1f %s", bytes, units[u]);
  return text;
}

// The free space of the folder @p path is written in; nullopt for a device or pipe (written in
// place) or when statvfs cannot tell.
std::optional<double> free_bytes_for(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (!ec && fs::exists(st) && !fs::is_regular_file(st)) return std::nullopt;
  fs::path dir = fs::path(path).parent_path();
  if (dir.empty()) dir = ".";
  struct statvfs v {};
  if (::statvfs(dir.c_str(), &v) != 0) return std::nullopt;
  return static_cast<double>(v.f_bavail) * static_cast<double>(v.f_frsize);
}

}  // namespace

double estimate_recording_bytes(const sim::Scenario& scenario, double duration_s) {
  const double beams = static_cast<double>(sim::lidar_geometry(scenario.lidar).beam_count);
  const double scans = std::floor(duration_s * scenario.lidar.rate_hz) + 1.0;
  const double samples = std::floor(duration_s * scenario.sensors.rate_hz) + 1.0;
  const double raw = scans * (kScanFixedBytes + kScanPerBeamBytes * beams) + samples * kSampleBytes;
  return raw * kLz4Factor;
}

SimulationSummary simulate_to_recording(const sim::Scenario& scenario, std::uint64_t seed,
                                        double duration_s, const std::string& path,
                                        const std::atomic<bool>* cancel) {
  check_cancelled(cancel);
  const double duration = as_job([&] { return sim::run_duration(scenario, duration_s); });
  const double need = estimate_recording_bytes(scenario, duration);
  if (const std::optional<double> free = free_bytes_for(path); free && need > *free) {
    char d[32];
    std::snprintf(d, sizeof d, "%g", duration);
    const bool given = !(duration_s <= 0.0);
    throw JobError(std::string(given ? "--duration " : "duration_s ") + d +
                   " s would write a bag of about " + size_text(need) + ", but " +
                   io::quote(std::filesystem::path(path).parent_path().empty()
                                 ? std::string(".")
                                 : std::filesystem::path(path).parent_path().string(),
                             200) +
                   " has " + size_text(*free) + " free");
  }
  SimulationWriter out(scenario, path);
  SimulationSummary summary;
  sim::SimulationSink sink;
  sink.scan = [&](sim::ScanFrame&& frame) {
    for (const sim::Truth t : frame.truth) ++summary.beams[static_cast<std::size_t>(t)];
    ++summary.scans;
    out.scan(frame);
  };
  sink.sensor = [&](const sim::SensorSample& sample) {
    check_cancelled(cancel);
    out.sensor(sample);
  };
  summary.actor_count = as_job([&] { return sim::simulate(scenario, seed, duration_s, sink); });
  out.finish();
  return summary;
}

}  // namespace dispel::jobs
