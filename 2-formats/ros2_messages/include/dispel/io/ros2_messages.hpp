#pragma once
/// @file
/// ROS 2 messages in their wire form, to and from the recording model (recording.hpp): CDR as
/// ROS 2 serialises it (XCDR1, "plain CDR": a 4-byte encapsulation header, then the fields with
/// each primitive aligned to its size from the end of that header), for the types dispel reads
/// and writes. Reads little- and big-endian; writes little-endian, as every ROS 2 middleware
/// does. No middleware and no bag library: a recording format and a live node can both use it.
///
/// The types follow ROS 2's common_interfaces (Humble to Kilted: the fields of these types did
/// not change): builtin_interfaces/msg/Time is int32 sec and uint32 nanosec, std_msgs/msg/Header
/// has no seq. See docs/rosbag2.md.

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "dispel/io/recording.hpp"
#include "dispel/pipeline/node_diagnostics.hpp"

namespace dispel::io {

/// A message that cannot be decoded: cut short, an unknown encapsulation, a length beyond the
/// data. what() names the problem and the byte; the caller adds the file and topic.
class CdrError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The ROS 2 type name of @p kind ("sensor_msgs/msg/LaserScan"); nullptr for kOther.
const char* ros2_type_name(MessageKind kind);
/// The kind of a ROS 2 type name; kOther for any other type.
MessageKind ros2_message_kind(const std::string& type_name);
/// The type's definition as rosbag2 stores it (schema encoding "ros2msg"): the .msg text, then
/// each type it uses after a line of 80 '=' and "MSG: pkg/msg/Type". Empty for kOther.
const std::string& ros2_definition(MessageKind kind);

/// A stamp in ROS 2's range (int32 seconds): clamped to it, as ROS 1's writer clamps to its own.
Stamp ros2_clamped(const Stamp& stamp);

/// Decodes one serialised message (with its encapsulation header). @throws CdrError
ScanMessage decode_ros2_scan(const std::uint8_t* data, std::size_t size);
OdometryMessage decode_ros2_odometry(const std::uint8_t* data, std::size_t size);
TransformsMessage decode_ros2_transforms(const std::uint8_t* data, std::size_t size);
JointStateMessage decode_ros2_joint_state(const std::uint8_t* data, std::size_t size);
ImuMessage decode_ros2_imu(const std::uint8_t* data, std::size_t size);
NavSatFixMessage decode_ros2_nav_sat_fix(const std::uint8_t* data, std::size_t size);
/// rosgraph_msgs/Clock (what a node under use_sim_time takes ROS time from): its time.
Stamp decode_ros2_clock(const std::uint8_t* data, std::size_t size);

/// Encodes a message, little-endian CDR with its encapsulation header. The fields the recording
/// model does not keep are written as ROS 1's writer writes them: zero (the covariances of an Imu,
/// z, roll, pitch, efforts), and an Imu without orientation says so in
/// orientation_covariance[0] = -1. An Odometry's covariances are kept whole.
std::vector<std::uint8_t> encode_ros2(const ScanMessage& message);
std::vector<std::uint8_t> encode_ros2(const OdometryMessage& message);
std::vector<std::uint8_t> encode_ros2(const TransformsMessage& message);
std::vector<std::uint8_t> encode_ros2(const JointStateMessage& message);
std::vector<std::uint8_t> encode_ros2(const ImuMessage& message);
/// diagnostic_msgs/DiagnosticArray: @p status stamped @p stamp (frame_id empty), as the nodes
/// publish it on /diagnostics.
std::vector<std::uint8_t> encode_ros2_diagnostics(
    const Stamp& stamp, const std::vector<pipeline::DiagnosticStatus>& status);

}  // namespace dispel::io
