#pragma once
/// @file
/// Beam-level evaluation of a filter against ground truth (the measures of the dynamic-point-
/// removal literature, e.g. ERASOR: preservation rate and rejection rate), and the time it takes
/// to remove each moving actor.

#include <cstdint>
#include <limits>
#include <map>
#include <vector>

namespace dispel::eval {

/// Ground-truth codes (as written by the simulator): 0 static, 1 moving, 2 actor standing still,
/// 3 no return.
inline constexpr std::uint8_t kTruthStatic = 0, kTruthMoving = 1, kTruthStill = 2,
                              kTruthNoReturn = 3;

struct Rates {
  std::int64_t static_beams = 0, static_kept = 0;
  std::int64_t moving_beams = 0, moving_removed = 0;
  std::int64_t still_beams = 0, still_removed = 0;
  /// Of the still beams, those of an actor that the scanner sees moving later (someone who stands
  /// and then walks off); the others are of an actor after it last moved in view (someone who
  /// walked in and stayed), or of no known actor.
  std::int64_t still_moves_later_beams = 0, still_moves_later_removed = 0;
  std::int64_t scans = 0;
  std::int64_t actors_seen = 0;     ///< Moving actors that appeared in a scan.
  std::int64_t actors_removed = 0;  ///< ... and were removed at some point.
  double preservation_rate() const { return ratio(static_kept, static_beams); }
  double rejection_rate() const { return ratio(moving_removed, moving_beams); }
  double still_removed_rate() const { return ratio(still_removed, still_beams); }
  double still_moves_later_removed_rate() const {
    return ratio(still_moves_later_removed, still_moves_later_beams);
  }
  /// Harmonic mean of preservation and rejection.
  double f1() const {
    const double p = preservation_rate(), r = rejection_rate();
    return p + r > 0.0 ? 2.0 * p * r / (p + r) : 0.0;
  }
  std::vector<double> latencies_s;  ///< One per actor that was removed.
  double latency_median_s() const { return quantile(0.5); }
  double latency_p90_s() const { return quantile(0.9); }

 private:
  static double ratio(std::int64_t a, std::int64_t b) {
    return b > 0 ? static_cast<double>(a) / static_cast<double>(b)
                 : std::numeric_limits<double>::quiet_NaN();
  }
  double quantile(double q) const;
};

/// Accumulates scans. An actor's latency is the time from the first scan in which it is seen
/// moving with at least `min_beams` beams (8, the thesis's N_min: with fewer, no segmentation can
/// make it an object) to the first scan in which at least half of its beams are removed.
class BeamEvaluator {
 public:
  explicit BeamEvaluator(int min_beams = 8) : min_beams_(min_beams) {}

  /// @p truth, @p actor (index + 1, or 0) and @p removed are per beam and of equal length.
  void add_scan(double stamp_s, const std::vector<std::uint8_t>& truth,
                const std::vector<std::int32_t>& actor, const std::vector<bool>& removed);

  Rates result() const;

 private:
  struct ActorTimes {
    double first_seen = std::numeric_limits<double>::quiet_NaN();
    double first_removed = std::numeric_limits<double>::quiet_NaN();
  };
  // An actor's still beams in one scan.
  struct StillScan {
    std::int32_t actor = 0;
    double stamp_s = 0.0;
    std::int32_t beams = 0, removed = 0;
  };
  int min_beams_;
  Rates rates_;
  std::map<std::int32_t, ActorTimes> actors_;
  std::vector<StillScan> still_;
  std::map<std::int32_t, double> last_moving_s_;  // Per actor: the last scan it moved in.
};

}  // namespace dispel::eval
