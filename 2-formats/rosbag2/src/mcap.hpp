#pragma once
// MCAP files (https://mcap.dev/spec, version 0 of the format), the parts rosbag2 uses: schemas,
// channels, messages, chunks (uncompressed, zstd, lz4 frames) with message indexes, and the
// summary (schemas, channels, statistics, chunk indexes, summary offsets). Attachments and
// metadata records are skipped on read and never written. Internal to dispel::io_rosbag2.

#include <cstdint>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace dispel::io::mcap {

enum class Compression { kNone, kZstd, kLz4 };

/// "", "zstd", "lz4": as chunks name them.
const char* compression_name(Compression c);

struct Schema {
  std::uint16_t id = 0;
  std::string name;
  std::string encoding;
  std::vector<std::uint8_t> data;
};

struct Channel {
  std::uint16_t id = 0;
  std::uint16_t schema_id = 0;
  std::string topic;
  std::string message_encoding;
  std::vector<std::pair<std::string, std::string>> metadata;  ///< In file order.
};

/// A message as read: its bytes are valid during the visit.
struct MessageView {
  std::uint16_t channel_id = 0;
  std::uint32_t sequence = 0;
  std::uint64_t log_time = 0;  ///< Nanoseconds.
  std::uint64_t publish_time = 0;
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
};

/// An MCAP file opened for reading: its structure checked when opened (magic at both ends, the
/// footer, the summary and its CRC, every chunk index within the data section). Errors are
/// io::InputError "<path>: corrupt MCAP file: <what, at which byte>".
class Reader {
 public:
  explicit Reader(std::string path);
  ~Reader();
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  const std::string& profile() const { return profile_; }
  const std::map<std::uint16_t, Schema>& schemas() const { return schemas_; }
  const std::map<std::uint16_t, Channel>& channels() const { return channels_; }
  std::uint64_t messages(std::uint16_t channel_id) const;
  std::uint64_t start_time() const { return start_time_; }
  std::uint64_t end_time() const { return end_time_; }

  /// Calls @p visit for every message of the channels @p wanted says yes to, in log-time order
  /// (equal times in file order). Checks every chunk's CRC when it has one.
  void read(const std::function<bool(std::uint16_t)>& wanted,
            const std::function<void(const MessageView&)>& visit);

 private:
  struct ChunkIndex {
    std::uint64_t start_time, end_time, offset, length;
  };
  void read_summary(std::uint64_t summary_start, std::uint64_t footer_at);
  void scan_data_section();
  std::vector<std::uint8_t> chunk_records(std::uint64_t offset, std::uint64_t length);
  /// The records of a chunk, or one record of the data section, found at byte @p base: schemas
  /// and channels are kept; each message on a channel defined before it goes to @p on_message
  /// with its offset in @p p. @throws std::length_error naming what is wrong and @p base
  void take_records(const std::uint8_t* p, std::size_t n, std::uint64_t base,
                    const std::function<void(const MessageView&, std::size_t)>& on_message);
  void read_indexed(const std::function<bool(std::uint16_t)>& wanted,
                    const std::function<void(const MessageView&)>& visit);
  /// Reads the data section in file order, then gives the wanted messages in time order; each
  /// message, wanted or not, goes to @p observe first when there is one.
  void read_linear(const std::function<bool(std::uint16_t)>& wanted,
                   const std::function<void(const MessageView&)>& visit,
                   const std::function<void(const MessageView&)>& observe = {});
  std::vector<std::uint8_t> bytes_at(std::uint64_t offset, std::uint64_t size, const char* what);
  [[noreturn]] void corrupt(const std::string& what) const;

  std::string path_;
  /// Closed when the reader goes, and when its constructor throws (a member, not the destructor).
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file_{nullptr, &std::fclose};
  std::uint64_t size_ = 0;
  std::uint64_t data_end_ = 0;  ///< Where the data section ends (the summary or the footer).
  std::string profile_;
  std::map<std::uint16_t, Schema> schemas_;
  std::map<std::uint16_t, Channel> channels_;
  std::map<std::uint16_t, std::uint64_t> counts_;
  std::uint64_t start_time_ = 0;
  std::uint64_t end_time_ = 0;
  std::vector<ChunkIndex> chunks_;
  bool indexed_ = false;  ///< Chunk indexes and statistics in the summary: read by them.
};

/// An MCAP file being written to an open stream: chunked, with message indexes, and a summary
/// (schemas, channels, statistics, chunk indexes, summary offsets) when finished. The caller owns
/// the stream and the file's name (see AtomicFile). Errors are io::OutputError naming @p name.
class Writer {
 public:
  Writer(std::FILE* out, std::string name, const std::string& profile, Compression compression,
         std::size_t chunk_bytes = 768 * 1024);
  ~Writer();
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  /// Adds a schema (written at once, before any message that uses it); its id.
  std::uint16_t add_schema(const std::string& name, const std::string& encoding,
                           const std::vector<std::uint8_t>& data);
  std::uint16_t add_channel(std::uint16_t schema_id, const std::string& topic,
                            const std::string& message_encoding,
                            const std::vector<std::pair<std::string, std::string>>& metadata);
  void write(std::uint16_t channel_id, std::uint64_t log_time, std::uint64_t publish_time,
             const std::uint8_t* data, std::size_t size);
  /// Writes the last chunk, the summary and the footer, and flushes.
  void finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dispel::io::mcap
