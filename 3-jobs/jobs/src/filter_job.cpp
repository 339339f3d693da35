#include "dispel/jobs/filter_job.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "dispel/io/carmen.hpp"
#include "dispel/io/config_yaml.hpp"
#include "dispel/io/recording_motion.hpp"
#include "dispel/io/text.hpp"
#include "dispel/pipeline/scan_filter_runner.hpp"

namespace dispel::jobs {
namespace {

using io::ends_with;

void check_period(const FilterJobOptions& o, const std::optional<double>& period,
                  const LaserScan& first) {
  if (o.scale_to_scanner && (!period || !(first.angle_increment_rad > 0.0))) {
    throw JobError(o.input +
                   ": --scale-to-scanner needs scans with a positive angle increment and "
                   "increasing stamps (or a stated scan_time)");
  }
}

// The scans' road to the filter, with the job's bookkeeping: the runner, and why each scan it
// passed through was passed through.
class ScanFilter {
 public:
  ScanFilter(const FilterJobOptions& o, FilterJobStats& stats)
      : runner_({filter_config(o), o.scale_to_scanner, 0.0, o.static_sensor}), stats_(stats) {}

  // @p why: why @p pose is std::nullopt (counted as odometry_<why>).
  const FilterResult& process(const LaserScan& scan, double stated_period_s,
                              const std::optional<Pose2>& pose, PoseLookup why) {
    const FilterResult& result = runner_.process(scan, stated_period_s, pose);
    ++stats_.scans;
    stats_.scan_time_s.push_back(runner_.last_time_s());
    stats_.scan_cpu_time_s.push_back(runner_.last_cpu_time_s());
    keep_if_slow(scan, result);
    if (result.registration.registered) {
      stats_.registration_residual_m.push_back(result.registration.residual_m);
      stats_.registration_inlier_share.push_back(result.registration.inlier_share);
      stats_.registration_degeneracy.push_back(result.registration.degeneracy);
    }
    switch (runner_.last_outcome()) {
      case pipeline::ScanOutcome::kFiltered:
        ++stats_.scans_filtered;
        break;
      case pipeline::ScanOutcome::kBadScan:
        ++stats_
              .scans_skipped[std::string("bad_scan_") + scan_issue_name(result.segmentation.issue)];
        break;
      case pipeline::ScanOutcome::kBadPose:
        ++stats_.scans_skipped["bad_pose"];
        break;
      case pipeline::ScanOutcome::kNoPose:
        ++stats_.scans_skipped[std::string("odometry_") + pose_lookup_name(why)];
        break;
      case pipeline::ScanOutcome::kWaitingForPeriod:
        ++stats_.scans_skipped["waiting_for_scan_period"];
        break;
    }
    return result;
  }

  void finish() {
    stats_.counters = runner_.filter_counters();
    stats_.config = runner_.config();
    stats_.scan_period_s = runner_.scan_period_s();
    warn_when_mostly_unfiltered();
  }

 private:
  // Keeps the kSlowScansKept scans that cost the most CPU time (a short list, sorted costliest
  // first: an insertion per slow scan).
  void keep_if_slow(const LaserScan& scan, const FilterResult& result) {
    std::vector<SlowScan>& slow = stats_.slowest_scans;
    const double cpu = runner_.last_cpu_time_s();
    if (slow.size() == FilterJobStats::kSlowScansKept && !(cpu > slow.back().cpu_time_s)) return;
    const SlowScan s{stats_.scans - 1, scan.stamp_s, runner_.last_time_s(), cpu,
                     result.event,     result.work};
    const auto at = std::upper_bound(
        slow.begin(), slow.end(), s,
        [](const SlowScan& a, const SlowScan& b) { return a.cpu_time_s > b.cpu_time_s; });
    slow.insert(at, s);
    if (slow.size() > FilterJobStats::kSlowScansKept) slow.pop_back();
  }

  // A log whose scans mostly reset the filter or pass through is filtered into (almost) nothing;
  // the summary alone ("0 dynamic removed") would not say so.
  void warn_when_mostly_unfiltered() {
    const auto event = [&](FilterEvent e) {
      return stats_.counters.events[static_cast<std::size_t>(e)];
    };
    const std::int64_t gap = event(FilterEvent::kResetTimeGap);
    const std::int64_t back = event(FilterEvent::kResetTimeBackwards);
    const std::int64_t jump = event(FilterEvent::kResetPoseJump);
    stats_.scans_reset = gap + back + jump;
    std::int64_t passed = 0;
    for (const auto& [reason, n] : stats_.scans_skipped) passed += n;
    const std::int64_t unfiltered = stats_.scans_reset + passed;
    stats_.mostly_unfiltered = stats_.scans > 0 && 2 * unfiltered > stats_.scans;
    if (!stats_.mostly_unfiltered) return;
    char text[400];
    std::snprintf(text, sizeof text,
                  "%lld of %lld scans reset the filter (%lld after a time gap above "
                  "max_time_gap_s %.3g s, %lld with time going back, %lld after a pose jump) "
                  "and %lld were passed through unchanged: moving objects are hardly removed "
                  "(a sparse or subsampled log?)",
                  static_cast<long long>(stats_.scans_reset), static_cast<long long>(stats_.scans),
                  static_cast<long long>(gap), stats_.config.max_time_gap_s,
                  static_cast<long long>(back), static_cast<long long>(jump),
                  static_cast<long long>(passed));
    stats_.warning = text;
  }

 public:
 private:
  pipeline::ScanFilterRunner runner_;
  FilterJobStats& stats_;
};

// The frame of the registered poses: the odometry frame at the first scan, or the first scan's
// sensor frame without odometry.
constexpr const char* kRegisteredFrame = "dispel_registered";

void write_outputs(io::RecordingWriter& out, const std::string& scan_topic, io::Stamp time,
                   const io::ScanMessage& scan, const FilterResult& result) {
  out.write(scan_topic + "_filtered", time, io::filtered_message(scan, result));
  out.write(scan_topic + "_labels", time, io::labels_message(scan, result));
  // The registered sensor pose (registration on): the laser in the filter's fixed frame.
  if (result.sensor_pose && result.registration.points > 0) {
    out.write(scan_topic + "_pose", time,
              io::odometry_message(scan.scan.stamp_s, kRegisteredFrame, scan.header.frame_id,
                                   *result.sensor_pose, 0.0, 0.0));
  }
}

// ------------------------------------------------------------------------------------------
// Recordings (ROS 1 bags).

FilterJobStats run_recording(const FilterJobOptions& o, const Progress& progress,
                             const std::atomic<bool>* cancel, const Notice& notice) {
  FilterJobStats stats;
  const std::unique_ptr<io::RecordingReader> in = open_recording(o.input);
  stats.input_format = in->format_name();
  const io::Topics& topics = in->topics();
  const std::string filtered_topic = o.scan_topic + "_filtered";
  const std::string labels_topic = o.scan_topic + "_labels";
  if (topics.has(o.scan_topic, io::MessageKind::kLaserScan) &&
      (topics.has(filtered_topic) || topics.has(labels_topic))) {
    throw JobError(o.input + ": already has " + filtered_topic + " or " + labels_topic +
                   "; filter the original recording");
  }
  const io::RecordingMotion motion = read_scan_motion(o, *in, cancel, notice);
  stats.odometry_refused = motion.poses_refused;
  stats.laser_only = motion.laser_only;

  ScanFilter filter(o, stats);
  const std::unique_ptr<io::RecordingWriter> out =
      create_recording(o.output, o.compression, o.format);
  as_job([&] {
    copy_recording(*in, *out, stats.left_out, stats.messages_in, cancel, progress,
                   [&](const io::RecordedMessage& m) {
                     if (m.topic() != o.scan_topic) return;
                     const std::optional<io::ScanMessage> scan = m.scan();
                     if (!scan) return;
                     PoseLookup why = PoseLookup::kOk;
                     const std::optional<Pose2> pose = motion.sensor_pose(scan->scan.stamp_s, &why);
                     const FilterResult& result =
                         filter.process(scan->scan, scan->scan_time, pose, why);
                     write_outputs(*out, o.scan_topic, m.time(), *scan, result);
                   });
    out->finish();
  });
  filter.finish();
  stats.messages_out = out->messages_written();
  if (progress) progress(1.0);
  return stats;
}

// ------------------------------------------------------------------------------------------
// CARMEN logs: the laser's pose comes with each laser line. The output carries what `dispel
// render` and `dispel slam` need: /odom (odom -> base_link) at every scan with the pose the
// filter used, the mounts on /tf_static (base_link -> laser: identity; base_link -> rear_laser:
// half a turn), and the log's ODOM lines as they are on /carmen_odom.

// A bag holds no time 0: a log that counts time from 0 (the GMapping-corrected classic logs) is
// shifted by kCarmenStampOffset_s; a log with every stamp at or after 1 s is kept as it is.
constexpr double kCarmenStampOffset_s = 1.0;

double carmen_stamp_offset(const io::CarmenLog& log) {
  double first = std::numeric_limits<double>::infinity();
  for (const io::CarmenScan& s : log.scans) first = std::min(first, s.scan.stamp_s);
  for (const TimedPose& p : log.odometry) first = std::min(first, p.stamp_s);
  return first < kCarmenStampOffset_s ? kCarmenStampOffset_s : 0.0;
}

FilterJobStats run_carmen(const FilterJobOptions& o, const Progress& progress,
                          const std::atomic<bool>* cancel, const Notice& notice) {
  FilterJobStats stats;
  stats.input_format = "carmen";
  const io::CarmenLog log = as_job([&] { return io::read_carmen_log(o.input); });
  stats.messages_in = log.lines;
  stats.malformed_lines = log.malformed_lines;
  const double offset = carmen_stamp_offset(log);
  stats.stamp_offset_s = offset;
  if (offset > 0.0 && notice) {
    notice(o.input +
           " counts time from 0: every stamp is shifted by +1 s (a ROS bag holds no "
           "time 0)");
  }
  pipeline::ScanPeriod period;
  for (std::size_t i = 0; i < log.scans.size() && !period.period(); ++i) {
    period.add(log.scans[i].scan.stamp_s, 0.0);
  }
  check_period(o, period.period(), log.scans.front().scan);

  ScanFilter filter(o, stats);
  const std::unique_ptr<io::RecordingWriter> out =
      create_recording(o.output, o.compression, o.format);
  as_job([&] {
    // The mounts, at the first stamp.
    double first = std::numeric_limits<double>::infinity();
    bool rear = false;
    for (const io::CarmenScan& cs : log.scans) {
      first = std::min(first, cs.scan.stamp_s);
      rear = rear || cs.kind == "RLASER";
    }
    const io::Stamp start = io::Stamp::from_seconds(first + offset);
    io::TransformsMessage mounts{{{start, "base_link", "laser", Pose2{}}}};
    if (rear) mounts.transforms.push_back({start, "base_link", "rear_laser", Pose2{0.0, 0.0, kPi}});
    out->write("/tf_static", start, mounts);

    // ODOM lines and scans in time order.
    std::size_t next_odom = 0;
    const auto write_odom_until = [&](double t) {
      for (; next_odom < log.odometry.size() && log.odometry[next_odom].stamp_s <= t; ++next_odom) {
        const TimedPose& p = log.odometry[next_odom];
        const io::OdometryMessage msg =
            io::odometry_message(p.stamp_s + offset, "odom", "base_link", p.pose);
        out->write("/carmen_odom", msg.header.stamp, msg);
      }
    };
    for (std::size_t i = 0; i < log.scans.size(); ++i) {
      check_cancelled(cancel);
      const io::CarmenScan& cs = log.scans[i];
      write_odom_until(cs.scan.stamp_s);
      const bool is_rear = cs.kind == "RLASER";
      LaserScan scan = cs.scan;
      scan.stamp_s += offset;
      const Pose2 laser = o.static_sensor ? Pose2{} : cs.laser_pose;
      // The robot's pose that puts the laser there through its mount.
      const Pose2 base =
          is_rear ? Pose2{laser.x_m, laser.y_m, wrap_angle(laser.yaw_rad - kPi)} : laser;
      const io::OdometryMessage odom =
          io::odometry_message(scan.stamp_s, "odom", "base_link", base);
      out->write("/odom", odom.header.stamp, odom);
      const io::ScanMessage msg = io::scan_message(scan, is_rear ? "rear_laser" : "laser");
      const FilterResult& result = filter.process(scan, 0.0, laser, PoseLookup::kOk);
      out->write(o.scan_topic, msg.header.stamp, msg);
      write_outputs(*out, o.scan_topic, msg.header.stamp, msg, result);
      if (progress && i % 64 == 0) {
        progress(static_cast<double>(i) / static_cast<double>(log.scans.size()));
      }
    }
    write_odom_until(std::numeric_limits<double>::infinity());
    out->finish();
  });
  filter.finish();
  stats.messages_out = out->messages_written();
  if (progress) progress(1.0);
  return stats;
}

}  // namespace

DynamicFilterConfig filter_config(const FilterJobOptions& o) {
  if (o.config) return *o.config;
  if (!o.config_path) return DynamicFilterConfig{};
  return as_job([&] { return io::load_filter_config(*o.config_path); });
}

io::RecordingMotion read_scan_motion(const FilterJobOptions& o, io::RecordingReader& in,
                                     const std::atomic<bool>* cancel, const Notice& notice) {
  io::MotionQuery query;
  query.scan_topic = o.scan_topic;
  const DynamicFilterConfig config = filter_config(o);
  query.pose_topic = o.static_sensor ? std::nullopt : std::optional<std::string>(o.odom_topic);
  query.laser_only = !o.static_sensor && o.odom_topic == "none";
  query.laser_only_without_odometry = config.registration.enabled;
  query.pose_tolerance_s = o.odom_tolerance_s;
  query.missing_scan_hint = "; choose one with --scan-topic";
  query.missing_pose_hint =
      "; choose one with --odom-topic, or use --static-sensor for a sensor that does not move";
  query.missing_mount_hint = "; record the sensor mount, or use --static-sensor";
  io::RecordingMotion motion =
      as_job([&] { return io::read_motion(in, query, [&] { check_cancelled(cancel); }); });
  check_period(o, motion.scan_period_s, motion.first_scan);
  if (motion.laser_only) {
    if (!config.registration.enabled) {
      throw JobError(o.input +
                     ": --odom-topic none needs the scan registration (registration.enabled: "
                     "true; the thesis preset has it off)");
    }
    if (notice) {
      notice(o.odom_topic == "none"
                 ? "laser-only (--odom-topic none): each scan registered to the earlier ones"
                 : o.input +
                       " has no nav_msgs/Odometry topic: filtering laser-only, each scan "
                       "registered to the earlier ones");
    }
  }
  return motion;
}

FilterJobStats run_filter_job(const FilterJobOptions& options, const Progress& progress,
                              const std::atomic<bool>* cancel, const Notice& notice) {
  check_input_file(options.input);
  if (options.output.empty()) throw JobError("no output file given (-o OUT.bag)");
  if (options.config_path) filter_config(options);  // Fail on a bad config before any reading.
  if (ends_with(options.input, ".log") || ends_with(options.input, ".clf")) {
    return run_carmen(options, progress, cancel, notice);
  }
  return run_recording(options, progress, cancel, notice);
}

}  // namespace dispel::jobs
