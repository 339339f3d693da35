// Fuzz target: the YAML file of a map_server map through dispel's map reader (read_map_yaml, as
// `dispel slam --map` reads one), beside a small valid PGM image named map.pgm (the seeds' image
// key names it). A map dispel refuses must be refused with a JobError of one line.

#include <cstddef>
#include <cstdint>
#include <optional>

#include "dispel/jobs/job.hpp"
#include "dispel/slam/grid_map.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto& folder = dispel::fuzz::temp_folder();
  // 4 x 3 pixels, 8 bits: black, white, grey and in between.
  static const std::string image = folder.write(
      "map.pgm", std::string("P5\n4 3\n255\n", 11) +
                     std::string("\x00\xfe\xcd\x80\x00\x00\xfe\xfe\xcd\x10\xf0\x64", 12));
  const std::string path = folder.write("map.yaml", data, size);
  std::optional<dispel::slam::GridMap> map;
  try {
    map = dispel::slam::read_map_yaml(path);
  } catch (const dispel::jobs::JobError& e) {
    dispel::fuzz::check_message(e.what());
  }
  if (map) map->validate();  // A map the reader accepts is a valid one (else JobError: a finding).
  return 0;
}
