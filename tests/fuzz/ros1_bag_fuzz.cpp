// Fuzz target: a ROS 1 bag through dispel's reader (Ros1BagReader: the record structure checked
// by bag_check.cpp, then Debian's bag library), as `dispel filter` and `dispel odom` open one:
// the topics, then every message read and the ones of the kinds dispel understands decoded.
// A bag dispel refuses must be refused with an InputError of one line.

#include <cstddef>
#include <cstdint>

#include "dispel/io/errors.hpp"
#include "dispel/io/ros1_bag.hpp"
#include "fuzz_recording.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = dispel::fuzz::temp_folder().write("input.bag", data, size);
  try {
    dispel::io::Ros1BagReader bag(path);
    volatile std::size_t sink = dispel::fuzz::read_all(bag);
    (void)sink;
  } catch (const dispel::io::InputError& e) {
    dispel::fuzz::check_message(e.what());
  }
  return 0;
}
