#pragma once
/// @file
/// How far an estimated planar trajectory is from the true one: absolute trajectory error (RMSE
/// of position and yaw), the error at the end, and the length of the path.

#include <cstdint>
#include <vector>

namespace dispel::eval {

/// One pose of a trajectory: time (s), position (m) and yaw (rad) in a fixed frame. A truth
/// without heading (GPS) has NaN yaw; its yaw errors are then NaN.
struct TrajectoryPoint {
  double t_s = 0.0;
  double x_m = 0.0;
  double y_m = 0.0;
  double yaw_rad = 0.0;
};

/// The errors of an estimate against the truth, over the truth's samples that fall inside the
/// estimate's time span (the estimate interpolated at their times).
struct TrajectoryErrors {
  double rmse_position_m = 0.0;
  double rmse_x_m = 0.0;
  double rmse_y_m = 0.0;
  double rmse_yaw_rad = 0.0;            ///< Of the wrapped yaw differences.
  double final_position_error_m = 0.0;  ///< At the last compared truth sample.
  double final_yaw_error_rad = 0.0;     ///< Absolute, wrapped, at the same sample.
  double max_position_error_m = 0.0;    ///< The largest over the compared samples.
  double max_yaw_error_rad = 0.0;       ///< The largest absolute; NaN when the truth has no yaw.
  double path_length_m = 0.0;           ///< Of the truth, over the compared samples.
  std::int64_t compared = 0;            ///< Truth samples compared.
  std::int64_t outside = 0;             ///< Truth samples outside the estimate's time span.
  double alignment_rotation_rad = 0.0;  ///< Applied to the estimate (0 without alignment).
};

struct TrajectoryComparison {
  /// > 0: before comparing, move the estimate rigidly (rotation and translation, least squares)
  /// onto the truth over the truth's first this many metres of path, for a truth in another frame
  /// (GPS east/north against odometry that starts at the origin facing x). 0: compare as they are.
  double align_first_m = 0.0;
};

/// Compares @p estimate with @p truth: the estimate is interpolated at each truth time (position
/// linearly, yaw along the shorter way round). Both must hold finite values (the truth's yaw may
/// be NaN throughout) with times that never decrease; at equal times the later sample wins.
/// @throws std::invalid_argument naming the problem (fewer than two samples, a non-finite value,
/// time going backwards at sample i, no truth sample inside the estimate's time span, too little
/// path to align on).
TrajectoryErrors compare_trajectories(const std::vector<TrajectoryPoint>& truth,
                                      const std::vector<TrajectoryPoint>& estimate,
                                      const TrajectoryComparison& how = {});

}  // namespace dispel::eval
