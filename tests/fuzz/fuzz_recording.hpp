#pragma once
// What a fuzz target of a recording reader does with what it opened, as `dispel filter` does:
// the topics and times, then every message read and the ones of the kinds dispel understands
// decoded.

#include <cstddef>

#include "dispel/io/recording.hpp"

namespace dispel::fuzz {

/// Reads all of @p r; returns a number made of what was read (for a sink the compiler keeps).
inline std::size_t read_all(io::RecordingReader& r) {
  using io::MessageKind;
  std::size_t decoded = 0;
  for (const auto& [topic, info] : r.topics().all()) decoded += topic.size() + info.type.size();
  decoded += static_cast<std::size_t>(r.begin_time().sec + r.end_time().sec);
  r.read({}, [&](const io::RecordedMessage& m) {
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
  return decoded;
}

}  // namespace dispel::fuzz
