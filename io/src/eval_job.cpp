#include "dispel/io/eval_job.hpp"

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/LaserScan.h>

#include <cmath>
#include <map>

#include "dispel/io/filter_job.hpp"

namespace dispel::io {
namespace {

std::map<ros::Time, sensor_msgs::LaserScan> read_scans(const std::string& path,
                                                       const std::string& topic) {
  std::map<ros::Time, sensor_msgs::LaserScan> scans;
  rosbag::Bag bag;
  try {
    bag.open(path, rosbag::bagmode::Read);
    rosbag::View view(bag, rosbag::TopicQuery(topic));
    for (const rosbag::MessageInstance& m : view) {
      if (const auto s = m.instantiate<sensor_msgs::LaserScan>()) scans[s->header.stamp] = *s;
    }
  } catch (const std::exception& e) {
    throw JobError(path + ": not a readable ROS 1 bag (" + e.what() + ")");
  }
  return scans;
}

}  // namespace

eval::Rates evaluate_bags(const std::string& truth_bag, const std::string& result_bag,
                          const std::string& scan_topic) {
  const auto truth = read_scans(truth_bag, "/scan_truth");
  const auto actors = read_scans(truth_bag, "/scan_truth_actor");
  if (truth.empty()) throw JobError(truth_bag + ": no /scan_truth (is it a bag from dispel sim?)");
  auto result = read_scans(result_bag, scan_topic + "_labels");
  bool from_labels = true;
  if (result.empty()) {
    result = read_scans(result_bag, scan_topic + "_filtered");
    from_labels = false;
  }
  if (result.empty()) {
    throw JobError(result_bag + ": no " + scan_topic + "_labels or " + scan_topic +
                   "_filtered (is it a bag from dispel filter?)");
  }
  eval::BeamEvaluator evaluator;
  std::int64_t paired = 0;
  for (const auto& [stamp, t] : truth) {
    const auto r = result.find(stamp);
    if (r == result.end()) continue;
    const auto a = actors.find(stamp);
    const std::size_t n = t.intensities.size();
    if (r->second.ranges.size() != n) {
      throw JobError(result_bag + ": scan at " + std::to_string(stamp.toSec()) + " has " +
                     std::to_string(r->second.ranges.size()) + " beams, the truth " +
                     std::to_string(n));
    }
    std::vector<std::uint8_t> codes(n);
    std::vector<std::int32_t> ids(n, 0);
    std::vector<bool> removed(n);
    for (std::size_t i = 0; i < n; ++i) {
      codes[i] = static_cast<std::uint8_t>(t.intensities[i]);
      if (a != actors.end() && a->second.intensities.size() == n) {
        ids[i] = static_cast<std::int32_t>(a->second.intensities[i]);
      }
      removed[i] = from_labels
                       ? (r->second.intensities[i] == 1.0F || r->second.intensities[i] == 2.0F)
                       : std::isnan(r->second.ranges[i]) && !std::isnan(t.ranges[i]);
    }
    evaluator.add_scan(stamp.toSec(), codes, ids, removed);
    ++paired;
  }
  if (paired == 0) {
    throw JobError(result_bag + ": no scan has the stamp of a scan in " + truth_bag);
  }
  return evaluator.result();
}

}  // namespace dispel::io
