#include "filter_command.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>

#include "cli_common.hpp"
#include "dispel/core/percentile.hpp"
#include "dispel/io/atomic_file.hpp"
#include "dispel/pipeline/resident_heap.hpp"

namespace dispel::apps {
namespace {

nlohmann::ordered_json stats_json(const jobs::FilterJobOptions& o, const jobs::FilterJobStats& s,
                                  const pipeline::ResidentHeap& heap) {
  nlohmann::ordered_json j;
  j["input"] = o.input;
  j["output"] = o.output;
  j["format"] = s.input_format;
  j["messages_in"] = s.messages_in;
  j["messages_out"] = s.messages_out;
  j["messages_left_out"] = s.left_out;
  nlohmann::ordered_json skipped = nlohmann::ordered_json::object();
  std::int64_t skipped_total = 0;
  for (const auto& [reason, n] : s.scans_skipped) {
    skipped[reason] = n;
    skipped_total += n;
  }
  j["scans"] = {{"total", s.scans},         {"processed", s.scans_filtered},
                {"skipped", skipped_total}, {"skipped_by_reason", skipped},
                {"reset", s.scans_reset},   {"mostly_unfiltered", s.mostly_unfiltered}};
  nlohmann::ordered_json events;
  for (std::size_t e = 0; e < kFilterEventCount; ++e) {
    events[filter_event_name(static_cast<FilterEvent>(e))] = s.counters.events[e];
  }
  j["events"] = events;
  j["beams_removed"] = {{"dynamic", s.counters.beams_removed_dynamic},
                        {"unknown", s.counters.beams_removed_unknown},
                        {"fragments", s.counters.beams_removed_fragments},
                        {"edge_pixels", s.counters.beams_removed_edge_pixels}};
  j["beams_kept_long_occupied"] = s.counters.beams_kept_long_occupied;
  j["free_space_refuted"] = s.counters.free_space_refuted;
  j["free_space_held"] = s.counters.free_space_held;
  j["free_space_seen_before"] = s.counters.free_space_seen_before;
  j["still_alone_to_static"] = s.counters.still_alone_to_static;
  j["fragment_follows"] = s.counters.fragment_follows;
  j["fragments_let_go"] = s.counters.fragments_let_go;
  j["laser_only"] = s.laser_only;
  j["beams_kept_explained"] = s.counters.beams_kept_explained;
  j["registration"] = {{"enabled", s.config.registration.enabled},
                       {"align", s.config.registration.align},
                       {"registered", s.counters.scans_registered},
                       {"fallbacks", s.counters.registration_fallbacks},
                       {"degenerate", s.counters.registration_degenerate},
                       {"without_odometry", s.counters.scans_without_odometry},
                       {"odometry_overruled", s.counters.odometry_overruled},
                       {"realigned", s.counters.scans_realigned},
                       {"guess_limited", s.counters.registration_guess_limited},
                       {"held_sideways", s.counters.registration_held_sideways},
                       {"voxels_restarted", s.counters.map_voxels_restarted},
                       {"residual_m",
                        {{"median", percentile(s.registration_residual_m, 0.5)},
                         {"p99", percentile(s.registration_residual_m, 0.99)}}},
                       {"inlier_share",
                        {{"median", percentile(s.registration_inlier_share, 0.5)},
                         {"p01", percentile(s.registration_inlier_share, 0.01)}}},
                       {"degeneracy",
                        {{"median", percentile(s.registration_degeneracy, 0.5)},
                         {"p01", percentile(s.registration_degeneracy, 0.01)}}}};
  j["tracks_created"] = s.counters.tracks_created;
  j["tracks_dropped"] = s.counters.tracks_dropped;
  const auto times_us = [](const std::vector<double>& t) {
    return nlohmann::ordered_json{{"median", percentile(t, 0.5) * 1e6},
                                  {"p99", percentile(t, 0.99) * 1e6},
                                  {"p99_9", percentile(t, 0.999) * 1e6},
                                  {"max", percentile(t, 1.0) * 1e6}};
  };
  j["scan_time_us"] = times_us(s.scan_time_s);
  j["scan_cpu_time_us"] = times_us(s.scan_cpu_time_s);
  j["resident_heap_bytes"] = heap.bytes;  // 0: none made resident (or a sanitizer's allocator).
  nlohmann::ordered_json slowest = nlohmann::ordered_json::array();
  for (const jobs::SlowScan& slow : s.slowest_scans) {
    slowest.push_back({{"index", slow.index},
                       {"stamp_s", slow.stamp_s},
                       {"time_us", slow.time_s * 1e6},
                       {"cpu_time_us", slow.cpu_time_s * 1e6},
                       {"event", filter_event_name(slow.event)},
                       {"beams", slow.work.beams},
                       {"objects", slow.work.objects},
                       {"tracks", slow.work.tracks},
                       {"registration_points", slow.work.registration_points},
                       {"registration_iterations", slow.work.registration_iterations},
                       {"registration_alignments", slow.work.registration_alignments},
                       {"registration_total_iterations", slow.work.registration_total_iterations},
                       {"registration_us", slow.work.registration_us},
                       {"free_space_us", slow.work.free_space_us},
                       {"map_voxels", slow.work.map_voxels},
                       {"free_space_tiles_started", slow.work.free_space_tiles_started}});
  }
  j["slowest_scans"] = slowest;
  j["config"] = {
      {"min_points", s.config.segmentation.min_points},
      {"cluster_gap_m", s.config.segmentation.cluster_gap_m},
      {"cluster_gap_spacings", s.config.segmentation.cluster_gap_spacings},
      {"min_width_m", s.config.segmentation.min_width_m},
      {"presumption",
       s.config.classification.presumption == Presumption::kGuilt ? "guilt" : "innocence"},
      {"dynamic_weight_limit", s.config.classification.dynamic_weight_limit},
      {"static_weight_limit", s.config.classification.static_weight_limit},
      {"matching",
       s.config.tracking.matching == Matching::kGlobal ? "global" : "nearest_neighbour"}};
  // The scanner's period --scale-to-scanner carried the counts over with (null when not needed).
  j["scan_period_s"] =
      s.scan_period_s ? nlohmann::ordered_json(*s.scan_period_s) : nlohmann::ordered_json(nullptr);
  if (s.input_format == "carmen") {
    j["malformed_lines"] = s.malformed_lines;
    j["stamp_offset_s"] = s.stamp_offset_s;
  }
  j["odometry_refused"] = s.odometry_refused;
  return j;
}

nlohmann::ordered_json clean_stats_json(const jobs::CleanJobOptions& o,
                                        const jobs::CleanJobStats& s) {
  nlohmann::ordered_json j;
  j["input"] = o.filter.input;
  j["output"] = o.filter.output;
  j["format"] = s.input_format;
  j["laser_only"] = s.laser_only;
  j["messages_in"] = s.messages_in;
  j["messages_out"] = s.messages_out;
  j["messages_left_out"] = s.left_out;
  const CleanCounts& c = s.counts;
  j["scans"] = {{"total", s.scans}, {"with_pose", c.scans_with_pose}};
  j["valid_beams"] = c.valid_beams;
  j["beams_removed"] = {{"online", c.removed_online},
                        {"moved_later", c.moved_later},
                        {"vacated", c.vacated},
                        {"walked_legs", c.walked_legs},
                        {"total", c.removed()}};
  j["beams_restored"] = c.restored;
  j["online_beams_removed"] = {{"dynamic", s.online.beams_removed_dynamic},
                               {"unknown", s.online.beams_removed_unknown}};
  j["first_pass_s"] = s.first_pass_s;
  j["second_pass_s"] = s.second_pass_s;
  j["config"] = {{"moving_min_scans", s.config.moving_min_scans},
                 {"moving_min_travel_m", s.config.moving_min_travel_m},
                 {"moved_from_m", s.config.moved_from_m},
                 {"max_width_m", s.config.max_width_m},
                 {"through_min_scans", s.config.through_min_scans},
                 {"through_gap_s", s.config.through_gap_s},
                 {"through_horizon_s", s.config.through_horizon_s},
                 {"poses_exact", s.config.poses_exact},
                 {"free_margin_m", s.config.free_margin_m},
                 {"max_range_m", s.config.max_range_m},
                 {"leg_walk_m", s.config.leg_walk_m},
                 {"leg_max_gap_s", s.config.leg_max_gap_s}};
  nlohmann::ordered_json objects = nlohmann::ordered_json::array();
  for (const CleanedObject& x : s.objects) {
    if (x.dynamic_scans == 0 && x.beams_removed == 0) continue;  // Static throughout.
    objects.push_back({{"track", x.track_id},
                       {"first_seen_s", x.first_seen_s},
                       {"last_seen_s", x.last_seen_s},
                       {"scans", x.scans},
                       {"dynamic_scans", x.dynamic_scans},
                       {"first_dynamic_s", x.first_dynamic_s},
                       {"last_dynamic_s", x.last_dynamic_s},
                       {"travel_m", x.travel_m},
                       {"dynamic_travel_m", x.dynamic_travel_m},
                       {"moving", x.moving},
                       {"walking_scans", x.walking_scans},
                       {"beams", x.beams},
                       {"beams_removed", x.beams_removed}});
  }
  j["objects"] = objects;
  return j;
}

// A bar on stderr, redrawn only when the whole percent changes.
class ProgressBar {
 public:
  void operator()(double fraction) {
    const int percent = static_cast<int>(fraction * 100.0);
    if (percent == last_) return;
    last_ = percent;
    const int filled = percent / 4;
    std::fprintf(stderr, "\r[%-25s] %3d%%",
                 std::string(static_cast<std::size_t>(filled), '#').c_str(), percent);
    std::fflush(stderr);
  }
  void finish() const {
    if (last_ >= 0) std::fprintf(stderr, "\n");
  }

 private:
  int last_ = -1;
};

// Runs @p job (given the progress callback and the Ctrl-C flag) with a bar on a terminal; an
// error or an interruption is printed as "dispel <command>: ...". Returns the exit code: 0 when
// the job ran, 1 on an error, 130 when interrupted (nothing written at @p output then).
template <typename Job>
int run_with_progress(const char* command, const std::string& output, Job&& job) {
  const Interrupts interrupts;
  ProgressBar bar;
  jobs::Progress progress;
  if (::isatty(STDERR_FILENO) != 0) progress = [&bar](double f) { bar(f); };
  try {
    job(progress, interrupts.flag());
  } catch (const jobs::JobCancelled&) {
    bar.finish();
    std::cerr << "dispel " << command << ": interrupted; " << error_line(output)
              << " was not written\n";
    return 130;
  } catch (const std::exception& e) {
    bar.finish();
    std::cerr << "dispel " << command << ": " << error_line(e.what()) << "\n";
    return 1;
  }
  bar.finish();
  return 0;
}

}  // namespace

int run_filter(FilterCommandOptions options) {
  options.job.compression = compression_named(options.compression);
  // Before the job's threads start, so that they allocate from the heap made resident.
  const pipeline::ResidentHeap heap =
      pipeline::reserve_resident_heap(static_cast<std::size_t>(options.resident_heap_mb) << 20);
  jobs::FilterJobStats stats;
  const int code = run_with_progress(
      "filter", options.job.output,
      [&](const jobs::Progress& progress, const std::atomic<bool>* cancel) {
        stats = jobs::run_filter_job(options.job, progress, cancel, [](const std::string& n) {
          std::cerr << "dispel filter: " << error_line(n) << "\n";
        });
      });
  if (code != 0) return code;

  std::int64_t skipped = 0;
  for (const auto& [reason, n] : stats.scans_skipped) skipped += n;
  std::printf(
      "dispel filter: %lld scans (%lld passed through unchanged), %lld dynamic and %lld unknown "
      "beams removed, %lld tracks; %.1f us per scan (median), %.1f us (p99), %.1f us (max)\n"
      "wrote %s: %lld messages\n",
      static_cast<long long>(stats.scans), static_cast<long long>(skipped),
      static_cast<long long>(stats.counters.beams_removed_dynamic),
      static_cast<long long>(stats.counters.beams_removed_unknown),
      static_cast<long long>(stats.counters.tracks_created),
      percentile(stats.scan_time_s, 0.5) * 1e6, percentile(stats.scan_time_s, 0.99) * 1e6,
      percentile(stats.scan_time_s, 1.0) * 1e6, options.job.output.c_str(),
      static_cast<long long>(stats.messages_out));
  for (const auto& [reason, n] : stats.scans_skipped) {
    std::printf("  passed through: %lld scans, %s\n", static_cast<long long>(n), reason.c_str());
  }
  std::fflush(stdout);
  if (!stats.warning.empty()) std::cerr << "dispel filter: warning: " << stats.warning << "\n";
  if (!stats.left_out.empty()) {
    std::cerr << "dispel filter: warning: " << jobs::left_out_summary(stats.left_out) << "\n";
  }

  if (!options.stats_path.empty()) {
    try {
      io::write_file_atomically(options.stats_path,
                                stats_json(options.job, stats, heap).dump(2) + "\n");
    } catch (const std::exception& e) {
      std::cerr << "dispel filter: statistics not written: " << error_line(e.what()) << " ("
                << options.job.output << " was written)\n";
      return 1;
    }
  }
  return 0;
}

int run_clean(CleanCommandOptions options) {
  options.job.filter.compression = compression_named(options.compression);
  jobs::CleanJobStats stats;
  const int code = run_with_progress(
      "clean", options.job.filter.output,
      [&](const jobs::Progress& progress, const std::atomic<bool>* cancel) {
        stats = jobs::run_clean_job(options.job, progress, cancel, [](const std::string& n) {
          std::cerr << "dispel clean: " << error_line(n) << "\n";
        });
      });
  if (code != 0) return code;
  const CleanCounts& c = stats.counts;
  std::int64_t moving = 0;
  for (const CleanedObject& x : stats.objects) moving += x.moving ? 1 : 0;
  std::printf(
      "dispel clean: %lld scans, %lld valid beams; removed %lld (online %lld, moved at another "
      "time %lld, left later %lld, walked legs %lld), %lld restored; %lld of %zu objects moved; "
      "%.2f s + %.2f s\n"
      "wrote %s: %lld messages\n",
      static_cast<long long>(stats.scans), static_cast<long long>(c.valid_beams),
      static_cast<long long>(c.removed()), static_cast<long long>(c.removed_online),
      static_cast<long long>(c.moved_later), static_cast<long long>(c.vacated),
      static_cast<long long>(c.walked_legs), static_cast<long long>(c.restored),
      static_cast<long long>(moving), stats.objects.size(), stats.first_pass_s, stats.second_pass_s,
      options.job.filter.output.c_str(), static_cast<long long>(stats.messages_out));
  std::fflush(stdout);
  if (!stats.left_out.empty()) {
    std::cerr << "dispel clean: warning: " << jobs::left_out_summary(stats.left_out) << "\n";
  }
  if (!options.stats_path.empty()) {
    try {
      io::write_file_atomically(options.stats_path,
                                clean_stats_json(options.job, stats).dump(2) + "\n");
    } catch (const std::exception& e) {
      std::cerr << "dispel clean: statistics not written: " << error_line(e.what()) << " ("
                << options.job.filter.output << " was written)\n";
      return 1;
    }
  }
  return 0;
}

jobs::Compression compression_named(const std::string& name) {
  if (name == "bz2") return jobs::Compression::kBz2;
  if (name == "lz4") return jobs::Compression::kLz4;
  if (name == "zstd") return jobs::Compression::kZstd;
  return jobs::Compression::kNone;
}

int run_convert(const jobs::ConvertJobOptions& options) {
  jobs::ConvertJobStats stats;
  const int code =
      run_with_progress("convert", options.output,
                        [&](const jobs::Progress& progress, const std::atomic<bool>* cancel) {
                          stats = jobs::run_convert_job(options, progress, cancel);
                        });
  if (code != 0) return code;
  std::printf("dispel convert: %lld messages of a %s recording\nwrote %s: %lld messages\n",
              static_cast<long long>(stats.messages_in), stats.input_format.c_str(),
              options.output.c_str(), static_cast<long long>(stats.messages_out));
  std::fflush(stdout);
  if (!stats.left_out.empty()) {
    std::cerr << "dispel convert: warning: " << jobs::left_out_summary(stats.left_out) << "\n";
  }
  return 0;
}

}  // namespace dispel::apps
