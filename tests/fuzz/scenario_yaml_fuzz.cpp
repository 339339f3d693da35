// Fuzz target: a simulator scenario (YAML) through dispel's reader, as `dispel sim` and
// `dispel experiment` read one. A file dispel refuses must be refused with a ConfigError of one
// line.

#include <cstddef>
#include <cstdint>

#include "dispel/io/scenario_yaml.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = dispel::fuzz::temp_folder().write("input.yaml", data, size);
  try {
    (void)dispel::io::load_scenario(path);
  } catch (const dispel::io::ConfigError& e) {
    dispel::fuzz::check_message(e.what());
  }
  return 0;
}
