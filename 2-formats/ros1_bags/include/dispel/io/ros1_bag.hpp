#pragma once
/// @file
/// ROS 1 bags, read and written with the real bag library (Debian's rosbag_storage): the
/// recording interfaces of recording.hpp for the ROS 1 format. The bag library's headers stay in
/// the .cpp; its errors come out as InputError or OutputError naming the file.

#include <memory>
#include <string>

#include "dispel/io/recording.hpp"

namespace dispel::io {

enum class BagCompression { kNone, kBz2, kLz4 };

class Ros1BagReader final : public RecordingReader {
 public:
  /// Opens @p path, its record structure checked first (lengths, offsets, index; see
  /// src/bag_check.hpp): the bag library trusts them and crashed on a corrupt one.
  /// A bag of format 1.2 (before 2010) is refused: the bag library reads it unchecked.
  /// @throws InputError "<path>: corrupt bag: record at byte N: ...",
  ///         "<path>: not a readable ROS 1 bag (...)", "<path>: a ROS bag of format 1.2 ..."
  explicit Ros1BagReader(const std::string& path);
  ~Ros1BagReader() override;

  const std::string& path() const override;
  std::string format_name() const override { return "rosbag"; }
  const Topics& topics() const override;
  Stamp begin_time() const override;
  Stamp end_time() const override;
  /// Errors of the bag library while reading or decoding (a truncated or corrupt bag) become
  /// InputError "<path>: cannot read the recording (...); it may be truncated or corrupt".
  void read(const std::vector<std::string>& topics,
            const std::function<void(const RecordedMessage&)>& visit) override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

class Ros1BagWriter final : public RecordingWriter {
 public:
  /// Starts "<path>.partial" (see AtomicFile). @throws OutputError "<path>: cannot write (...)"
  Ros1BagWriter(const std::string& path, BagCompression compression);
  /// Without finish(), nothing is left behind (and nothing is thrown).
  ~Ros1BagWriter() override;

  /// A message of a Ros1BagReader: its bytes and connection header are copied. A message of
  /// another format is written decoded (write_decoded): OutputError for a kind it cannot decode.
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
