#pragma once
// For the ROS 2 tests: waiting for what DDS does in its own threads, and readers of Cyclone's own
// types (from idlc), the tests' second opinion on dispel's raw CDR.
#include <dds/dds.h>

#include <chrono>
#include <functional>
#include <string>
#include <thread>

#include "dispel/ros2/dds.hpp"

namespace dispel::ros2::cyclone_test {

/// How long a wait may take before the test fails: it bounds how long a failure takes to show,
/// not how long a pass takes (discovery in one process or on the loopback takes milliseconds; a
/// loaded machine may keep a thread waiting for a core for seconds).
constexpr double kWaitS = 20.0;

/// CYCLONEDDS_URI for the live tests: unicast discovery on the loopback (no multicast: CI
/// machines may have none), ports for up to 20 participants; nothing leaves the machine.
constexpr const char* kLoopback =
    "<General><Interfaces><NetworkInterface address=\"127.0.0.1\"/></Interfaces>"
    "<AllowMulticast>false</AllowMulticast></General><Discovery><Peers><Peer "
    "address=\"127.0.0.1\"/></Peers><ParticipantIndex>auto</ParticipantIndex>"
    "<MaxAutoParticipantIndex>20</MaxAutoParticipantIndex></Discovery>";

/// Whether @p condition came true within kWaitS (looked at every 2 ms).
inline bool eventually(const std::function<bool()>& condition) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(kWaitS);
  while (!condition()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return true;
}

/// A reader of Cyclone's type @p descriptor on the DDS topic @p topic: reliable, keep all, and
/// transient local when asked (to get what was written before it). Negative: DDS's error.
inline dds_entity_t typed_reader(const Participant& participant,
                                 const dds_topic_descriptor_t* descriptor, const std::string& topic,
                                 bool transient_local) {
  const dds_entity_t t =
      dds_create_topic(participant.handle(), descriptor, topic.c_str(), nullptr, nullptr);
  if (t < 0) return t;
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  if (transient_local) dds_qset_durability(qos, DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_history(qos, DDS_HISTORY_KEEP_ALL, 0);
  const dds_entity_t r = dds_create_reader(participant.handle(), t, qos, nullptr);
  dds_delete_qos(qos);
  return r;
}

}  // namespace dispel::ros2::cyclone_test
