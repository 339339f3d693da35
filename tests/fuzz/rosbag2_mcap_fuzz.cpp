// Fuzz target: a rosbag2 MCAP file through dispel's reader (Rosbag2Reader: dispel's own MCAP
// container code, then the CDR decoders of io_ros2_messages), as `dispel filter` opens one: the
// topics, then every message read and the ones of the kinds dispel understands decoded. A file
// dispel refuses must be refused with an InputError of one line.

#include <cstddef>
#include <cstdint>

#include "dispel/io/errors.hpp"
#include "dispel/io/rosbag2.hpp"
#include "fuzz_recording.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = dispel::fuzz::temp_folder().write("input.mcap", data, size);
  try {
    dispel::io::Rosbag2Reader bag(path);
    volatile std::size_t sink = dispel::fuzz::read_all(bag);
    (void)sink;
  } catch (const dispel::io::InputError& e) {
    dispel::fuzz::check_message(e.what());
  }
  return 0;
}
