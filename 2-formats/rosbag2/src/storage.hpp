#pragma once
// The storage of a rosbag2 recording, one file of it: MCAP (mcap_storage.cpp, over dispel's own
// MCAP code) or sqlite3 (sqlite3_storage.cpp, over Debian's libsqlite3). Rosbag2Reader and
// Rosbag2Writer (rosbag2.cpp) see a file only through these interfaces. Internal to
// dispel::io_rosbag2.

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "dispel/io/recording.hpp"
#include "mcap.hpp"

namespace dispel::io::rosbag2 {

/// Key and value pairs as an MCAP channel holds them: "offered_qos_profiles" (rosbag2's YAML of
/// the publishers' QoS) and "topic_type_hash" (the type's hash, since Jazzy).
using Metadata = std::vector<std::pair<std::string, std::string>>;

/// The value of @p key, or "" when there is none.
std::string value_of(const Metadata& metadata, const std::string& key);

/// A topic of a file.
struct StoredTopic {
  std::string name;
  std::string type;                        ///< "sensor_msgs/msg/LaserScan"; "" without a schema.
  std::string serialization_format;        ///< "cdr".
  Metadata metadata;                       ///< See Metadata.
  std::string definition_encoding;         ///< "ros2msg"; "" when the file holds no definition.
  std::vector<std::uint8_t> definition;    ///< The type's definition (MCAP schema data).
  MessageKind kind = MessageKind::kOther;  ///< Set by the reader.
  std::uint64_t messages = 0;
};

/// A file opened for reading. Errors are InputError "<path>: ...".
class StorageReader {
 public:
  virtual ~StorageReader() = default;
  const std::vector<StoredTopic>& topics() const { return topics_; }
  std::vector<StoredTopic>& topics() { return topics_; }
  /// The receive times of its first and last message, in nanoseconds (0 without messages).
  std::uint64_t start_ns() const { return start_ns_; }
  std::uint64_t end_ns() const { return end_ns_; }
  std::uint64_t total_messages() const;

  /// Calls @p visit for every message of the topics (indexes into topics()) @p wanted says yes
  /// to, in receive-time order (equal times in the order they were written); its bytes are
  /// valid during the visit.
  virtual void read(
      const std::function<bool(std::size_t)>& wanted,
      const std::function<void(std::size_t topic, std::uint64_t ns, const std::uint8_t* data,
                               std::size_t size)>& visit) = 0;

 protected:
  std::vector<StoredTopic> topics_;
  std::uint64_t start_ns_ = 0;
  std::uint64_t end_ns_ = 0;
};

/// A file being written: @p file on disk, errors naming @p name (the path the user gave).
/// Errors are OutputError "<name>: cannot write (...)".
class StorageWriter {
 public:
  virtual ~StorageWriter() = default;
  /// Adds a topic (its name, type, serialization format, metadata and definition); its index.
  virtual std::size_t add_topic(const StoredTopic& topic) = 0;
  virtual void write(std::size_t topic, std::uint64_t ns, const std::uint8_t* data,
                     std::size_t size) = 0;
  /// Completes and closes the file. @p metadata is the bag's metadata (the mapping under
  /// rosbag2_bagfile_information, version @p metadata_version), which sqlite3 files keep too.
  virtual void finish(const std::string& metadata, int metadata_version) = 0;
};

std::unique_ptr<StorageReader> open_mcap(const std::string& path);
std::unique_ptr<StorageReader> open_sqlite3(const std::string& path);
std::unique_ptr<StorageWriter> create_mcap(const std::string& file, const std::string& name,
                                           mcap::Compression compression);
std::unique_ptr<StorageWriter> create_sqlite3(const std::string& file, const std::string& name);

}  // namespace dispel::io::rosbag2
