// dispel_soak: the simulator streamed into the dynamic filter (pipeline::ScanFilterRunner, the
// road `dispel filter` and the nodes take) and the odometry fusion (pipeline::OdometryRunner), in
// one process, no files, at full speed, for hours of simulated time. One table row per period:
// memory, per-scan filter times, tracks, the registered map, odometry fusion time, share of beams
// removed; at the end a verdict whether memory and the 99th percentile stayed flat. Timing never
// fails the run: exit 0 when it ran, 1 on an error, 2 on a bad command line (docs/soak.md).

#include <sys/resource.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <fstream>
#include <iostream>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "dispel/core/dynamic_filter.hpp"
#include "dispel/core/percentile.hpp"
#include "dispel/core/pose_buffer.hpp"
#include "dispel/io/config_yaml.hpp"
#include "dispel/io/scenario_yaml.hpp"
#include "dispel/io/text.hpp"
#include "dispel/pipeline/odometry_runner.hpp"
#include "dispel/pipeline/scan_filter_runner.hpp"
#include "dispel/sim/simulator.hpp"

#ifndef DISPEL_SOAK_SCENARIO
#define DISPEL_SOAK_SCENARIO "config/scenarios/soak.yaml"
#endif

namespace {

using Clock = std::chrono::steady_clock;

struct Options {
  double hours = 24.0;
  std::string scenario = DISPEL_SOAK_SCENARIO;
  std::string config;  // Empty: dispel's default filter and odometry.
  std::uint64_t seed = 1;
  double report_every_s = 3600.0;
};

// Resident memory now, from /proc/self/statm (the second field, in pages); 0 when unreadable.
double rss_mib() {
  std::ifstream statm("/proc/self/statm");
  long long size = 0, resident = 0;
  if (!(statm >> size >> resident)) return 0.0;
  return static_cast<double>(resident) * static_cast<double>(::sysconf(_SC_PAGESIZE)) /
         (1024.0 * 1024.0);
}

// The peak resident memory of the process so far (getrusage: KiB on Linux).
double peak_rss_mib() {
  rusage u{};
  if (::getrusage(RUSAGE_SELF, &u) != 0) return 0.0;
  return static_cast<double>(u.ru_maxrss) / 1024.0;
}

// One period's figures, reset after its row is printed (vectors keep their capacity).
struct Period {
  std::int64_t scans = 0;
  std::vector<float> filter_us;  // Per scan: wall time (steady_clock).
  std::vector<float> cpu_us;     // Per scan: the thread's CPU time (ScanFilterRunner).
  std::vector<float> odom_us;    // Per sensor sample (wheels + IMU added, estimates released).
  std::int64_t beams = 0;
  std::int64_t removed = 0;
  std::size_t tracks_max = 0;
  std::int64_t map_voxels = 0;  // After the period's last filtered scan.
  void clear() {
    scans = 0;
    filter_us.clear();
    cpu_us.clear();
    odom_us.clear();
    beams = removed = 0;
    tracks_max = 0;
  }
};

struct Row {
  double hours = 0.0;
  double rss = 0.0;
  double p99_us = 0.0;
  double cpu_p99_us = 0.0;
};

int run(const Options& o) {
  const dispel::sim::Scenario scenario = dispel::io::load_scenario(o.scenario);
  dispel::pipeline::ScanFilterRunnerOptions filter_options;
  dispel::io::OdometrySettings odometry;
  if (!o.config.empty()) {
    filter_options.config = dispel::io::load_filter_config(o.config);
    odometry = dispel::io::load_odometry_settings(o.config);
  }
  // As `dispel filter --scale-to-scanner` runs on the simulator's bag: the thesis's counts carried
  // over to this scanner, its period from the scans' stated scan_time.
  filter_options.scale_to_scanner = true;
  odometry.filter.track_width_m = scenario.robot.wheel_base_m;
  dispel::pipeline::ScanFilterRunner filter(filter_options);
  // Measurements come in stamp order: released as they come (no reordering window).
  dispel::pipeline::OdometryRunner fusion(odometry.filter, 0.0);

  const double duration_s = o.hours * 3600.0;
  // The simulator's stamps are a bag's, 32-bit seconds (sim::run_duration would name --duration).
  if (!(scenario.start_time_s + duration_s < 4294967295.0)) {
    throw std::invalid_argument(
        "--hours must keep the stamps below 2^32 s: at most " +
        std::to_string(static_cast<long long>((4294967295.0 - scenario.start_time_s) / 3600.0)) +
        " h from this scenario's start");
  }
  const auto periods = std::max<std::int64_t>(
      1, static_cast<std::int64_t>(std::ceil(duration_s / o.report_every_s - 1e-9)));
  const double scan_period_s = 1.0 / scenario.lidar.rate_hz;
  const dispel::Pose2 mount = scenario.robot.laser_mount;

  std::printf("dispel_soak: %s, seed %llu, %.4g simulated h, a row every %.4g s\n",
              dispel::io::quote(o.scenario, 200).c_str(), static_cast<unsigned long long>(o.seed),
              o.hours, o.report_every_s);
  std::printf("%8s %9s %8s %9s %9s %9s %9s %8s %8s %6s %6s %7s %8s %8s %8s\n", "sim_h", "scans",
              "rss_MiB", "filt_med", "filt_p99", "filt_p999", "filt_max", "cpu_med", "cpu_p99",
              "tracks", "trk_mx", "voxels", "odom_med", "odom_p99", "removed");
  std::printf("%8s %9s %8s %9s %9s %9s %9s %8s %8s %6s %6s %7s %8s %8s %8s\n", "", "", "", "us",
              "us", "us", "us", "us", "us", "", "", "", "us", "us", "share");
  std::fflush(stdout);

  Period period;
  std::vector<Row> rows;
  std::int64_t current = 0;
  std::int64_t total_scans = 0;
  const auto report = [&](std::int64_t index) {
    Row row;
    row.hours = std::min(duration_s, static_cast<double>(index + 1) * o.report_every_s) / 3600.0;
    row.rss = rss_mib();
    const double filt_med = dispel::percentile(period.filter_us, 0.5);
    row.p99_us = dispel::percentile(period.filter_us, 0.99);
    const double filt_p999 = dispel::percentile(period.filter_us, 0.999);
    const double filt_max = period.filter_us.empty() ? 0.0
                                                     : *std::max_element(period.filter_us.begin(),
                                                                         period.filter_us.end());
    const double cpu_med = dispel::percentile(period.cpu_us, 0.5);
    row.cpu_p99_us = dispel::percentile(period.cpu_us, 0.99);
    const double odom_med = dispel::percentile(period.odom_us, 0.5);
    const double odom_p99 = dispel::percentile(period.odom_us, 0.99);
    const double removed =
        period.beams > 0 ? static_cast<double>(period.removed) / static_cast<double>(period.beams)
                         : 0.0;
    std::printf(
        "%8.3f %9lld %8.1f %9.0f %9.0f %9.0f %9.0f %8.0f %8.0f %6lld %6zu %7lld %8.1f %8.1f "
        "%8.4f\n",
        row.hours, static_cast<long long>(period.scans), row.rss, filt_med, row.p99_us, filt_p999,
        filt_max, cpu_med, row.cpu_p99_us, static_cast<long long>(filter.counts().tracks),
        period.tracks_max, static_cast<long long>(period.map_voxels), odom_med, odom_p99, removed);
    std::fflush(stdout);
    rows.push_back(row);
    period.clear();
  };
  // Advances the period to the one holding @p elapsed_s (the last one holds the run's end).
  const auto enter = [&](double elapsed_s) {
    const auto index = std::min<std::int64_t>(
        periods - 1, static_cast<std::int64_t>(std::floor(elapsed_s / o.report_every_s)));
    while (current < index) {
      report(current);
      ++current;
    }
  };

  // A scan waits for the odometry sample at or after its stamp (at most one sample period).
  std::deque<dispel::sim::ScanFrame> waiting;
  // The odometry's poses, interpolated at the scans' stamps and forgotten once behind them.
  dispel::PoseBuffer odometry_poses;
  const auto filter_scan = [&](const dispel::sim::ScanFrame& frame,
                               const std::optional<dispel::Pose2>& sensor_pose) {
    enter(frame.scan.stamp_s - scenario.start_time_s);
    const Clock::time_point t0 = Clock::now();
    const dispel::FilterResult& result = filter.process(frame.scan, scan_period_s, sensor_pose);
    const Clock::time_point t1 = Clock::now();
    period.filter_us.push_back(
        static_cast<float>(std::chrono::duration<double, std::micro>(t1 - t0).count()));
    period.cpu_us.push_back(static_cast<float>(filter.last_cpu_time_s() * 1e6));
    if (filter.last_outcome() == dispel::pipeline::ScanOutcome::kFiltered) {
      period.map_voxels = result.work.map_voxels;
    }
    ++period.scans;
    ++total_scans;
    period.beams += static_cast<std::int64_t>(result.labels.size());
    period.removed += result.removed_dynamic + result.removed_unknown;
    period.tracks_max = std::max(period.tracks_max, result.tracks.size());
  };
  dispel::sim::SimulationSink sink;
  sink.scan = [&](dispel::sim::ScanFrame&& frame) { waiting.push_back(std::move(frame)); };
  sink.sensor = [&](const dispel::sim::SensorSample& s) {
    odometry_poses.add(s.stamp_s, s.odom_pose);
    // The scans up to this sample first (they may belong to the period before it).
    while (!waiting.empty() && waiting.front().scan.stamp_s <= s.stamp_s) {
      const dispel::sim::ScanFrame& frame = waiting.front();
      dispel::Pose2 odometry_pose;
      if (odometry_poses.lookup(frame.scan.stamp_s, odometry_pose) == dispel::PoseLookup::kOk) {
        filter_scan(frame, odometry_pose * mount);
      } else {
        filter_scan(frame, std::nullopt);
      }
      odometry_poses.forget_before(frame.scan.stamp_s);
      waiting.pop_front();
    }
    enter(s.stamp_s - scenario.start_time_s);
    const Clock::time_point t0 = Clock::now();
    fusion.add_wheels(s.stamp_s, s.wheel_left_mps, s.wheel_right_mps);
    fusion.add_imu(s.stamp_s, s.imu_yaw_rate_radps);
    fusion.release();
    const Clock::time_point t1 = Clock::now();
    period.odom_us.push_back(
        static_cast<float>(std::chrono::duration<double, std::micro>(t1 - t0).count()));
  };
  const Clock::time_point start = Clock::now();
  dispel::sim::simulate(scenario, o.seed, duration_s, sink);
  // Scans after the last sample (none when the rates divide evenly): filtered without a pose.
  for (const dispel::sim::ScanFrame& frame : waiting) filter_scan(frame, std::nullopt);
  report(current);
  const double wall_s = std::chrono::duration<double>(Clock::now() - start).count();

  std::printf(
      "%lld scans in %.1f s of wall time (%.0f scans/s, %.1f simulated s per wall s); "
      "peak RSS %.1f MiB\n",
      static_cast<long long>(total_scans), wall_s,
      static_cast<double>(total_scans) / std::max(wall_s, 1e-9),
      duration_s / std::max(wall_s, 1e-9), peak_rss_mib());
  // The verdict compares the last period with the second (the first includes the warm-up: the
  // map filling, the allocator growing): flat when the last period's RSS is at most 10% or
  // 16 MiB (whichever is more) above the second's, and its p99 filter time, wall and CPU, at
  // most 1.5 times the second's plus 100 us (timing on a shared machine is noisy; the CPU time
  // leaves out the waits for a CPU). Reported, never a failure.
  if (rows.size() < 2) {
    std::printf(
        "verdict: not judged (%zu period; the rule compares the last period with the "
        "second)\n",
        rows.size());
    return 0;
  }
  const Row& second = rows[1];
  const Row& last = rows.back();
  const bool rss_flat = last.rss <= std::max(second.rss * 1.10, second.rss + 16.0);
  const bool p99_flat = last.p99_us <= second.p99_us * 1.5 + 100.0;
  const bool cpu_flat = last.cpu_p99_us <= second.cpu_p99_us * 1.5 + 100.0;
  std::printf(
      "verdict: RSS %s (%.1f MiB at %.3f h against %.1f MiB at %.3f h; flat: within "
      "max(10%%, 16 MiB)); p99 %s (%.0f us against %.0f us), CPU p99 %s (%.0f us against "
      "%.0f us; flat: at most 1.5x + 100 us)\n",
      rss_flat ? "flat" : "GROWING", last.rss, last.hours, second.rss, second.hours,
      p99_flat ? "flat" : "GROWING", last.p99_us, second.p99_us, cpu_flat ? "flat" : "GROWING",
      last.cpu_p99_us, second.cpu_p99_us);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "dispel_soak: the simulator streamed into the dynamic filter and the odometry fusion, in "
      "one process, for hours of simulated time; a table of memory and times per period "
      "(docs/soak.md)"};
  Options o;
  app.add_option("--hours", o.hours, "Simulated hours (default 24)");
  app.add_option("--scenario", o.scenario, "Scenario YAML (default config/scenarios/soak.yaml)");
  app.add_option("--config", o.config,
                 "Filter configuration YAML, its odometry: section too "
                 "(default: dispel's default)");
  app.add_option("--seed", o.seed, "Random seed");
  app.add_option("--report-every-s", o.report_every_s,
                 "Simulated seconds per table row (default 3600)");
  try {
    app.parse(argc, argv);
    if (!(std::isfinite(o.hours) && o.hours > 0.0)) {
      throw CLI::ValidationError("--hours",
                                 "must be a finite number > 0, got " + std::to_string(o.hours));
    }
    if (!(std::isfinite(o.report_every_s) && o.report_every_s > 0.0)) {
      throw CLI::ValidationError("--report-every-s", "must be a finite number > 0, got " +
                                                         std::to_string(o.report_every_s));
    }
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::cerr << "dispel_soak: " << e.what() << "\n";
    return 2;
  }
  try {
    return run(o);
  } catch (const std::exception& e) {
    std::cerr << "dispel_soak: " << dispel::io::one_line(e.what(), 400) << "\n";
    return 1;
  }
}
