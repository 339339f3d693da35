// Fuzz target: a ROS 1 bag through dispel's reader (Ros1BagReader: the record structure checked
// by bag_check.cpp, then Debian's bag library), as `dispel filter` and `dispel odom` open one:
// the topics, then every message read and the ones of the kinds dispel understands decoded.
// A bag dispel refuses must be refused with an InputError of one line.

#include <cstddef>
#include <cstdint>

#include "dispel/io/errors.hpp"
#include "dispel/io/ros1_bag.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using dispel::io::MessageKind;
  const std::string path = dispel::fuzz::temp_folder().write("input.bag", data, size);
  try {
    dispel::io::Ros1BagReader bag(path);
    std::size_t decoded = 0;
    for (const auto& [topic, info] : bag.topics().all()) decoded += topic.size() + info.type.size();
    decoded += static_cast<std::size_t>(bag.begin_time().sec + bag.end_time().sec);
    bag.read({}, [&](const dispel::io::RecordedMessage& m) {
      decoded += static_cast<std::size_t>(m.time().nsec);
      switch (m.kind()) {
        case MessageKind::kLaserScan:
          if (const auto s = m.scan()) decoded += s->scan.ranges_m.size();
          break;
        case MessageKind::kOdometry:
          if (const auto o = m.odometry()) decoded += o->child_frame_id.size();
          break;
        case MessageKind::kTransforms:
          if (const auto t = m.transforms()) decoded += t->transforms.size();
          break;
        case MessageKind::kJointState:
          if (const auto j = m.joint_state()) decoded += j->velocities.size();
          break;
        case MessageKind::kImu:
          if (const auto i = m.imu()) decoded += i->has_orientation ? 1 : 0;
          break;
        case MessageKind::kNavSatFix:
          if (const auto f = m.nav_sat_fix()) decoded += static_cast<std::size_t>(f->status + 1);
          break;
        case MessageKind::kOther:
          break;
      }
    });
    volatile std::size_t sink = decoded;
    (void)sink;
  } catch (const dispel::io::InputError& e) {
    dispel::fuzz::check_message(e.what());
  }
  return 0;
}
