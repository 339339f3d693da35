#include "dispel/core/pose_buffer.hpp"

#include <algorithm>
#include <cmath>

namespace dispel {

bool PoseBuffer::add(double stamp_s, const Pose2& pose) {
  if (!std::isfinite(stamp_s) || !std::isfinite(pose.x_m) || !std::isfinite(pose.y_m) ||
      !std::isfinite(pose.yaw_rad)) {
    return false;
  }
  if (!poses_.empty() && !(stamp_s > poses_.back().stamp_s)) return false;
  poses_.push_back({stamp_s, pose});
  return true;
}

PoseLookup PoseBuffer::lookup(double stamp_s, Pose2& pose) const {
  if (poses_.empty()) return PoseLookup::kEmpty;
  if (stamp_s <= poses_.front().stamp_s) {
    if (poses_.front().stamp_s - stamp_s > tolerance_s_) return PoseLookup::kBeforeFirst;
    pose = poses_.front().pose;
    return PoseLookup::kOk;
  }
  if (stamp_s >= poses_.back().stamp_s) {
    if (stamp_s - poses_.back().stamp_s > tolerance_s_) return PoseLookup::kAfterLast;
    pose = poses_.back().pose;
    return PoseLookup::kOk;
  }
  const auto after = std::upper_bound(poses_.begin(), poses_.end(), stamp_s,
                                      [](double t, const TimedPose& p) { return t < p.stamp_s; });
  const TimedPose& b = *after;
  const TimedPose& a = *(after - 1);
  if (b.stamp_s - a.stamp_s > max_gap_s_) {
    // Not interpolated across the gap; a pose within the tolerance of either side is used, as at
    // the ends (a scanner at 4 Hz has scans at the very stamps of the poses around a long gap).
    if (stamp_s - a.stamp_s <= tolerance_s_ && stamp_s - a.stamp_s <= b.stamp_s - stamp_s) {
      pose = a.pose;
      return PoseLookup::kOk;
    }
    if (b.stamp_s - stamp_s <= tolerance_s_) {
      pose = b.pose;
      return PoseLookup::kOk;
    }
    return PoseLookup::kGap;
  }
  const double w = (stamp_s - a.stamp_s) / (b.stamp_s - a.stamp_s);
  pose.x_m = a.pose.x_m + w * (b.pose.x_m - a.pose.x_m);
  pose.y_m = a.pose.y_m + w * (b.pose.y_m - a.pose.y_m);
  pose.yaw_rad = wrap_angle(a.pose.yaw_rad + w * wrap_angle(b.pose.yaw_rad - a.pose.yaw_rad));
  return PoseLookup::kOk;
}

void PoseBuffer::forget_before(double stamp_s) {
  const auto after = std::upper_bound(poses_.begin(), poses_.end(), stamp_s,
                                      [](double t, const TimedPose& p) { return t < p.stamp_s; });
  if (after - poses_.begin() > 1) poses_.erase(poses_.begin(), after - 1);
}

const char* pose_lookup_name(PoseLookup result) {
  switch (result) {
    case PoseLookup::kOk:
      return "ok";
    case PoseLookup::kEmpty:
      return "no_poses";
    case PoseLookup::kBeforeFirst:
      return "before_first_pose";
    case PoseLookup::kAfterLast:
      return "after_last_pose";
    case PoseLookup::kGap:
      return "pose_gap";
  }
  return "unknown";
}

}  // namespace dispel
