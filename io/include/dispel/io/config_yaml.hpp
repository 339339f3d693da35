#pragma once
/// @file
/// The filter's configuration from YAML. Keys mirror the configuration structs (config/default.yaml
/// lists every one with its default):
///   preset: default | thesis   the starting point: default_config() (when absent) or
///                              thesis_config(); every other key changes it
///   segmentation: {...}, tracking: {...}, velocity: {...}, classification: {...},
///   free_space: {...}, max_time_gap_s, max_pose_jump_m, max_pose_jump_rad
/// Missing keys keep the preset's value. Unknown keys, wrong types and invalid values are errors.

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
