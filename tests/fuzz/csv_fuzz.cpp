// Fuzz target: a CSV file through dispel's CSV reader, with each set of columns dispel reads:
// wheel speeds (`dispel odom --wheels-csv`: t, v_left, v_right), yaw rates (--imu-csv: t,
// yaw_rate) and trajectories (`dispel eval-trajectory`, --truth-csv: t, x, y, yaw). A file dispel
// refuses must be refused with an InputError of one line.

#include <cstddef>
#include <cstdint>

#include "dispel/io/csv.hpp"
#include "dispel/io/errors.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = dispel::fuzz::temp_folder().write("input.csv", data, size);
  const std::vector<std::vector<std::string>> column_sets = {{"t", "v_left", "v_right"},
                                                             {"t", "yaw_rate"}};
  for (const auto& columns : column_sets) {
    try {
      (void)dispel::io::read_csv(path, columns);
    } catch (const dispel::io::InputError& e) {
      dispel::fuzz::check_message(e.what());
    }
  }
  try {
    (void)dispel::io::read_trajectory_csv(path);
  } catch (const dispel::io::InputError& e) {
    dispel::fuzz::check_message(e.what());
  }
  return 0;
}
