#pragma once
/// @file
/// ROS 2 recordings (rosbag2) in MCAP storage: the recording interfaces of recording.hpp for a
/// bag folder (metadata.yaml and its .mcap files) or a single .mcap file. Messages are CDR
/// (ros2_messages.hpp); the container is read and written by dispel's own MCAP code, checked in
/// the tests against the MCAP reference library (@mcap/core). See docs/rosbag2.md.

#include <memory>
#include <string>

#include "dispel/io/recording.hpp"

namespace dispel::io {

enum class Rosbag2Compression { kNone, kZstd, kLz4 };

/// True when @p path names a rosbag2 recording to read: a folder, or a file ending in .mcap or
/// .db3.
bool is_rosbag2_path(const std::string& path);

class Rosbag2Reader final : public RecordingReader {
 public:
  /// Opens a bag folder (its metadata.yaml names the storage and the files) or one .mcap file.
  /// @throws InputError "<path>: ..." naming the problem: no metadata.yaml, a storage other
  /// than mcap, a corrupt or truncated MCAP file (bad magic, CRC mismatch, a chunk cut short).
  explicit Rosbag2Reader(const std::string& path);
  ~Rosbag2Reader() override;

  const std::string& path() const override;
  std::string format_name() const override { return "rosbag2 (mcap)"; }
  const Topics& topics() const override;
  Stamp begin_time() const override;
  Stamp end_time() const override;
  void read(const std::vector<std::string>& topics,
            const std::function<void(const RecordedMessage&)>& visit) override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

class Rosbag2Writer final : public RecordingWriter {
 public:
  /// Writes @p path: a name ending in .mcap is one MCAP file; any other name is a bag folder
  /// holding <name>_0.mcap and metadata.yaml. Written under "<path>.partial" and renamed when
  /// finished. @throws OutputError "<path>: ..." (a folder that exists already, an unwritable
  /// place)
  Rosbag2Writer(const std::string& path, Rosbag2Compression compression);
  /// Without finish(), nothing is left behind (and nothing is thrown).
  ~Rosbag2Writer() override;

  /// A message of a Rosbag2Reader: its bytes, type definition and QoS metadata are copied. A
  /// message of another format is written decoded (write_decoded).
  void copy(const RecordedMessage& message) override;
  bool can_copy(const RecordedMessage& message) const override;
  void write(const std::string& topic, Stamp time, const ScanMessage& message) override;
  void write(const std::string& topic, Stamp time, const OdometryMessage& message) override;
  void write(const std::string& topic, Stamp time, const TransformsMessage& message) override;
  void write(const std::string& topic, Stamp time, const JointStateMessage& message) override;
  void write(const std::string& topic, Stamp time, const ImuMessage& message) override;
  void finish() override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dispel::io
