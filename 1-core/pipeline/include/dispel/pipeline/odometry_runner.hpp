#pragma once
/// @file
/// The one road from wheel speeds and IMU yaw rates to odometry, for `dispel odom` and the
/// odometry node alike. Measurements arrive on two sources, each a little late and in its own
/// order; they wait in a buffer until they are reorder_window_s older than the newest stamp
/// received (or until flushed), and are then fused in stamp order (wheels before the IMU at equal
/// stamps, equal keys in arrival order). One estimate is given out per time stamp, after every
/// measurement at that stamp, when the last of them was accepted or gated. `dispel odom` adds a
/// whole recording and flushes once; a node releases as it goes.

#include <cstdint>
#include <optional>
#include <queue>
#include <vector>

#include "dispel/core/odometry_fusion.hpp"

namespace dispel::pipeline {

/// What fuses the measurements.
enum class OdometryEngine : std::uint8_t {
  kFusion,         ///< OdometryFusion: the UKF with the configured model.
  kDeadReckoning,  ///< WheelOdometry: the wheels alone; IMU measurements are ignored.
};

class OdometryRunner {
 public:
  /// @throws std::invalid_argument for a bad @p config (OdometryConfig::validate()) or a
  /// @p reorder_window_s that is NaN or negative (+infinity: nothing is released before a flush).
  OdometryRunner(const OdometryConfig& config, double reorder_window_s,
                 OdometryEngine engine = OdometryEngine::kFusion);

  /// Buffers a measurement. One with a non-finite stamp is handed to the engine at once (which
  /// counts it as rejected); one older than the last fused stamp is counted as rejected when its
  /// turn comes.
  void add_wheels(double t_s, double v_left_mps, double v_right_mps);
  void add_imu(double t_s, double yaw_rate_radps);

  /// Fuses the measurements that are reorder_window_s older than the newest stamp (all of them
  /// with @p flush) and returns the estimates to give out, in time order.
  std::vector<OdometryEstimate> release(bool flush = false);

  std::size_t pending() const { return buffer_.size(); }
  double reorder_window_s() const { return window_s_; }
  OdometryEngine engine() const { return engine_; }
  /// The engine's counters (dead reckoning: wheels only).
  OdometryCounters counters() const;
  /// The latest estimate of the engine.
  OdometryEstimate estimate() const;
  /// Measurements whose stamp is earlier than the previous one of the same source, as they
  /// arrived (put back in order by the buffer when within the window).
  std::int64_t arrived_out_of_order() const { return arrived_out_of_order_; }

 private:
  struct Measurement {
    double t_s;
    int source;         // 0 wheels, 1 IMU: wheels first at equal stamps.
    std::uint64_t seq;  // Arrival order among equal keys.
    double a;           // Wheels: v_left; IMU: yaw rate.
    double b;           // Wheels: v_right.
  };
  struct Later {
    bool operator()(const Measurement& x, const Measurement& y) const;
  };

  void add(double t_s, int source, double a, double b);
  OdometryEvent fuse(const Measurement& m);

  OdometryEngine engine_;
  std::optional<OdometryFusion> fusion_;
  std::optional<WheelOdometry> wheels_only_;
  double window_s_;
  std::priority_queue<Measurement, std::vector<Measurement>, Later> buffer_;
  std::uint64_t next_seq_ = 0;
  double newest_s_;
  double last_given_s_;
  double last_arrival_s_[2];
  std::int64_t arrived_out_of_order_ = 0;
};

}  // namespace dispel::pipeline
