#include "dispel/io/filter_job.hpp"

#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/LaserScan.h>
#include <sys/stat.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>

#include "dispel/core/pose_buffer.hpp"
#include "dispel/io/atomic_file.hpp"
#include "dispel/io/bag_topics.hpp"
#include "dispel/io/carmen.hpp"
#include "dispel/io/config_yaml.hpp"
#include "dispel/io/frame_tree.hpp"
#include "dispel/io/ros_convert.hpp"

namespace dispel::io {
namespace {

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

void check_input_file(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    throw JobError(path + ": " + std::strerror(errno));
  }
  if (!S_ISREG(st.st_mode)) throw JobError(path + ": not a regular file");
}

void check_not_cancelled(const std::atomic<bool>* cancel) {
  if (cancel != nullptr && cancel->load()) throw JobCancelled();
}

rosbag::compression::CompressionType bag_compression(Compression c) {
  switch (c) {
    case Compression::kBz2:
      return rosbag::compression::BZ2;
    case Compression::kLz4:
      return rosbag::compression::LZ4;
    case Compression::kNone:
      break;
  }
  return rosbag::compression::Uncompressed;
}

DynamicFilterConfig base_config(const FilterJobOptions& o) {
  if (o.config) return *o.config;
  if (!o.config_path) return default_config();
  try {
    return load_filter_config(*o.config_path);
  } catch (const ConfigError& e) {
    throw JobError(e.what());
  }
}

// Median time between consecutive stamps (the scan period), or 0 if unknown.
double median_period(std::vector<double> stamps) {
  std::vector<double> d;
  for (std::size_t i = 1; i < stamps.size(); ++i) {
    if (stamps[i] > stamps[i - 1]) d.push_back(stamps[i] - stamps[i - 1]);
  }
  if (d.empty()) return 0.0;
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return d[d.size() / 2];
}

DynamicFilterConfig final_config(const FilterJobOptions& o, const LaserScan& first,
                                 const std::vector<double>& stamps) {
  DynamicFilterConfig config = base_config(o);
  if (o.scale_to_scanner) {
    const double period = median_period(stamps);
    if (!(period > 0.0) || !(first.angle_increment_rad > 0.0)) {
      throw JobError(o.input +
                     ": --scale-to-scanner needs scans with a positive angle increment and "
                     "increasing stamps");
    }
    config = scale_to_scanner(config, first.angle_increment_rad, period);
  }
  return config;
}

// Runs the filter on one scan and keeps the bookkeeping.
class ScanProcessor {
 public:
  ScanProcessor(const DynamicFilterConfig& config, FilterJobStats& stats)
      : filter_(config), stats_(stats) {}

  // A pose, or nullopt with the reason the scan is passed through.
  const FilterResult& process(const LaserScan& scan, const std::optional<Pose2>& pose,
                              const std::string& no_pose_reason) {
    ++stats_.scans;
    const auto start = std::chrono::steady_clock::now();
    const Pose2 p = pose ? *pose : Pose2{std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0};
    filter_.process(scan, p, result_);
    stats_.scan_time_s.push_back(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    if (result_.event == FilterEvent::kRejectedScan) {
      ++stats_
            .scans_skipped[std::string("bad_scan_") + scan_issue_name(result_.segmentation.issue)];
    } else if (result_.event == FilterEvent::kRejectedPose) {
      ++stats_.scans_skipped[pose ? "bad_pose" : no_pose_reason];
    } else {
      ++stats_.scans_filtered;
    }
    stats_.counters = filter_.counters();
    return result_;
  }

 private:
  DynamicFilter filter_;
  FilterResult result_;
  FilterJobStats& stats_;
};

void open_output(rosbag::Bag& out, const AtomicFile& file, const FilterJobOptions& o) {
  try {
    out.open(file.temp_path(), rosbag::bagmode::Write);
  } catch (const std::exception& e) {
    throw JobError(o.output + ": cannot write (" + e.what() + ")");
  }
  out.setCompression(bag_compression(o.compression));
}

// The two messages that follow each scan in the output.
void write_filter_outputs(rosbag::Bag& out, const std::string& scan_topic, const ros::Time& time,
                          const sensor_msgs::LaserScan& scan, const FilterResult& result) {
  out.write(scan_topic + "_filtered", time, filtered_message(scan, result));
  out.write(scan_topic + "_labels", time, labels_message(scan, result));
}

// ------------------------------------------------------------------------------------------
// ROS 1 bags.

FilterJobStats run_bag(const FilterJobOptions& o, const Progress& progress,
                       const std::atomic<bool>* cancel) {
  FilterJobStats stats;
  stats.input_format = "rosbag";
  rosbag::Bag in;
  open_bag_for_reading(in, o.input);
  const BagTopics topics(in);
  if (!topics.has(o.scan_topic, "sensor_msgs/LaserScan")) {
    throw JobError(o.input + ": no sensor_msgs/LaserScan topic " + o.scan_topic +
                   " (LaserScan topics: " + topics.list("sensor_msgs/LaserScan") +
                   "); choose one with --scan-topic");
  }
  const std::string filtered_topic = o.scan_topic + "_filtered";
  const std::string labels_topic = o.scan_topic + "_labels";
  if (topics.has(filtered_topic) || topics.has(labels_topic)) {
    throw JobError(o.input + ": already has " + filtered_topic + " or " + labels_topic +
                   "; filter the original recording");
  }
  if (!o.static_sensor) {
    if (!topics.has(o.odom_topic, "nav_msgs/Odometry")) {
      throw JobError(o.input + ": no nav_msgs/Odometry topic " + o.odom_topic +
                     " (Odometry topics: " + topics.list("nav_msgs/Odometry") +
                     "); choose one with --odom-topic, or use --static-sensor for a sensor that "
                     "does not move");
    }
  }

  PoseBuffer odometry(o.odom_tolerance_s, 0.5);
  FrameTree mounts;
  std::string base_frame = "base_link";
  std::string odom_frame = "odom";
  std::string laser_frame;
  LaserScan first_scan;
  std::vector<double> first_stamps;
  std::int64_t refused_odometry = 0;
  try {
    // First pass: odometry, the sensor mount, and a look at the scanner.
    std::vector<std::string> wanted{o.scan_topic, "/tf", "/tf_static"};
    if (!o.static_sensor) wanted.push_back(o.odom_topic);
    rosbag::View view(in, rosbag::TopicQuery(wanted));
    bool have_odom_frames = false;
    for (const rosbag::MessageInstance& m : view) {
      check_not_cancelled(cancel);
      if (m.getTopic() == o.scan_topic) {
        if (first_stamps.size() >= 200) continue;
        const auto scan = m.instantiate<sensor_msgs::LaserScan>();
        if (!scan) continue;
        if (first_stamps.empty()) {
          first_scan = from_ros(*scan);
          laser_frame = scan->header.frame_id;
        }
        first_stamps.push_back(to_seconds(scan->header.stamp));
      } else if (m.getTopic() == o.odom_topic && !o.static_sensor) {
        const auto odom = m.instantiate<nav_msgs::Odometry>();
        if (!odom) continue;
        if (!have_odom_frames) {
          if (!odom->child_frame_id.empty())
            base_frame = FrameTree::normalise(odom->child_frame_id);
          if (!odom->header.frame_id.empty())
            odom_frame = FrameTree::normalise(odom->header.frame_id);
          have_odom_frames = true;
        }
        if (!odometry.add(to_seconds(odom->header.stamp), from_ros(odom->pose.pose))) {
          ++refused_odometry;
        }
      } else {
        const auto tf = m.instantiate<tf2_msgs::TFMessage>();
        if (!tf) continue;
        for (const auto& t : tf->transforms) {
          const std::string parent = FrameTree::normalise(t.header.frame_id);
          const std::string child = FrameTree::normalise(t.child_frame_id);
          // Only fixed mounts: not the robot's motion in odom or map.
          if (parent == odom_frame || child == odom_frame || parent == "map" || child == "map") {
            continue;
          }
          mounts.set(parent, child, from_ros(t.transform));
        }
      }
    }
  } catch (...) {
    rethrow_as_recording_error(o.input);
  }
  if (first_stamps.empty()) throw JobError(o.input + ": no scans on " + o.scan_topic);
  if (!o.static_sensor && odometry.empty()) {
    throw JobError(o.input + ": no usable odometry on " + o.odom_topic);
  }
  Pose2 mount;
  if (!o.static_sensor) {
    const auto found = mounts.lookup(base_frame, laser_frame.empty() ? base_frame : laser_frame);
    if (!found) {
      throw JobError(o.input + ": no transform from " + base_frame + " to " + laser_frame +
                     " in /tf_static or /tf; record the sensor mount, or use --static-sensor");
    }
    mount = *found;
  }
  stats.config = final_config(o, first_scan, first_stamps);
  ScanProcessor processor(stats.config, stats);
  stats.odometry_refused = refused_odometry;

  // Second pass: copy everything, and filter the scans.
  AtomicFile output(o.output);
  try {
    rosbag::Bag out;
    open_output(out, output, o);
    rosbag::View all(in);
    const double total = std::max<double>(1.0, static_cast<double>(all.size()));
    for (const rosbag::MessageInstance& m : all) {
      check_not_cancelled(cancel);
      out.write(m.getTopic(), m.getTime(), m, m.getConnectionHeader());
      ++stats.messages_in;
      ++stats.messages_out;
      if (progress && stats.messages_in % 256 == 0)
        progress(static_cast<double>(stats.messages_in) / total);
      if (m.getTopic() != o.scan_topic) continue;
      const auto msg = m.instantiate<sensor_msgs::LaserScan>();
      if (!msg) continue;
      const LaserScan scan = from_ros(*msg);
      std::optional<Pose2> pose;
      std::string reason;
      if (o.static_sensor) {
        pose = Pose2{};
      } else {
        Pose2 base_pose;
        const PoseLookup found = odometry.lookup(scan.stamp_s, base_pose);
        if (found == PoseLookup::kOk) {
          pose = base_pose * mount;
        } else {
          reason = std::string("odometry_") + pose_lookup_name(found);
        }
      }
      const FilterResult& result = processor.process(scan, pose, reason);
      write_filter_outputs(out, o.scan_topic, m.getTime(), *msg, result);
      stats.messages_out += 2;
    }
    out.close();
  } catch (...) {
    rethrow_as_recording_error(o.input);
  }
  if (progress) progress(1.0);
  output.commit();
  return stats;
}

// ------------------------------------------------------------------------------------------
// CARMEN logs.

FilterJobStats run_carmen(const FilterJobOptions& o, const Progress& progress,
                          const std::atomic<bool>* cancel) {
  FilterJobStats stats;
  stats.input_format = "carmen";
  CarmenLog log;
  try {
    log = read_carmen_log(o.input);
  } catch (const std::exception& e) {
    throw JobError(e.what());
  }
  stats.messages_in = log.lines;
  stats.malformed_lines = log.malformed_lines;
  std::vector<double> stamps;
  for (std::size_t i = 0; i < log.scans.size() && i < 200; ++i) {
    stamps.push_back(log.scans[i].scan.stamp_s);
  }
  stats.config = final_config(o, log.scans.front().scan, stamps);
  ScanProcessor processor(stats.config, stats);

  AtomicFile output(o.output);
  try {
    rosbag::Bag out;
    open_output(out, output, o);
    // Odometry and scans in time order; a stamp that is not finite goes at its file position.
    std::size_t next_odom = 0;
    const auto write_odom_until = [&](double t) {
      for (; next_odom < log.odometry.size() && log.odometry[next_odom].stamp_s <= t; ++next_odom) {
        const TimedPose& p = log.odometry[next_odom];
        if (!std::isfinite(p.stamp_s) || p.stamp_s < 0.0) continue;
        const nav_msgs::Odometry msg = to_ros_odometry(p.stamp_s, "odom", "base_link", p.pose);
        out.write("/odom", msg.header.stamp, msg);
        ++stats.messages_out;
      }
    };
    for (std::size_t i = 0; i < log.scans.size(); ++i) {
      check_not_cancelled(cancel);
      const CarmenScan& cs = log.scans[i];
      write_odom_until(cs.scan.stamp_s);
      if (!std::isfinite(cs.scan.stamp_s) || cs.scan.stamp_s < 0.0) {
        ++stats.scans_skipped["bad_stamp"];
        continue;
      }
      const sensor_msgs::LaserScan msg =
          to_ros(cs.scan, cs.kind == "RLASER" ? "rear_laser" : "laser");
      const FilterResult& result =
          processor.process(cs.scan, o.static_sensor ? Pose2{} : cs.laser_pose, "");
      out.write(o.scan_topic, msg.header.stamp, msg);
      write_filter_outputs(out, o.scan_topic, msg.header.stamp, msg, result);
      stats.messages_out += 3;
      if (progress && i % 64 == 0)
        progress(static_cast<double>(i) / static_cast<double>(log.scans.size()));
    }
    write_odom_until(std::numeric_limits<double>::infinity());
    out.close();
  } catch (const JobError&) {
    throw;
  } catch (const JobCancelled&) {
    throw;
  } catch (const std::exception& e) {
    throw JobError(o.output + ": cannot write the bag (" + e.what() + ")");
  }
  if (progress) progress(1.0);
  output.commit();
  return stats;
}

}  // namespace

FilterJobStats run_filter_job(const FilterJobOptions& options, const Progress& progress,
                              const std::atomic<bool>* cancel) {
  check_input_file(options.input);
  if (options.output.empty()) throw JobError("no output file given (-o OUT.bag)");
  if (options.config_path) base_config(options);  // Fail on a bad config before any reading.
  if (ends_with(options.input, ".log") || ends_with(options.input, ".clf")) {
    return run_carmen(options, progress, cancel);
  }
  return run_bag(options, progress, cancel);
}

}  // namespace dispel::io
