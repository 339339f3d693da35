#pragma once
/// @file
/// The part of a live odometry node that is not middleware: wheel speeds and IMU yaw rates that
/// arrive on two topics, each a little late and in its own order, put back into time order before
/// the fusion sees them. Measurements wait in a buffer until they are reorder_window_s older than
/// the newest stamp received (or until flushed), and are then fused in stamp order (wheels before
/// the IMU at equal stamps), as `dispel odom` fuses a whole recording sorted by stamp. One
/// estimate is given out per time stamp, after every measurement at that stamp, when the fusion
/// accepted or gated it: `dispel odom` writes its CSV rows by the same rule.

#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "dispel/core/odometry_fusion.hpp"

namespace dispel::node {

class OdometryRunner {
 public:
  /// @throws std::invalid_argument for a bad @p config (OdometryConfig::validate()) or a
  /// @p reorder_window_s that is not a finite number >= 0.
  OdometryRunner(const OdometryConfig& config, double reorder_window_s);

  /// Buffers a measurement (the fusion counts a non-finite one at once, and one older than the
  /// last fused stamp when its turn comes, as rejected).
  void add_wheels(double t_s, double v_left_mps, double v_right_mps);
  void add_imu(double t_s, double yaw_rate_radps);

  /// Fuses the measurements that are reorder_window_s older than the newest stamp (all of them
  /// with @p flush) and returns the estimates to publish, in time order.
  std::vector<OdometryEstimate> release(bool flush = false);

  std::size_t pending() const { return buffer_.size(); }
  double reorder_window_s() const { return window_s_; }
  const OdometryFusion& fusion() const { return fusion_; }

 private:
  struct Measurement {
    bool imu;
    double a;  // Wheels: v_left; IMU: yaw rate.
    double b;  // Wheels: v_right.
  };
  using Key = std::pair<double, int>;  // (stamp, 0 wheels / 1 IMU)

  void add(double t_s, const Measurement& m);
  OdometryEvent fuse(double t_s, const Measurement& m);

  OdometryFusion fusion_;
  double window_s_;
  std::multimap<Key, Measurement> buffer_;  // Equal keys keep their arrival order.
  double newest_s_;
  double last_published_s_;
};

}  // namespace dispel::node
