#pragma once
/// @file
/// ROS 2's graph over DDS: what a participant publishes on `ros_discovery_info` so that ROS 2's
/// tools (`ros2 node list`, `ros2 topic info -v`) see its nodes and which readers and writers are
/// theirs (rmw_dds_common's ParticipantEntitiesInfo, docs/ros2.md).

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "dispel/ros2/dds.hpp"

namespace dispel::ros2 {

/// The size of a gid in ROS 2's graph messages: 24 bytes up to Humble, 16 from Iron on. The two
/// layouts share a type name and do not read each other's samples: a node must use its robot's.
enum class GidLayout { kHumble, kIron };

/// The layout of a ROS 2 distribution by name: "humble" (and older); "iron", "jazzy", "kilted",
/// "rolling". @throws DdsError for another name, listing these.
GidLayout gid_layout_named(const std::string& distribution);

/// A DDS entity's 16-byte GUID, as the graph names it.
using Guid = std::array<std::uint8_t, 16>;

/// One node of a participant: its namespace ("/"), name, and the GUIDs of its readers and
/// writers.
struct NodeEntities {
  std::string name_space = "/";
  std::string name;
  std::vector<Guid> readers;
  std::vector<Guid> writers;
};

/// rmw_dds_common/msg/ParticipantEntitiesInfo in CDR (with its encapsulation header): the
/// participant's gid and its nodes. A gid is the GUID, zero-padded to 24 bytes for Humble.
/// @throws DdsError for a name longer than the message allows (256).
std::vector<std::uint8_t> encode_participant_entities(const Guid& participant,
                                                      const std::vector<NodeEntities>& nodes,
                                                      GidLayout layout);

/// The topic ROS 2's graph goes on: "ros_discovery_info" (no "rt" prefix), of type
/// rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_.
DdsTopic discovery_topic();

/// Its QoS as ROS 2's RMW writes it: reliable, transient local, keep last 1 (each sample is a
/// participant's whole state).
inline Qos discovery_qos() {
  return {Qos::Reliability::kReliable, Qos::Durability::kTransientLocal, 1};
}

}  // namespace dispel::ros2
