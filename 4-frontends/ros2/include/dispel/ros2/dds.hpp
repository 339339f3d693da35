#pragma once
/// @file
/// ROS 2's mapping onto DDS, over Eclipse Cyclone DDS (Debian's cyclonedds-dev, the library of
/// ROS 2's Cyclone RMW), for a process that talks to ROS 2 nodes without a ROS 2 install
/// (docs/ros2.md): topic and type names as ROS 2 mangles them, its QoS profiles, and readers and
/// writers of serialised messages. A sample is a ROS 2 message in CDR with its 4-byte
/// encapsulation header, exactly as rosbag2 stores it: dispel::io's ros2_messages encodes and
/// decodes it (one codec for recordings and the wire). Types are keyless and carried in XCDR1,
/// as rmw_cyclonedds carries them.

#include <array>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

struct ddsi_sertype;  // Cyclone's description of a type (dds/ddsi/ddsi_sertype.h).

namespace dispel::ros2 {

/// A DDS call that failed, or a name or setting DDS or ROS 2 cannot take; the message names it.
class DdsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A QoS as ROS 2's profiles state it (history keep-last; liveliness, deadline and lifespan as
/// DDS's defaults, as in ROS 2's profiles).
struct Qos {
  enum class Reliability { kBestEffort, kReliable };
  enum class Durability { kVolatile, kTransientLocal };
  Reliability reliability = Reliability::kReliable;
  Durability durability = Durability::kVolatile;
  int depth = 10;  ///< Keep last this many.

  /// rmw_qos_profile_sensor_data: best effort, volatile, keep last 5.
  static Qos sensor_data() { return {Reliability::kBestEffort, Durability::kVolatile, 5}; }
  /// rmw_qos_profile_default: reliable, volatile, keep last 10.
  static Qos defaults() { return {Reliability::kReliable, Durability::kVolatile, 10}; }
  /// tf2_ros's static broadcaster: reliable, transient local, keep last 1.
  static Qos tf_static_publisher() {
    return {Reliability::kReliable, Durability::kTransientLocal, 1};
  }
  /// tf2_ros's listener of /tf_static: reliable, transient local, keep last 100.
  static Qos tf_static_subscriber() {
    return {Reliability::kReliable, Durability::kTransientLocal, 100};
  }
};

/// The DDS topic of a ROS 2 topic: "rt" before its absolute name ("/scan" is "rt/scan").
/// @throws DdsError for a name that is not absolute or not a valid ROS 2 name.
std::string dds_topic_name(const std::string& ros_topic);

/// The DDS type of a ROS 2 message type, "pkg/msg/Name" or "pkg/Name":
/// "pkg::msg::dds_::Name_". @throws DdsError for a name of another form.
std::string dds_type_name(const std::string& ros_type);

/// The domain ROS_DOMAIN_ID names, 0 when it is unset or empty. @throws DdsError when it is not
/// an integer from 0 to 232 (the domains DDS's port mapping has room for).
int domain_from_environment();

/// A DDS domain participant, as a ROS 2 context has one: its USER_DATA "enclave=/;" (Humble to
/// Jazzy), so ROS 2's graph takes it for one of its own.
class Participant {
 public:
  /// @throws DdsError when Cyclone cannot make it (a domain out of range, no network).
  explicit Participant(int domain_id);
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  int domain_id() const { return domain_id_; }
  std::int32_t handle() const { return handle_; }
  /// The participant's DDS GUID (what ROS 2's graph calls its gid).
  std::array<std::uint8_t, 16> guid() const;

 private:
  int domain_id_;
  std::int32_t handle_;
};

/// Which end of a topic (for the status counts).
struct Matches {
  int current = 0;       ///< Endpoints of the other end matched now.
  int incompatible = 0;  ///< Endpoints of the other end not matched for their QoS, in all.
  std::string last_incompatible_policy;  ///< The QoS policy that failed last ("" when none).
};

/// A topic by its DDS names, as they go on the wire (ROS 2's own ros_discovery_info has no
/// "rt" prefix).
struct DdsTopic {
  std::string name;  ///< "rt/scan", "ros_discovery_info"
  std::string type;  ///< "sensor_msgs::msg::dds_::LaserScan_"
  /// A ROS 2 topic of a ROS 2 message type, by dds_topic_name() and dds_type_name().
  static DdsTopic ros(const std::string& ros_topic, const std::string& ros_type) {
    return {dds_topic_name(ros_topic), dds_type_name(ros_type)};
  }
};

/// A writer of one ROS 2 topic.
class Writer {
 public:
  /// @throws DdsError (a name, a topic of the same name and another type, a QoS DDS refuses).
  Writer(Participant& participant, const std::string& ros_topic, const std::string& ros_type,
         const Qos& qos)
      : Writer(participant, DdsTopic::ros(ros_topic, ros_type), qos) {}
  Writer(Participant& participant, const DdsTopic& topic, const Qos& qos);
  ~Writer();
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  /// Publishes one message: CDR with its encapsulation header (4 bytes, then the fields).
  /// @throws DdsError when the bytes are not that, or DDS cannot send them.
  void write(const std::vector<std::uint8_t>& cdr);
  /// The readers matched, and those whose QoS this writer cannot offer.
  Matches matches() const;
  std::array<std::uint8_t, 16> guid() const;
  /// The DDS writer (dds_entity_t), for what this class does not wrap.
  std::int32_t handle() const { return writer_; }

 private:
  std::int32_t topic_ = 0, writer_ = 0;
  ::ddsi_sertype* type_ = nullptr;  ///< The topic's, owned by Cyclone.
};

/// A reader of one ROS 2 topic.
class Reader {
 public:
  /// @throws DdsError as Writer's.
  Reader(Participant& participant, const std::string& ros_topic, const std::string& ros_type,
         const Qos& qos)
      : Reader(participant, DdsTopic::ros(ros_topic, ros_type), qos) {}
  Reader(Participant& participant, const DdsTopic& topic, const Qos& qos);
  ~Reader();
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  /// Waits up to @p timeout_s seconds for a message, then takes all there are, oldest first:
  /// each CDR with its encapsulation header. Empty when none came in time.
  std::vector<std::vector<std::uint8_t>> take(double timeout_s);
  /// The writers matched, and those that cannot offer this reader's QoS.
  Matches matches() const;
  std::array<std::uint8_t, 16> guid() const;
  /// The DDS reader (dds_entity_t), for what this class does not wrap.
  std::int32_t handle() const { return reader_; }

 private:
  std::int32_t topic_ = 0, reader_ = 0, waitset_ = 0, condition_ = 0;
};

}  // namespace dispel::ros2
