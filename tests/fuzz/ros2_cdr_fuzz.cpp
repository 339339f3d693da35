// Fuzz target: the CDR decoders of io_ros2_messages, each type on the same bytes (a message as a
// live ROS 2 node or a recording hands it over). A message dispel refuses must be refused with a
// CdrError of one line.

#include <cstddef>
#include <cstdint>

#include "dispel/io/ros2_messages.hpp"
#include "fuzz_support.hpp"

namespace {

template <typename Fn>
std::size_t decoded_by(Fn fn, const std::uint8_t* data, std::size_t size) {
  try {
    const auto message = fn(data, size);  // Called: sizeof(fn(...)) would not call it.
    (void)message;
    return 1;
  } catch (const dispel::io::CdrError& e) {
    dispel::fuzz::check_message(e.what());
    return 0;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace dispel::io;
  std::size_t n = 0;
  n += decoded_by(decode_ros2_scan, data, size);
  n += decoded_by(decode_ros2_odometry, data, size);
  n += decoded_by(decode_ros2_transforms, data, size);
  n += decoded_by(decode_ros2_joint_state, data, size);
  n += decoded_by(decode_ros2_imu, data, size);
  n += decoded_by(decode_ros2_nav_sat_fix, data, size);
  volatile std::size_t sink = n;
  (void)sink;
  return 0;
}
