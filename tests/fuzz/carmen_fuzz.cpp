// Fuzz target: a CARMEN log (FLASER, RLASER, ROBOTLASER1, ODOM lines) through dispel's reader,
// as `dispel filter IN.log` reads one. A log dispel refuses must be refused with an InputError
// of one line; the first malformed line it skips is reported in one line too.

#include <cstddef>
#include <cstdint>

#include "dispel/io/carmen.hpp"
#include "dispel/io/errors.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = dispel::fuzz::temp_folder().write("input.log", data, size);
  try {
    const dispel::io::CarmenLog log = dispel::io::read_carmen_log(path);
    if (!log.first_malformed.empty()) dispel::fuzz::check_message(log.first_malformed.c_str());
  } catch (const dispel::io::InputError& e) {
    dispel::fuzz::check_message(e.what());
  }
  return 0;
}
