#include "dispel/jobs/clean_job.hpp"

#include <chrono>
#include <cmath>
#include <limits>

#include "dispel/io/text.hpp"
#include "dispel/pipeline/scan_filter_runner.hpp"

namespace dispel::jobs {
namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

CleanConfig clean_config(const CleanJobOptions& options) {
  CleanConfig c = options.clean;
  c.poses_exact = options.filter.static_sensor;
  if (c.through_min_scans == kThroughScansBySensor) {
    c.through_min_scans = options.filter.static_sensor ? kStaticSensorThroughScans : 0;
  }
  return c;
}

CleanJobStats run_clean_job(const CleanJobOptions& options, const Progress& progress,
                            const std::atomic<bool>* cancel, const Notice& notice) {
  const FilterJobOptions& o = options.filter;
  check_input_file(o.input);
  if (o.output.empty()) throw JobError("no output file given (-o OUT.bag)");
  if (io::ends_with(o.input, ".log") || io::ends_with(o.input, ".clf")) {
    throw JobError(o.input +
                   ": dispel clean reads bags, rosbag2 recordings and MRPT rawlogs; write the "
                   "CARMEN log as a bag with dispel filter first");
  }
  const DynamicFilterConfig config = filter_config(o);
  CleanJobStats stats;
  stats.config = clean_config(options);
  OfflineCleaner cleaner = as_job([&] { return OfflineCleaner(stats.config); });
  const std::unique_ptr<io::RecordingReader> in = open_recording(o.input);
  stats.input_format = in->format_name();
  const io::Topics& topics = in->topics();
  const std::string clean_topic = o.scan_topic + "_clean";
  const std::string labels_topic = o.scan_topic + "_clean_labels";
  if (topics.has(clean_topic) || topics.has(labels_topic)) {
    throw JobError(o.input + ": already has " + clean_topic + " or " + labels_topic +
                   "; clean the original recording");
  }
  const io::RecordingMotion motion = read_scan_motion(o, *in, cancel, notice);
  stats.laser_only = motion.laser_only;

  // Pass 1: the online filter over every scan; the cleaner remembers what it found.
  const auto first_start = std::chrono::steady_clock::now();
  pipeline::ScanFilterRunner runner({config, o.scale_to_scanner, 0.0, o.static_sensor});
  as_job([&] {
    in->read({o.scan_topic}, [&](const io::RecordedMessage& m) {
      const std::optional<io::ScanMessage> scan = m.scan();
      if (!scan) return;
      if (stats.scans % 64 == 0) {
        check_cancelled(cancel);
        if (progress && motion.scans > 0) {
          progress(0.5 * static_cast<double>(stats.scans) / static_cast<double>(motion.scans));
        }
      }
      const FilterResult& result =
          runner.process(scan->scan, scan->scan_time, motion.sensor_pose(scan->scan.stamp_s));
      cleaner.add(scan->scan, result);
      ++stats.scans;
    });
  });
  cleaner.finish();
  stats.online = runner.filter_counters();
  stats.first_pass_s = seconds_since(first_start);

  // Pass 2: every message as it was, each scan's cleaned copy and its labels.
  const auto second_start = std::chrono::steady_clock::now();
  const std::unique_ptr<io::RecordingWriter> out =
      create_recording(o.output, o.compression, o.format);
  std::size_t index = 0;
  std::vector<CleanLabel> labels;
  const Progress second_half = [&](double f) {
    if (progress) progress(0.5 + 0.5 * f);
  };
  as_job([&] {
    copy_recording(*in, *out, stats.left_out, stats.messages_in, cancel, second_half,
                   [&](const io::RecordedMessage& m) {
                     if (m.topic() != o.scan_topic) return;
                     const std::optional<io::ScanMessage> scan = m.scan();
                     if (!scan) return;
                     if (index >= cleaner.scans()) {
                       throw JobError(o.input + ": more scans on " + o.scan_topic +
                                      " in the second pass than in the first");
                     }
                     cleaner.label(index++, scan->scan, labels);
                     io::ScanMessage cleaned = *scan;
                     io::ScanMessage labelled = *scan;
                     labelled.scan.intensities.assign(labels.size(), 0.0F);
                     for (std::size_t b = 0; b < labels.size(); ++b) {
                       if (removed(labels[b])) {
                         cleaned.scan.ranges_m[b] = std::numeric_limits<float>::quiet_NaN();
                       }
                       labelled.scan.intensities[b] = static_cast<float>(labels[b]);
                     }
                     out->write(clean_topic, m.time(), cleaned);
                     out->write(labels_topic, m.time(), labelled);
                   });
    out->finish();
  });
  stats.messages_out = out->messages_written();
  stats.counts = cleaner.counts();
  stats.objects = cleaner.objects();
  stats.second_pass_s = seconds_since(second_start);
  if (progress) progress(1.0);
  return stats;
}

}  // namespace dispel::jobs
