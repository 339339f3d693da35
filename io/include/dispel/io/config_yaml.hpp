#pragma once
/// @file
/// The filter's configuration from YAML. Keys mirror the configuration structs:
///   segmentation: {cluster_gap_m, min_points, gap_metric, merge_facing_edges,
///                  join_full_circle_seam, masked_sectors: [[begin_rad, end_rad], ...]}
///   tracking: {match_distance_m, matching, max_missed_scans, inherit_on_split, max_gate_m,
///              max_extent_change_m}
///   velocity: {position_variance_m2, velocity_variance_m2ps2, measurement_variance_m2,
///              velocity_decay, nominal_scan_period_s}
///   classification: {presumption, speed_limit_mps, dynamic_weight_limit, static_weight_limit,
///                    max_direction_difference_rad, max_dynamic_extent_m, max_point_count_ratio,
///                    slow_scans_reduce_dynamic_weight}
///   max_time_gap_s, max_pose_jump_m, max_pose_jump_rad
/// Missing keys keep their defaults. Unknown keys, wrong types and invalid values are errors.

#include <stdexcept>
#include <string>

#include "dispel/core/dynamic_filter.hpp"

namespace dispel::io {

/// A configuration that cannot be used; what() is one line naming the file and the key.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Reads and validates a configuration file. @throws ConfigError
DynamicFilterConfig load_filter_config(const std::string& path);

/// Parses and validates YAML text; @p origin names it in errors. @throws ConfigError
DynamicFilterConfig parse_filter_config(const std::string& yaml_text, const std::string& origin);

}  // namespace dispel::io
