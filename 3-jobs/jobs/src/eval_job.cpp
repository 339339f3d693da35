#include "dispel/jobs/eval_job.hpp"

#include <cmath>
#include <map>

#include "dispel/core/offline_cleaner.hpp"

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

}  // namespace

eval::Rates evaluate_bags(const std::string& truth_bag, const std::string& result_bag,
                          const std::string& scan_topic) {
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
      removed[i] = from_labels ? (rs.intensities.size() == n && rs.intensities[i] >= 0.0F &&
                                  rs.intensities[i] <= 7.0F &&
                                  dispel::removed(static_cast<CleanLabel>(
                                      static_cast<std::uint8_t>(rs.intensities[i]))))
                               : std::isnan(rs.ranges_m[i]) && !std::isnan(t.scan.ranges_m[i]);
    }
    evaluator.add_scan(stamp.seconds(), codes, ids, removed);
    ++paired;
  }
  if (paired == 0) {
    throw JobError(result_bag + ": no scan has the stamp of a scan in " + truth_bag);
  }
  return evaluator.result();
}

}  // namespace dispel::jobs
