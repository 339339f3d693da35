#include "dispel/jobs/eval_job.hpp"

#include <cmath>
#include <map>
#include <optional>
#include <stdexcept>

#include "dispel/core/offline_cleaner.hpp"
#include "dispel/io/recording_motion.hpp"

namespace dispel::jobs {
namespace {

// The scans of each topic by their header's stamp.
std::map<std::string, std::map<io::Stamp, io::ScanMessage>> read_scans(
    const std::string& path, const std::vector<std::string>& topics) {
  std::map<std::string, std::map<io::Stamp, io::ScanMessage>> scans;
  const std::unique_ptr<io::RecordingReader> in = open_recording(path);
  as_job([&] {
    in->read(topics, [&](const io::RecordedMessage& m) {
      if (auto s = m.scan()) scans[m.topic()][s->header.stamp] = std::move(*s);
    });
  });
  return scans;
}

// The three maps of MapQuality.
struct Grids {
  eval::OccupancyGrid oracle, result, raw;
  std::int64_t scans = 0;
};

// One scan into the maps, each return from the true sensor pose at its beam's time. A scan
// without a true pose at its first or last beam (before the first pose, after the last, in a
// gap) is left out of all three.
void draw_scan(const LaserScan& scan, const std::vector<std::uint8_t>& codes,
               const std::vector<bool>& removed, const io::RecordingMotion& motion, Grids& grids) {
  const std::size_t n = scan.ranges_m.size();
  if (n == 0) return;
  const std::optional<Pose2> first = motion.sensor_pose(scan.stamp_s);
  const double last_s = scan.stamp_s + scan.time_increment_s * static_cast<double>(n - 1);
  if (!first || !motion.sensor_pose(last_s)) return;
  ++grids.scans;
  for (std::size_t i = 0; i < n; ++i) {
    const float r = scan.ranges_m[i];
    // A beam without a return (the truth's code, +Inf, or at the range limit) clears the cells up
    // to the range limit; a NaN beam (no measurement, e.g. one removed) changes nothing: REP 117.
    const bool no_return = codes[i] == eval::kTruthNoReturn || std::isinf(r) ||
                           (std::isfinite(r) && r >= scan.range_max_m);
    if (no_return ? !std::isfinite(scan.range_max_m) : !(r >= scan.range_min_m)) continue;
    const double beam_s = scan.stamp_s + scan.time_increment_s * static_cast<double>(i);
    const std::optional<Pose2> pose =
        scan.time_increment_s != 0.0 ? motion.sensor_pose(beam_s) : first;
    if (!pose) continue;
    const double bearing = scan.angle_min_rad + scan.angle_increment_rad * static_cast<double>(i);
    const double range = no_return ? static_cast<double>(scan.range_max_m) : static_cast<double>(r);
    const Eigen::Vector2d from = pose->translation();
    const Eigen::Vector2d to = pose->apply({range * std::cos(bearing), range * std::sin(bearing)});
    if (no_return) {
      grids.raw.add_no_return(from, to);
      grids.result.add_no_return(from, to);
      grids.oracle.add_no_return(from, to);
      continue;
    }
    grids.raw.add_return(from, to);
    if (!removed[i]) grids.result.add_return(from, to);
    if (codes[i] == eval::kTruthStatic) grids.oracle.add_return(from, to);
  }
}

}  // namespace

Evaluation evaluate_recordings(const std::string& truth_bag, const std::string& result_bag,
                               const std::string& scan_topic,
                               const std::optional<eval::OccupancyGridConfig>& map) {
  std::optional<Grids> grids;
  std::optional<io::RecordingMotion> motion;
  if (map) {
    try {
      grids.emplace(
          Grids{eval::OccupancyGrid(*map), eval::OccupancyGrid(*map), eval::OccupancyGrid(*map)});
    } catch (const std::invalid_argument& e) {
      throw JobError(e.what());
    }
    const std::unique_ptr<io::RecordingReader> in = open_recording(truth_bag);
    io::MotionQuery query;
    query.scan_topic = "/scan";
    query.pose_topic = "/ground_truth";
    query.default_fixed_frame = "map";
    query.missing_pose_hint = " (the map quality needs the true poses of dispel sim)";
    motion = as_job([&] { return io::read_motion(*in, query); });
  }
  auto truth_scans = read_scans(truth_bag, {"/scan_truth", "/scan_truth_actor"});
  const auto& truth = truth_scans["/scan_truth"];
  const auto& actors = truth_scans["/scan_truth_actor"];
  if (truth.empty()) throw JobError(truth_bag + ": no /scan_truth (is it a bag from dispel sim?)");
  auto result_scans = read_scans(result_bag, {scan_topic + "_labels", scan_topic + "_filtered"});
  bool from_labels = true;
  const std::map<io::Stamp, io::ScanMessage>* result = &result_scans[scan_topic + "_labels"];
  if (result->empty()) {
    result = &result_scans[scan_topic + "_filtered"];
    from_labels = false;
  }
  if (result->empty()) {
    throw JobError(result_bag + ": no " + scan_topic + "_labels or " + scan_topic +
                   "_filtered (is it a bag from dispel filter?)");
  }
  eval::BeamEvaluator evaluator;
  std::int64_t paired = 0;
  for (const auto& [stamp, t] : truth) {
    const auto r = result->find(stamp);
    if (r == result->end()) continue;
    const auto a = actors.find(stamp);
    const std::size_t n = t.scan.intensities.size();
    const LaserScan& rs = r->second.scan;
    if (rs.ranges_m.size() != n) {
      throw JobError(result_bag + ": scan at " + std::to_string(stamp.seconds()) + " has " +
                     std::to_string(rs.ranges_m.size()) + " beams, the truth " + std::to_string(n));
    }
    std::vector<std::uint8_t> codes(n);
    std::vector<std::int32_t> ids(n, 0);
    std::vector<bool> removed(n);
    for (std::size_t i = 0; i < n; ++i) {
      codes[i] = static_cast<std::uint8_t>(t.scan.intensities[i]);
      if (a != actors.end() && a->second.scan.intensities.size() == n) {
        ids[i] = static_cast<std::int32_t>(a->second.scan.intensities[i]);
      }
      // Labels: BeamLabel (dispel filter) or CleanLabel (dispel clean), whose removed values
      // include BeamLabel's (1 dynamic, 2 unknown).
      if (from_labels) {
        const std::optional<CleanLabel> label =
            rs.intensities.size() == n ? clean_label(rs.intensities[i]) : std::nullopt;
        removed[i] = label && dispel::removed(*label);
      } else {
        removed[i] = std::isnan(rs.ranges_m[i]) && !std::isnan(t.scan.ranges_m[i]);
      }
    }
    evaluator.add_scan(stamp.seconds(), codes, ids, removed);
    if (grids) draw_scan(t.scan, codes, removed, *motion, *grids);
    ++paired;
  }
  if (paired == 0) {
    throw JobError(result_bag + ": no scan has the stamp of a scan in " + truth_bag);
  }
  Evaluation out;
  out.rates = evaluator.result();
  if (grids) {
    if (grids->scans == 0) throw JobError(truth_bag + ": no scan has a true pose");
    out.map =
        MapQuality{eval::compare_maps(grids->oracle, grids->result),
                   eval::compare_maps(grids->oracle, grids->raw), map->resolution_m, grids->scans};
  }
  return out;
}

eval::Rates evaluate_bags(const std::string& truth_bag, const std::string& result_bag,
                          const std::string& scan_topic) {
  return evaluate_recordings(truth_bag, result_bag, scan_topic, std::nullopt).rates;
}

}  // namespace dispel::jobs
