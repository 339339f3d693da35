#pragma once
/// @file
/// The 2D laser scan as dispel sees it, and the checks a scan must pass before it is used.

#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

namespace dispel {

/// One sweep of a 2D LiDAR, in the sensor frame (x forward, y left, angles counter-clockwise).
///
/// Mirrors sensor_msgs/LaserScan. Beam i points at bearing angle_min_rad + i * angle_increment_rad.
/// A range that is NaN, infinite, or outside [range_min_m, range_max_m] is an invalid beam
/// (REP 117): it is carried through untouched and is never part of an object.
struct LaserScan {
  double stamp_s = 0.0;              ///< Time of the first beam, seconds.
  double angle_min_rad = 0.0;        ///< Bearing of beam 0.
  double angle_increment_rad = 0.0;  ///< Bearing step between beams; must be > 0.
  float range_min_m = 0.0F;          ///< Shortest valid range.
  float range_max_m = 0.0F;          ///< Longest valid range (may be +infinity).
  /// Time between two beams, seconds (sensor_msgs/LaserScan time_increment): beam i is measured
  /// at stamp_s + i * time_increment_s. 0 when the scanner states none (all beams at stamp_s).
  double time_increment_s = 0.0;
  std::vector<float> ranges_m;     ///< One range per beam.
  std::vector<float> intensities;  ///< Empty, or one value per beam.

  /// Number of beams.
  std::size_t size() const { return ranges_m.size(); }

  /// Bearing of beam @p i in radians (not wrapped).
  double bearing_rad(std::size_t i) const {
    return angle_min_rad + static_cast<double>(i) * angle_increment_rad;
  }

  /// True when beam @p i holds a usable range: finite and inside [range_min_m, range_max_m].
  bool is_valid(std::size_t i) const {
    const float r = ranges_m[i];
    return r >= range_min_m && r <= range_max_m;  // false for NaN; +inf only if range_max is.
  }
};

/// The unit vector of each beam's bearing in the sensor frame, computed once for a scanner's
/// geometry and again only when it changes: (cos, sin) of bearing_rad(i), the same values a
/// per-beam std::cos and std::sin give.
class BeamDirections {
 public:
  /// The directions for @p scan's geometry (beam count, angle_min_rad, angle_increment_rad).
  const std::vector<Eigen::Vector2d>& of(const LaserScan& scan) {
    if (scan.size() != unit_.size() || scan.angle_min_rad != angle_min_rad_ ||
        scan.angle_increment_rad != angle_increment_rad_) {
      angle_min_rad_ = scan.angle_min_rad;
      angle_increment_rad_ = scan.angle_increment_rad;
      unit_.resize(scan.size());
      for (std::size_t i = 0; i < scan.size(); ++i) {
        const double bearing = scan.bearing_rad(i);
        unit_[i] = Eigen::Vector2d(std::cos(bearing), std::sin(bearing));
      }
    }
    return unit_;
  }

 private:
  double angle_min_rad_ = 0.0;
  double angle_increment_rad_ = 0.0;
  std::vector<Eigen::Vector2d> unit_;
};

/// What can be wrong with a scan as a whole. A scan with any of these is rejected, never used.
enum class ScanIssue {
  kNone = 0,
  kEmpty,                   ///< No beams.
  kNonFiniteAngles,         ///< angle_min_rad or angle_increment_rad is NaN or infinite.
  kNonPositiveIncrement,    ///< angle_increment_rad <= 0.
  kBadRangeLimits,          ///< range_min_m < 0, NaN, or range_max_m <= range_min_m.
  kIntensityCountMismatch,  ///< intensities is neither empty nor one per beam.
  kNonFiniteStamp,          ///< stamp_s is NaN or infinite.
};

/// Number of ScanIssue values, for counting skipped scans by reason.
inline constexpr std::size_t kScanIssueCount = 7;

/// Checks the scan's header and array lengths (not the individual ranges: those may be invalid).
ScanIssue check_scan(const LaserScan& scan);

/// Short stable name of an issue, e.g. "non_positive_increment" (for counters and JSON keys).
const char* scan_issue_name(ScanIssue issue);

/// One-line human explanation naming the offending field and value, e.g.
/// "angle_increment_rad must be > 0, got 0". Empty for ScanIssue::kNone.
std::string describe_scan_issue(const LaserScan& scan, ScanIssue issue);

}  // namespace dispel
