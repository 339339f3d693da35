#pragma once
// For the ROS 2 live tests, whichever DDS the test's own side is built on (Cyclone DDS, or Fast DDS
// in the cross-vendor test): how long a wait may take, the loopback the node is kept on, and
// waiting for what DDS does in its own threads.
#include <chrono>
#include <functional>
#include <thread>

namespace dispel::ros2::live_test {

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

}  // namespace dispel::ros2::live_test
