#pragma once
/// @file
/// The one road from wheel speeds and IMU yaw rates to odometry, for `dispel odom` and the
/// odometry node alike. Measurements arrive on two sources, each a little late and in its own
/// order; they wait in a buffer and are fused in stamp order (wheels before the IMU at equal
/// stamps, equal keys in arrival order). One estimate is given out per time stamp, after every
/// measurement at that stamp, when the last of them was accepted or gated. `dispel odom` adds a
/// whole recording and flushes once; a node releases as it goes.
///
/// When a measurement is released (live): once every source the buffer waits for has delivered a
/// stamp at least reorder_window_s later than it. Each source arrives in order on its own (one
/// publisher, one connection), so waiting for the slower source puts the two back in order
/// however far apart a busy machine delivers them; the window is for disorder within a source and
/// for a source that was not waited for coming back (its stamps may be older than the other's by
/// the difference of their latencies). Both sources are waited for from the start (by dead
/// reckoning the wheels alone), a source that has not delivered yet too; a source is no longer
/// waited for once it has been quiet for source_timeout_s while measurements wait (release_at(),
/// on the arrival clock), until it delivers again. A measurement older than one already fused is
/// late: refused by the fusion, counted (counters(): kRejectedOutOfOrder).

#include <array>
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

/// Where a measurement comes from.
enum class OdometrySource : std::uint8_t { kWheels, kImu };

/// How one source's measurements arrived: the jitter the buffer has to absorb.
struct OdometryArrivals {
  std::int64_t count = 0;  ///< Measurements added.
  /// Arrived with a stamp earlier than the latest of the same source.
  std::int64_t out_of_order = 0;
  /// The largest amount (s of stamp time) by which a measurement's stamp was earlier than the
  /// latest stamp of its own source when it arrived: what reorder_window_s has to cover.
  double largest_lag_in_source_s = 0.0;
  /// The largest amount by which it was earlier than the latest stamp of any source: what a
  /// window measured from the newest stamp alone would have to cover.
  double largest_lag_s = 0.0;
  /// The longest time on release_at()'s arrival clock between two measurements of the source
  /// (or since measurements began to wait) while measurements waited: what source_timeout_s has
  /// to exceed (the gap of a source given up as quiet counts when it comes back).
  double longest_gap_s = 0.0;
};

class OdometryRunner {
 public:
  static constexpr std::size_t kSources = 2;

  /// @throws std::invalid_argument for a bad @p config (OdometryConfig::validate()) or a
  /// @p reorder_window_s that is NaN or negative (+infinity: nothing is released before a flush).
  OdometryRunner(const OdometryConfig& config, double reorder_window_s,
                 OdometryEngine engine = OdometryEngine::kFusion);

  /// Buffers a measurement. One with a non-finite stamp is handed to the engine at once (which
  /// counts it as rejected); one older than the last fused stamp is counted as rejected when its
  /// turn comes. A source not waited for is waited for again from its measurement with a finite
  /// stamp on (the IMU never by dead reckoning).
  void add_wheels(double t_s, double v_left_mps, double v_right_mps);
  void add_imu(double t_s, double yaw_rate_radps);

  /// Fuses the measurements that every source waited for has passed by reorder_window_s (all of
  /// them with @p flush) and returns the estimates to give out, in time order.
  std::vector<OdometryEstimate> release(bool flush = false);

  /// Live use: @p now_s is the arrival clock (monotonic seconds), the time at which the
  /// measurements added since the previous call arrived; call it after each measurement and
  /// periodically. First stops waiting for each source from which nothing has arrived for
  /// @p source_timeout_s while measurements wait (a measurement waits at most that long for a
  /// quiet source; when every source is quiet, everything is released), then releases as
  /// release() does. @throws std::invalid_argument for a NaN or negative timeout.
  std::vector<OdometryEstimate> release_at(double now_s, double source_timeout_s);

  /// Stops waiting for @p source until its next measurement.
  void stop_waiting_for(OdometrySource source);
  bool waiting_for(OdometrySource source) const { return waiting_[index(source)]; }
  /// Times a source was given up as quiet by release_at().
  std::int64_t quiet_count(OdometrySource source) const { return quiet_count_[index(source)]; }

  std::size_t pending() const { return buffer_.size(); }
  double reorder_window_s() const { return window_s_; }
  OdometryEngine engine() const { return engine_; }
  /// The engine's counters (dead reckoning: wheels only).
  OdometryCounters counters() const;
  /// Measurements of @p source refused as late (older than one already fused).
  std::int64_t late(OdometrySource source) const;
  /// The latest estimate of the engine.
  OdometryEstimate estimate() const;
  /// How the measurements of @p source arrived.
  const OdometryArrivals& arrivals(OdometrySource source) const { return arrivals_[index(source)]; }
  /// Measurements whose stamp is earlier than the previous one of the same source, as they
  /// arrived (put back in order by the buffer when within the window), both sources.
  std::int64_t arrived_out_of_order() const {
    return arrivals_[0].out_of_order + arrivals_[1].out_of_order;
  }

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
  static std::size_t index(OdometrySource s) { return static_cast<std::size_t>(s); }

  void add(double t_s, int source, double a, double b);
  OdometryEvent fuse(const Measurement& m);
  double horizon() const;

  OdometryEngine engine_;
  std::optional<OdometryFusion> fusion_;
  std::optional<WheelOdometry> wheels_only_;
  double window_s_;
  std::priority_queue<Measurement, std::vector<Measurement>, Later> buffer_;
  std::uint64_t next_seq_ = 0;
  double newest_s_;
  double last_given_s_;
  std::array<double, kSources> latest_s_;
  std::array<bool, kSources> waiting_{};
  std::array<OdometryArrivals, kSources> arrivals_{};
  std::array<std::int64_t, kSources> quiet_count_{};
  // release_at(): the arrival clock.
  std::array<bool, kSources> arrived_since_release_{};
  bool empty_before_arrivals_ = true;  // The buffer was empty before those arrivals.
  std::array<double, kSources> last_arrival_s_;
  double pending_since_s_;  // When the buffer last became non-empty.
};

}  // namespace dispel::pipeline
