#pragma once
/// @file
/// Timed poses (e.g. odometry) and their interpolation at scan times.

#include <cstddef>
#include <optional>
#include <vector>

#include "dispel/core/pose2.hpp"

namespace dispel {

/// A pose at a time.
struct TimedPose {
  double stamp_s = 0.0;
  Pose2 pose;
};

/// Why a pose could not be given for a time.
enum class PoseLookup {
  kOk,
  kEmpty,        ///< No poses at all.
  kBeforeFirst,  ///< Earlier than the first pose by more than the tolerance.
  kAfterLast,    ///< Later than the last pose by more than the tolerance.
  kGap,          ///< Between two poses further apart than max_gap_s.
};

/// Poses in time order, interpolated linearly (yaw along the shorter arc). Never extrapolates
/// beyond `tolerance_s`: within it the nearest end pose is used, beyond it the lookup fails. Nor
/// does it interpolate across a gap longer than `max_gap_s`: there too only a pose within
/// `tolerance_s` of the stamp is used.
class PoseBuffer {
 public:
  /// @param tolerance_s how far before the first or after the last pose a lookup may be.
  /// @param max_gap_s two poses further apart than this are not interpolated between.
  explicit PoseBuffer(double tolerance_s = 0.05, double max_gap_s = 0.5)
      : tolerance_s_(tolerance_s), max_gap_s_(max_gap_s) {}

  /// Adds a pose. Poses with a non-finite value or a stamp not after the last one are refused
  /// (returns false) so the buffer stays ordered; the caller counts them.
  bool add(double stamp_s, const Pose2& pose);

  /// The pose at @p stamp_s, or why there is none.
  PoseLookup lookup(double stamp_s, Pose2& pose) const;

  /// Forgets the poses no lookup at @p stamp_s or later needs: those before the last one at or
  /// before it (a buffer fed for hours stays a few poses long).
  void forget_before(double stamp_s);

  std::size_t size() const { return poses_.size(); }
  bool empty() const { return poses_.empty(); }
  const std::vector<TimedPose>& poses() const { return poses_; }

 private:
  double tolerance_s_;
  double max_gap_s_;
  std::vector<TimedPose> poses_;
};

/// Stable short name, e.g. "after_last".
const char* pose_lookup_name(PoseLookup result);

}  // namespace dispel
