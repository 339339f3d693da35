// Fuzz target: a filter configuration file (YAML) through dispel's reader, both of its readings:
// the filter's keys (`dispel filter --config`, the filter node) and the `odometry:` section
// (`dispel odom --config`). A file dispel refuses must be refused with a ConfigError of one line.

#include <cstddef>
#include <cstdint>

#include "dispel/io/config_yaml.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = dispel::fuzz::temp_folder().write("input.yaml", data, size);
  try {
    (void)dispel::io::load_filter_config(path);
  } catch (const dispel::io::ConfigError& e) {
    dispel::fuzz::check_message(e.what());
  }
  try {
    (void)dispel::io::load_odometry_settings(path);
  } catch (const dispel::io::ConfigError& e) {
    dispel::fuzz::check_message(e.what());
  }
  return 0;
}
