#include "dispel/core/laser_scan.hpp"

#include <cmath>
#include <sstream>

namespace dispel {

ScanIssue check_scan(const LaserScan& scan) {
  if (scan.ranges_m.empty()) return ScanIssue::kEmpty;
  if (!std::isfinite(scan.angle_min_rad) || !std::isfinite(scan.angle_increment_rad)) {
    return ScanIssue::kNonFiniteAngles;
  }
  if (!(scan.angle_increment_rad > 0.0)) return ScanIssue::kNonPositiveIncrement;
  if (!std::isfinite(scan.range_min_m) || scan.range_min_m < 0.0F ||
      !(scan.range_max_m > scan.range_min_m)) {
    return ScanIssue::kBadRangeLimits;
  }
  if (!scan.intensities.empty() && scan.intensities.size() != scan.ranges_m.size()) {
    return ScanIssue::kIntensityCountMismatch;
  }
  if (!std::isfinite(scan.stamp_s)) return ScanIssue::kNonFiniteStamp;
  return ScanIssue::kNone;
}

const char* scan_issue_name(ScanIssue issue) {
  switch (issue) {
    case ScanIssue::kNone:
      return "none";
    case ScanIssue::kEmpty:
      return "empty";
    case ScanIssue::kNonFiniteAngles:
      return "non_finite_angles";
    case ScanIssue::kNonPositiveIncrement:
      return "non_positive_increment";
    case ScanIssue::kBadRangeLimits:
      return "bad_range_limits";
    case ScanIssue::kIntensityCountMismatch:
      return "intensity_count_mismatch";
    case ScanIssue::kNonFiniteStamp:
      return "non_finite_stamp";
  }
  return "unknown";
}

std::string describe_scan_issue(const LaserScan& scan, ScanIssue issue) {
  std::ostringstream out;
  switch (issue) {
    case ScanIssue::kNone:
      return {};
    case ScanIssue::kEmpty:
      out << "scan has no beams (ranges is empty)";
      break;
    case ScanIssue::kNonFiniteAngles:
      out << "angle_min_rad and angle_increment_rad must be finite, got " << scan.angle_min_rad
          << " and " << scan.angle_increment_rad;
      break;
    case ScanIssue::kNonPositiveIncrement:
      out << "angle_increment_rad must be > 0, got " << scan.angle_increment_rad
          << " (reverse the beam order of a scanner that sweeps clockwise)";
      break;
    case ScanIssue::kBadRangeLimits:
      out << "range limits must satisfy 0 <= range_min_m < range_max_m, got range_min_m "
          << scan.range_min_m << " and range_max_m " << scan.range_max_m;
      break;
    case ScanIssue::kIntensityCountMismatch:
      out << "intensities has " << scan.intensities.size() << " values but ranges has "
          << scan.ranges_m.size() << " (must be empty or equal)";
      break;
    case ScanIssue::kNonFiniteStamp:
      out << "stamp_s must be finite, got " << scan.stamp_s;
      break;
  }
  return out.str();
}

}  // namespace dispel
