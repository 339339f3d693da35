#include "dispel/core/dynamic_filter_config.hpp"

#include <algorithm>
#include <cmath>

#include "dispel/core/invalid_field.hpp"
#include "dispel/core/pose2.hpp"

namespace dispel {

void TrackingConfig::validate() const {
  if (!std::isfinite(match_distance_m) || !(match_distance_m > 0.0)) {
    reject_field("tracking.match_distance_m", match_distance_m, "a finite number > 0");
  }
  if (matching != Matching::kGlobal && matching != Matching::kNearestNeighbour) {
    reject_field("tracking.matching", static_cast<int>(matching), "global or nearest_neighbour");
  }
  if (max_missed_scans < 0) reject_field("tracking.max_missed_scans", max_missed_scans, ">= 0");
  if (!std::isfinite(companion_distance_m) || companion_distance_m < 0.0) {
    reject_field("tracking.companion_distance_m", companion_distance_m, "a finite number >= 0");
  }
  if (!std::isfinite(companion_speed_difference_mps) || companion_speed_difference_mps < 0.0) {
    reject_field("tracking.companion_speed_difference_mps", companion_speed_difference_mps,
                 "a finite number >= 0");
  }
  if (!std::isfinite(fragment_distance_m) || fragment_distance_m < 0.0) {
    reject_field("tracking.fragment_distance_m", fragment_distance_m, "a finite number >= 0");
  }
  if (!std::isfinite(max_gate_m) || max_gate_m < match_distance_m) {
    reject_field("tracking.max_gate_m", max_gate_m, "finite and >= match_distance_m");
  }
  if (!(max_extent_change_m > 0.0)) {
    reject_field("tracking.max_extent_change_m", max_extent_change_m, "> 0");
  }
}

void DynamicFilterConfig::validate() const {
  segmentation.validate();
  tracking.validate();
  velocity.validate();
  classification.validate();
  free_space.validate();
  registration.validate();
  if (!(max_time_gap_s > 0.0)) reject_field("max_time_gap_s", max_time_gap_s, "> 0");
  if (!(max_pose_jump_m > 0.0)) reject_field("max_pose_jump_m", max_pose_jump_m, "> 0");
  if (!(max_pose_jump_rad > 0.0)) reject_field("max_pose_jump_rad", max_pose_jump_rad, "> 0");
  if (!(max_speed_mps >= 0.0 && max_speed_mps <= 100.0))
    reject_field("max_speed_mps", max_speed_mps, "in [0, 100]");
  if (!(max_turn_rate_radps >= 0.0 && max_turn_rate_radps <= 100.0))
    reject_field("max_turn_rate_radps", max_turn_rate_radps, "in [0, 100]");
}

DynamicFilterConfig thesis_config() {
  DynamicFilterConfig c;
  c.segmentation.gap_metric = GapMetric::kRangeDifference;
  c.segmentation.cluster_gap_spacings = 0.0;
  c.segmentation.min_width_m = 0.0;
  c.tracking.matching = Matching::kNearestNeighbour;
  c.tracking.max_missed_scans = 10;
  c.tracking.inherit_on_split = false;
  c.tracking.companion_distance_m = 0.0;
  c.tracking.fragment_distance_m = 0.0;
  c.tracking.follow_fragments = false;
  c.tracking.remove_edge_pixels = false;
  // Used by global matching only; the values the thesis preset had when it matched globally.
  c.tracking.max_gate_m = 1.0;
  c.tracking.max_extent_change_m = 0.5;
  c.velocity.position_variance_m2 = 0.75;
  c.velocity.velocity_variance_m2ps2 = 1.5;
  c.velocity.measurement_variance_m2 = 15.0;
  c.velocity.velocity_decay = 0.8;
  c.classification.speed_limit_mps = 0.08;
  c.classification.dynamic_weight_limit = 18;
  c.classification.static_weight_limit = 50;
  c.classification.slow_scans_reduce_dynamic_weight = false;
  c.classification.still_scans_to_static = 0;
  c.classification.still_alone_to_static_s = 0.0;
  c.free_space.enabled = false;
  c.registration.enabled = false;
  return c;
}

DynamicFilterConfig scale_to_scanner(DynamicFilterConfig config, double angle_increment_rad,
                                     double scan_period_s) {
  if (!std::isfinite(angle_increment_rad) || !(angle_increment_rad > 0.0)) {
    reject_field("angle_increment_rad", angle_increment_rad, "a finite number > 0");
  }
  if (!std::isfinite(scan_period_s) || !(scan_period_s > 0.0)) {
    reject_field("scan_period_s", scan_period_s, "a finite number > 0");
  }
  constexpr double kThesisIncrementRad = 275.0 / 1616.0 * kPi / 180.0;
  constexpr double kThesisPeriodS = 0.05;
  const double beams = kThesisIncrementRad / angle_increment_rad;
  const double scans = kThesisPeriodS / scan_period_s;
  ClassificationConfig& c = config.classification;
  config.segmentation.min_points =
      std::max(3, static_cast<int>(std::lround(config.segmentation.min_points * beams)));
  c.dynamic_weight_limit =
      std::max(1, static_cast<int>(std::lround(c.dynamic_weight_limit * scans)));
  c.static_weight_limit = std::max(1, static_cast<int>(std::lround(c.static_weight_limit * scans)));
  if (c.still_scans_to_static > 0) {
    c.still_scans_to_static =
        std::max(1, static_cast<int>(std::lround(c.still_scans_to_static * scans)));
  }
  return config;
}

}  // namespace dispel
