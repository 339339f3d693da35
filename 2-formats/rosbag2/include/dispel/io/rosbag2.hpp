#pragma once
/// @file
/// ROS 2 recordings (rosbag2) in MCAP or sqlite3 storage: the recording interfaces of
/// recording.hpp for a bag folder (metadata.yaml and its .mcap or .db3 files), a single .mcap file
/// or a single .db3 file. Messages are CDR (ros2_messages.hpp); MCAP is read and written by
/// dispel's own code, checked in the tests against the MCAP reference library (@mcap/core);
/// sqlite3 through Debian's libsqlite3. See docs/rosbag2.md.

#include <memory>
#include <string>

#include "dispel/io/recording.hpp"

namespace dispel::io {

enum class Rosbag2Compression { kNone, kZstd, kLz4 };
/// The storage of a bag folder written: MCAP files or sqlite3 databases (rosbag2's storage_id).
enum class Rosbag2Storage { kMcap, kSqlite3 };

/// True when @p path names a rosbag2 recording to read: a folder, or a file ending in .mcap or
/// .db3.
bool is_rosbag2_path(const std::string& path);

class Rosbag2Reader final : public RecordingReader {
 public:
  /// Opens a bag folder (its metadata.yaml names the storage and the files), one .mcap file or
  /// one .db3 file (sqlite3: the schema of every ROS 2 release, from Foxy's to Jazzy's).
  /// @throws InputError "<path>: ..." naming the problem: no metadata.yaml, a storage other
  /// than mcap or sqlite3, a corrupt or truncated MCAP file (bad magic, CRC mismatch, a chunk cut
  /// short), a .db3 file that is not an SQLite database, is corrupt, is locked or lacks
  /// rosbag2's tables.
  explicit Rosbag2Reader(const std::string& path);
  ~Rosbag2Reader() override;

  const std::string& path() const override;
  /// "rosbag2 (mcap)" or "rosbag2 (sqlite3)".
  std::string format_name() const override;
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
  /// Writes @p path: a name ending in .mcap is one MCAP file, one ending in .db3 one sqlite3
  /// file (rosbag2's schema version 4, as Jazzy writes it); any other name is a bag folder
  /// holding metadata.yaml and <name>_0.mcap, or <name>_0.db3 with @p storage kSqlite3. Written
  /// under "<path>.partial" and renamed when finished. @throws OutputError "<path>: ..." (a
  /// folder that exists already, an unwritable place, zstd or lz4 asked of sqlite3 storage)
  Rosbag2Writer(const std::string& path, Rosbag2Compression compression,
                Rosbag2Storage storage = Rosbag2Storage::kMcap);
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
