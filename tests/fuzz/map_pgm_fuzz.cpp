// Fuzz target: the PGM image of a map_server map through dispel's map reader (read_map_yaml, as
// `dispel slam --map` reads one), named by three YAML files: one per mode (trinary, scale, raw;
// scale with equal thresholds). A map dispel refuses must be refused with a JobError of one line.

#include <cstddef>
#include <cstdint>
#include <optional>

#include "dispel/jobs/job.hpp"
#include "dispel/slam/grid_map.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto& folder = dispel::fuzz::temp_folder();
  static const std::vector<std::string> yamls = [&] {
    const std::string common = "image: map.pgm\nresolution: 0.05\norigin: [-1.0, -2.0, 0.0]\n";
    return std::vector<std::string>{
        folder.write("trinary.yaml",
                     common + "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"),
        folder.write("scale.yaml", common + "negate: 1\noccupied_thresh: 0.5\nfree_thresh: 0.5\n"
                                            "mode: scale\n"),
        folder.write("raw.yaml",
                     common + "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\nmode: raw\n")};
  }();
  folder.write("map.pgm", data, size);
  for (const auto& yaml : yamls) {
    std::optional<dispel::slam::GridMap> map;
    try {
      map = dispel::slam::read_map_yaml(yaml);
    } catch (const dispel::jobs::JobError& e) {
      dispel::fuzz::check_message(e.what());
    }
    if (map) map->validate();  // A map the reader accepts is a valid one (else: a finding).
  }
  return 0;
}
