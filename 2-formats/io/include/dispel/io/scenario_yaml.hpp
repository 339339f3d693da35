#pragma once
/// @file
/// Scenarios from YAML (schema: docs/simulator.md). Unknown keys and bad values are errors that
/// name the key.

#include <string>

#include "dispel/io/config_yaml.hpp"
#include "dispel/sim/scenario.hpp"

namespace dispel::io {

/// @throws ConfigError naming the file and the key.
sim::Scenario load_scenario(const std::string& path);
sim::Scenario parse_scenario(const std::string& yaml_text, const std::string& origin);

}  // namespace dispel::io
