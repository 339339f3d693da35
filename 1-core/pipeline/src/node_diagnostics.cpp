#include "dispel/pipeline/node_diagnostics.hpp"

#include <iomanip>
#include <sstream>

namespace dispel::pipeline {
namespace {

std::string fixed(double value, int decimals) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(decimals) << value;
  return out.str();
}
std::string milliseconds(double seconds) { return fixed(seconds * 1e3, 3); }
std::string seconds(double s) { return fixed(s, 4); }

}  // namespace

DiagnosticStatus filter_node_status(const std::string& node_name, ScanFilterRunner& runner,
                                    const FilterNodeTallies& tallies) {
  const ScanTimes times = runner.take_times();
  const ScanFilterCounts& c = runner.counts();
  const FilterCounters f = runner.filter_counters();
  DiagnosticStatus s;
  s.name = node_name + ": dynamic filter";
  s.message =
      std::to_string(times.count) + " scans, " + milliseconds(times.mean_s) + " ms per scan (mean)";
  if (tallies.without_pose_in_period > 0) {
    s.level = DiagnosticStatus::Level::kWarn;
    s.message += "; " + std::to_string(tallies.without_pose_in_period) + " without a sensor pose";
  } else if (times.count == 0) {
    s.message = "no scans";
  }
  s.values = {
      {"scans in period", std::to_string(times.count)},
      {"processing time last (ms)", milliseconds(times.last_s)},
      {"processing time mean (ms)", milliseconds(times.mean_s)},
      {"processing time max (ms)", milliseconds(times.max_s)},
      {"scans", std::to_string(c.scans + tallies.dropped)},
      {"scans filtered", std::to_string(c.filtered)},
      {"scans without a sensor pose", std::to_string(tallies.without_pose)},
      {"scans dropped (no sensor pose)", std::to_string(tallies.dropped)},
      {"scans published unfiltered (no sensor pose)", std::to_string(c.no_pose + c.bad_pose)},
      {"scans published unfiltered (scanner period not known yet)",
       std::to_string(c.waiting_period)},
      {"scans rejected (bad scan)", std::to_string(c.rejected_scan)},
      {"tracks", std::to_string(c.tracks)},
      {"beams removed (dynamic)", std::to_string(f.beams_removed_dynamic)},
      {"beams removed (unknown)", std::to_string(f.beams_removed_unknown)},
      {"min_points", std::to_string(runner.config().segmentation.min_points)},
      {"dynamic_weight_limit", std::to_string(runner.config().classification.dynamic_weight_limit)},
  };
  return s;
}

std::int64_t odometry_refused(const OdometryRunner& runner) {
  const OdometryCounters c = runner.counters();
  return c.count(OdometryEvent::kRejectedNonFinite) + c.count(OdometryEvent::kRejectedOutOfOrder) +
         c.count(OdometryEvent::kNumericalFailure);
}

DiagnosticStatus odometry_node_status(const std::string& node_name, const std::string& model,
                                      const OdometryRunner& runner,
                                      const OdometryNodeTallies& tallies) {
  const OdometryCounters c = runner.counters();
  const auto count = [](const auto& counts, OdometryEvent e) {
    return std::to_string(counts[static_cast<std::size_t>(e)]);
  };
  const OdometryArrivals& aw = runner.arrivals(OdometrySource::kWheels);
  const OdometryArrivals& ai = runner.arrivals(OdometrySource::kImu);
  const auto quiet = [&runner](OdometrySource source) {
    return std::to_string(runner.quiet_count(source));
  };
  DiagnosticStatus s;
  s.name = node_name + ": odometry fusion";
  s.level =
      tallies.refused_in_period ? DiagnosticStatus::Level::kWarn : DiagnosticStatus::Level::kOk;
  s.message = std::to_string(tallies.published) + " estimates published";
  s.values = {
      {"model", model},
      {"estimates published", std::to_string(tallies.published)},
      {"wheels received", std::to_string(aw.count)},
      {"imu received", std::to_string(ai.count)},
      {"wheels accepted", count(c.wheels, OdometryEvent::kAccepted)},
      {"wheels gated", count(c.wheels, OdometryEvent::kGated)},
      {"wheels gate overridden", count(c.wheels, OdometryEvent::kGateOverridden)},
      {"wheels late", count(c.wheels, OdometryEvent::kRejectedOutOfOrder)},
      {"wheels not finite", count(c.wheels, OdometryEvent::kRejectedNonFinite)},
      {"wheel messages without both wheels", std::to_string(tallies.malformed)},
      {"imu accepted", count(c.imu, OdometryEvent::kAccepted)},
      {"imu gated", count(c.imu, OdometryEvent::kGated)},
      {"imu late", count(c.imu, OdometryEvent::kRejectedOutOfOrder)},
      {"imu not finite", count(c.imu, OdometryEvent::kRejectedNonFinite)},
      {"numerical failures", std::to_string(c.count(OdometryEvent::kNumericalFailure))},
      {"waiting for reordering", std::to_string(runner.pending())},
      {"wheels arrived out of order", std::to_string(aw.out_of_order)},
      {"imu arrived out of order", std::to_string(ai.out_of_order)},
      {"wheels largest lag in source (s)", seconds(aw.largest_lag_in_source_s)},
      {"imu largest lag in source (s)", seconds(ai.largest_lag_in_source_s)},
      {"wheels largest lag behind newest (s)", seconds(aw.largest_lag_s)},
      {"imu largest lag behind newest (s)", seconds(ai.largest_lag_s)},
      {"wheels longest gap (s)", seconds(aw.longest_gap_s)},
      {"imu longest gap (s)", seconds(ai.longest_gap_s)},
      {"wheels given up as quiet", quiet(OdometrySource::kWheels)},
      {"imu given up as quiet", quiet(OdometrySource::kImu)},
  };
  return s;
}

}  // namespace dispel::pipeline
