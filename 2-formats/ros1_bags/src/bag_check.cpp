#include "bag_check.hpp"

#include <bzlib.h>
#include <roslz4/lz4s.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "dispel/io/errors.hpp"
#include "dispel/io/text.hpp"

namespace dispel::io {
namespace {

// The record types of a ROS bag v2.0 (the "op" header field).
constexpr std::uint8_t kMessageData = 0x02;
constexpr std::uint8_t kBagHeader = 0x03;
constexpr std::uint8_t kIndexData = 0x04;
constexpr std::uint8_t kChunk = 0x05;
constexpr std::uint8_t kChunkInfo = 0x06;
constexpr std::uint8_t kConnection = 0x07;

// A record header holds a few short fields (rosbag writes at most about 100 bytes).
constexpr std::uint64_t kMaxHeader = 1 << 20;
// A chunk is decompressed whole, by the bag library and here: its size is bounded (rosbag writes
// chunks of 768 KiB by default).
constexpr std::uint64_t kMaxChunk = std::uint64_t{1} << 30;

std::string bytes(std::uint64_t n) { return std::to_string(n) + (n == 1 ? " byte" : " bytes"); }

// Where the records being read are: the file, or one chunk's decompressed records in memory.
class Source {
 public:
  virtual ~Source() = default;
  virtual std::uint64_t size() const = 0;
  virtual void read(std::uint64_t pos, void* out, std::size_t n) = 0;
  // "record at byte N" (of the file), "record at byte N of the chunk at byte M".
  virtual std::string where(std::uint64_t pos) const = 0;
  virtual std::string end_name() const = 0;
};

class Checker;

struct Record {
  std::uint64_t pos = 0;
  std::uint8_t op = 0;
  std::map<std::string, std::string> fields;
  std::uint64_t data_pos = 0;
  std::uint32_t data_len = 0;
  std::uint64_t end() const { return data_pos + data_len; }
};

class Checker {
 public:
  explicit Checker(const std::string& path) : path_(path) {}

  [[noreturn]] void fail(const Source& src, std::uint64_t pos, const std::string& what) const {
    throw InputError(one_line(path_ + ": corrupt bag: " + src.where(pos) + ": " + what));
  }
  const std::string& path() const { return path_; }

  // The fields of a header (or of a connection record's data): 4-byte length, "name=value".
  std::map<std::string, std::string> fields(const Source& src, std::uint64_t pos,
                                            const std::string& what, const std::string& text) {
    std::map<std::string, std::string> out;
    std::size_t i = 0;
    while (i < text.size()) {
      if (text.size() - i < 4) {
        fail(src, pos, what + ": " + bytes(text.size() - i) + " left over after its last field");
      }
      std::uint32_t len = 0;
      std::memcpy(&len, text.data() + i, 4);
      i += 4;
      if (len > text.size() - i) {
        fail(src, pos,
             what + ": a field of " + bytes(len) + " is longer than the " + bytes(text.size() - i) +
                 " left of it");
      }
      const std::string field = text.substr(i, len);
      i += len;
      const auto eq = field.find('=');
      if (eq == std::string::npos) fail(src, pos, what + ": a field without '=' " + quote(field));
      out[field.substr(0, eq)] = field.substr(eq + 1);
    }
    return out;
  }

  // The record at @p pos of @p src: its header read and checked, its data only located.
  Record record(Source& src, std::uint64_t pos) {
    Record r;
    r.pos = pos;
    const std::uint64_t size = src.size();
    if (size - pos < 8) {
      fail(src, pos,
           "truncated: " + bytes(size - pos) + " left, a record takes at least 8 (" +
               src.end_name() + " has " + bytes(size) + ")");
    }
    std::uint32_t header_len = 0;
    src.read(pos, &header_len, 4);
    if (header_len > size - pos - 8) {
      fail(src, pos,
           "a header of " + bytes(header_len) + " runs past the end (" + src.end_name() + " has " +
               bytes(size) + ")");
    }
    if (header_len > kMaxHeader) {
      fail(src, pos, "a header of " + bytes(header_len) + " (a record header is at most 1 MiB)");
    }
    std::string header(header_len, '\0');
    src.read(pos + 4, header.data(), header_len);
    r.fields = fields(src, pos, "header", header);
    src.read(pos + 4 + header_len, &r.data_len, 4);
    r.data_pos = pos + 8 + header_len;
    if (r.data_len > size - r.data_pos) {
      fail(src, pos,
           "data of " + bytes(r.data_len) + " runs past the end (" + src.end_name() + " has " +
               bytes(size) + ")");
    }
    const auto op = r.fields.find("op");
    if (op == r.fields.end() || op->second.size() != 1) {
      fail(src, pos, "the header has no one-byte 'op' field (the record type)");
    }
    r.op = static_cast<std::uint8_t>(op->second[0]);
    return r;
  }

  template <typename T>
  T field(const Source& src, const Record& r, const std::string& name, const char* kind) {
    const auto it = r.fields.find(name);
    if (it == r.fields.end()) fail(src, r.pos, std::string(kind) + " without a '" + name + "'");
    if (it->second.size() != sizeof(T)) {
      fail(src, r.pos,
           std::string(kind) + ": '" + name + "' has " + bytes(it->second.size()) + ", not " +
               std::to_string(sizeof(T)));
    }
    T value;
    std::memcpy(&value, it->second.data(), sizeof(T));
    return value;
  }

  std::string data(Source& src, const Record& r) {
    std::string d(r.data_len, '\0');
    src.read(r.data_pos, d.data(), d.size());
    return d;
  }

 private:
  std::string path_;
};

class FileSource final : public Source {
 public:
  FileSource(const std::string& path, std::FILE* f, std::uint64_t size)
      : path_(path), f_(f), size_(size) {}
  std::uint64_t size() const override { return size_; }
  void read(std::uint64_t pos, void* out, std::size_t n) override {
    if (n == 0) return;
    if (::fseeko(f_, static_cast<off_t>(pos), SEEK_SET) != 0 || std::fread(out, 1, n, f_) != n) {
      throw InputError(path_ + ": cannot read (" +
                       (std::ferror(f_) ? std::string(std::strerror(errno)) : "file shrank") + ")");
    }
  }
  std::string where(std::uint64_t pos) const override {
    return "record at byte " + std::to_string(pos);
  }
  std::string end_name() const override { return "the file"; }

 private:
  const std::string& path_;
  std::FILE* f_;
  std::uint64_t size_;
};

class ChunkSource final : public Source {
 public:
  ChunkSource(std::vector<char> data, std::uint64_t chunk_pos)
      : data_(std::move(data)), chunk_pos_(chunk_pos) {}
  std::uint64_t size() const override { return data_.size(); }
  void read(std::uint64_t pos, void* out, std::size_t n) override {
    std::memcpy(out, data_.data() + pos, n);  // Callers checked pos + n <= size().
  }
  std::string where(std::uint64_t pos) const override {
    return "record at byte " + std::to_string(pos) + " of the chunk at byte " +
           std::to_string(chunk_pos_);
  }
  std::string end_name() const override { return "the chunk"; }

 private:
  std::vector<char> data_;
  std::uint64_t chunk_pos_;
};

struct Chunk {
  std::map<std::uint32_t, std::uint32_t> messages;  // Offset of each message record: its conn.
  std::map<std::uint32_t, std::uint32_t> indexed;   // Index data records after it: conn, count.
};

// A chunk's records (decompressed): connections and messages, every message's offset kept.
Chunk check_chunk(Checker& c, FileSource& file, const Record& r) {
  const auto compression = r.fields.count("compression") ? r.fields.at("compression") : "";
  const auto size = c.field<std::uint32_t>(file, r, "size", "chunk");
  if (compression != "none" && compression != "lz4" && compression != "bz2") {
    c.fail(file, r.pos, "chunk compressed with unknown " + quote(compression));
  }
  if (size > kMaxChunk) {
    c.fail(file, r.pos,
           "chunk of " + bytes(size) +
               " uncompressed (a chunk is at most 1 GiB; rosbag writes 768 KiB)");
  }
  // LZ4 expands a byte of its data into at most 255: a chunk that states more than 256 times its
  // data cannot hold it (a few bytes that stated 1 GiB had it allocated and zeroed first).
  if (compression == "lz4" && size > 256 * std::uint64_t{r.data_len} + 64) {
    c.fail(file, r.pos,
           "lz4 chunk of " + bytes(r.data_len) + " states " + bytes(size) +
               " uncompressed (lz4 expands at most 255 times)");
  }
  if (compression == "none" && size != r.data_len) {
    c.fail(file, r.pos, "uncompressed chunk of " + bytes(size) + " holds " + bytes(r.data_len));
  }
  std::vector<char> records(size);
  if (compression == "none") {
    file.read(r.data_pos, records.data(), size);
  } else {
    if (r.data_len > kMaxChunk) {
      c.fail(file, r.pos, "compressed chunk of " + bytes(r.data_len) + " (at most 1 GiB)");
    }
    std::vector<char> packed(r.data_len);
    file.read(r.data_pos, packed.data(), packed.size());
    bool ok = false;
    if (compression == "lz4") {
      unsigned int out = size;
      ok = roslz4_buffToBuffDecompress(packed.data(), r.data_len, records.data(), &out) ==
               ROSLZ4_OK &&
           out == size;
    } else {
      unsigned int out = size;
      ok = BZ2_bzBuffToBuffDecompress(records.data(), &out, packed.data(), r.data_len, 0, 0) ==
               BZ_OK &&
           out == size;
    }
    if (!ok) {
      c.fail(file, r.pos,
             compression + " chunk does not decompress to the " + bytes(size) + " it states");
    }
  }
  Chunk chunk;
  ChunkSource src(std::move(records), r.pos);
  std::uint64_t pos = 0;
  while (pos < src.size()) {
    const Record m = c.record(src, pos);
    if (m.op == kMessageData) {
      const auto conn = c.field<std::uint32_t>(src, m, "conn", "message data");
      c.field<std::uint64_t>(src, m, "time", "message data");
      chunk.messages[static_cast<std::uint32_t>(pos)] = conn;
    } else if (m.op == kConnection) {
      c.field<std::uint32_t>(src, m, "conn", "connection");
      if (!m.fields.count("topic")) c.fail(src, pos, "connection without a 'topic'");
      c.fields(src, pos, "connection header", c.data(src, m));
    } else {
      c.fail(src, pos, "record of type " + std::to_string(m.op) + " inside a chunk");
    }
    pos = m.end();
  }
  return chunk;
}

// Walks a serialised ROS 1 message: every length checked against the bytes left.
class MessageWalker {
 public:
  MessageWalker(const std::string& what, const std::uint8_t* data, std::size_t size)
      : what_(what), data_(data), size_(size) {}

  void skip(std::uint64_t n, const char* field) {
    if (n > left()) {
      throw InputError(one_line(what_ + ": " + field + " of " + bytes(n) +
                                " runs past the end of the message (" + bytes(left()) + " left)"));
    }
    pos_ += static_cast<std::size_t>(n);
  }
  std::uint32_t length(const char* field) {
    if (left() < 4) skip(4, field);
    std::uint32_t n = 0;
    std::memcpy(&n, data_ + pos_, 4);
    pos_ += 4;
    return n;
  }
  void string(const char* field) { skip(length(field), field); }
  void header() {
    skip(12, "a header's seq and stamp");
    string("a header's frame_id");
  }
  // An array of @p count values of @p value_size bytes each (its length read first).
  void array(std::uint64_t value_size, const char* field) {
    const std::uint64_t n = length(field);
    if (n * value_size > left()) {
      throw InputError(one_line(what_ + ": an array of " + std::to_string(n) + " " +
                                std::to_string(value_size) + "-byte values (" + field +
                                ") runs past the end of the message (" + bytes(left()) + " left)"));
    }
    pos_ += static_cast<std::size_t>(n * value_size);
  }
  // The length of an array of values of at least @p min_size bytes each, checked.
  std::uint32_t count(std::uint64_t min_size, const char* field) {
    const std::uint32_t n = length(field);
    if (n * min_size > left()) {
      throw InputError(one_line(what_ + ": an array of " + std::to_string(n) + " " + field +
                                " (at least " + bytes(min_size) +
                                " each) runs past the end of the message (" + bytes(left()) +
                                " left)"));
    }
    return n;
  }

 private:
  std::uint64_t left() const { return size_ - pos_; }
  const std::string& what_;
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

}  // namespace

void check_message_lengths(const std::string& path, const std::string& topic, Stamp time,
                           MessageKind kind, const std::uint8_t* data, std::size_t size) {
  char at[48];
  std::snprintf(at, sizeof at, "%lld.%09u s", static_cast<long long>(time.sec), time.nsec);
  const std::string what = path + ": corrupt bag: message at " + at + " on " + quote(topic) + " (" +
                           message_kind_name(kind) + ")";
  MessageWalker w(what, data, size);
  constexpr std::uint64_t kDouble = 8;
  switch (kind) {
    case MessageKind::kLaserScan:
      w.header();
      w.skip(7 * 4, "the angles, times and range limits");
      w.array(4, "ranges");
      w.array(4, "intensities");
      break;
    case MessageKind::kOdometry:
      w.header();
      w.string("child_frame_id");
      w.skip((7 + 36 + 6 + 36) * kDouble, "the pose and twist with their covariances");
      break;
    case MessageKind::kTransforms: {
      // A TransformStamped: a header (at least 16 bytes), child_frame_id (at least 4), 7 doubles.
      const std::uint32_t n = w.count(16 + 4 + 7 * kDouble, "transforms");
      for (std::uint32_t i = 0; i < n; ++i) {
        w.header();
        w.string("child_frame_id");
        w.skip(7 * kDouble, "a transform");
      }
      break;
    }
    case MessageKind::kJointState: {
      w.header();
      const std::uint32_t n = w.count(4, "joint names");
      for (std::uint32_t i = 0; i < n; ++i) w.string("a joint name");
      w.array(kDouble, "position");
      w.array(kDouble, "velocity");
      w.array(kDouble, "effort");
      break;
    }
    case MessageKind::kImu:
      w.header();
      w.skip((4 + 9 + 3 + 9 + 3 + 9) * kDouble, "the orientation, rates and accelerations");
      break;
    case MessageKind::kNavSatFix:
      w.header();
      w.skip(1 + 2 + (3 + 9) * kDouble + 1, "the status, position and covariance");
      break;
    case MessageKind::kOther:
      break;  // Never decoded.
  }
}

void check_bag_structure(const std::string& path) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) return;  // The bag library says why it cannot be opened.
  // The version line, read as the bag library reads it (fgets of at most 1023 bytes, then sscanf
  // "#ROS%99s V%d.%d", the version major * 100 + minor in its int): "#ROSBAGZZZ V2.0" is a bag v2.0
  // to it, whose records start after that line (fuzzing: such a line skipped this check when it
  // wanted "#ROSBAG V2.0" exactly, and the bag library read past a buffer).
  char line[1024];
  if (std::fgets(line, sizeof line, f.get()) == nullptr) return;
  char name[100];
  int major = 0;
  int minor = 0;
  if (std::sscanf(line, "#ROS%99s V%d.%d", name, &major, &minor) != 3) {
    return;  // Not a bag: the bag library names what it is not.
  }
  const auto version = static_cast<std::uint32_t>(major) * 100U + static_cast<std::uint32_t>(minor);
  // Format 1.2 (ROS before 2010): the bag library reads it without checking a length or an offset
  // (a crafted header length of 3.75 GiB was allocated) and it is not checked here: refused.
  if (version == 102) {
    throw InputError(one_line(path + ": a ROS bag of format 1.2 (before 2010) is not read; " +
                              "convert it to format 2.0: rosbag filter " + path + " new.bag True"));
  }
  if (version != 200) return;  // The bag library names the version it does not read.
  const auto first_record = static_cast<std::uint64_t>(::ftello(f.get()));
  if (::fseeko(f.get(), 0, SEEK_END) != 0) return;
  const auto size = static_cast<std::uint64_t>(::ftello(f.get()));
  FileSource file(path, f.get(), size);
  Checker c(path);

  const Record header = c.record(file, first_record);
  if (header.op != kBagHeader) {
    c.fail(file, header.pos,
           "the first record is of type " + std::to_string(header.op) + ", not the bag header (3)");
  }
  // An encrypted bag would have the bag library run GnuPG for its key: not read.
  const auto encryptor = header.fields.find("encryptor");
  if (encryptor != header.fields.end() && encryptor->second != "rosbag/NoEncryptor") {
    throw InputError(one_line(path + ": an encrypted bag (encryptor " + quote(encryptor->second) +
                              ") is not read; decrypt it first: rosbag decrypt " + path));
  }
  const auto index_pos = c.field<std::uint64_t>(file, header, "index_pos", "bag header");
  const auto conn_count = c.field<std::uint32_t>(file, header, "conn_count", "bag header");
  const auto chunk_count = c.field<std::uint32_t>(file, header, "chunk_count", "bag header");
  if (index_pos == 0) {
    c.fail(file, header.pos,
           "the bag has no index (it was not closed; `rosbag reindex` rebuilds it)");
  }
  if (index_pos < header.end() || index_pos > size) {
    c.fail(file, header.pos,
           "the index at byte " + std::to_string(index_pos) + " is outside the file's records (" +
               std::to_string(header.end()) + " to " + std::to_string(size) + ")");
  }

  std::map<std::uint64_t, Chunk> chunks;
  Chunk* last_chunk = nullptr;
  std::set<std::uint32_t> connections;  // Those of the index (after index_pos).
  std::set<std::uint64_t> described;    // Chunks with a chunk info.
  std::vector<std::uint8_t> index_ops;  // The record types from index_pos on.
  bool index_found = index_pos == size;
  std::uint64_t pos = header.end();
  while (pos < size) {
    const Record r = c.record(file, pos);
    if (pos == index_pos) index_found = true;
    if (pos > index_pos && !index_found) {
      c.fail(file, header.pos,
             "the index at byte " + std::to_string(index_pos) + " is not at a record's start");
    }
    const bool in_index = index_found;
    if (in_index) index_ops.push_back(r.op);
    switch (r.op) {
      case kChunk:
        if (in_index) c.fail(file, pos, "chunk after the index");
        last_chunk = &(chunks[pos] = check_chunk(c, file, r));
        break;
      case kIndexData: {
        const auto ver = c.field<std::uint32_t>(file, r, "ver", "index data");
        const auto conn = c.field<std::uint32_t>(file, r, "conn", "index data");
        const auto count = c.field<std::uint32_t>(file, r, "count", "index data");
        if (ver != 1) c.fail(file, pos, "index data of version " + std::to_string(ver) + ", not 1");
        if (std::uint64_t{count} * 12 != r.data_len) {
          c.fail(file, pos,
                 "index data of " + std::to_string(count) + " entries holds " + bytes(r.data_len) +
                     ", not " + std::to_string(std::uint64_t{count} * 12));
        }
        if (last_chunk == nullptr || in_index) c.fail(file, pos, "index data not after a chunk");
        if (!last_chunk->indexed.emplace(conn, count).second) {
          c.fail(file, pos, "a second index data of connection " + std::to_string(conn));
        }
        const std::string entries = c.data(file, r);
        for (std::uint32_t i = 0; i < count; ++i) {
          std::uint32_t offset = 0;
          std::memcpy(&offset, entries.data() + 12 * i + 8, 4);
          const auto m = last_chunk->messages.find(offset);
          if (m == last_chunk->messages.end() || m->second != conn) {
            c.fail(file, pos,
                   "index entry " + std::to_string(i) + " points at byte " +
                       std::to_string(offset) + " of its chunk, not at a message of connection " +
                       std::to_string(conn));
          }
        }
        break;
      }
      case kConnection:
        if (in_index) connections.insert(c.field<std::uint32_t>(file, r, "conn", "connection"));
        c.field<std::uint32_t>(file, r, "conn", "connection");
        if (!r.fields.count("topic")) c.fail(file, pos, "connection without a 'topic'");
        c.fields(file, pos, "connection header", c.data(file, r));
        break;
      case kChunkInfo: {
        const auto ver = c.field<std::uint32_t>(file, r, "ver", "chunk info");
        const auto chunk_pos = c.field<std::uint64_t>(file, r, "chunk_pos", "chunk info");
        c.field<std::uint64_t>(file, r, "start_time", "chunk info");
        c.field<std::uint64_t>(file, r, "end_time", "chunk info");
        const auto count = c.field<std::uint32_t>(file, r, "count", "chunk info");
        if (ver != 1) c.fail(file, pos, "chunk info of version " + std::to_string(ver) + ", not 1");
        if (std::uint64_t{count} * 8 != r.data_len) {
          c.fail(
              file, pos,
              "chunk info of " + std::to_string(count) + " connections holds " + bytes(r.data_len));
        }
        const auto chunk = chunks.find(chunk_pos);
        if (chunk == chunks.end()) {
          c.fail(file, pos, "chunk info for byte " + std::to_string(chunk_pos) + ", not a chunk");
        }
        if (!described.insert(chunk_pos).second) {
          c.fail(file, pos,
                 "a second chunk info for the chunk at byte " + std::to_string(chunk_pos));
        }
        const std::string entries = c.data(file, r);
        std::map<std::uint32_t, std::uint32_t> counts;
        for (std::uint32_t i = 0; i < count; ++i) {
          std::uint32_t conn = 0, n = 0;
          std::memcpy(&conn, entries.data() + 8 * i, 4);
          std::memcpy(&n, entries.data() + 8 * i + 4, 4);
          counts[conn] = n;
        }
        if (counts != chunk->second.indexed) {
          c.fail(file, pos,
                 "chunk info for the chunk at byte " + std::to_string(chunk_pos) +
                     " does not match the index data after it");
        }
        break;
      }
      case kMessageData:
        break;  // Not in a bag v2.0 outside a chunk; the bag library never reads it.
      case kBagHeader:
        c.fail(file, pos, "a second bag header");
      default:
        c.fail(file, pos, "record of unknown type " + std::to_string(r.op));
    }
    pos = r.end();
  }
  if (!index_found) {
    c.fail(file, header.pos,
           "the index at byte " + std::to_string(index_pos) + " is not at a record's start");
  }
  // The bag library reads conn_count connections from index_pos, then chunk_count chunk infos.
  const std::uint64_t expected = std::uint64_t{conn_count} + chunk_count;
  bool as_stated = index_ops.size() >= expected;
  for (std::size_t i = 0; as_stated && i < expected; ++i) {
    as_stated = index_ops[i] == (i < conn_count ? kConnection : kChunkInfo);
  }
  if (!as_stated || described.size() != chunks.size()) {
    c.fail(file, header.pos,
           "the bag header states " + std::to_string(conn_count) + " connections and " +
               std::to_string(chunk_count) + " chunks in its index; the file has " +
               std::to_string(connections.size()) + " and " + std::to_string(described.size()) +
               " of " + std::to_string(chunks.size()) + " chunks");
  }
  for (const auto& [chunk_pos, chunk] : chunks) {
    for (const auto& [conn, count] : chunk.indexed) {
      if (!connections.count(conn)) {
        c.fail(file, chunk_pos,
               "chunk indexes messages of connection " + std::to_string(conn) +
                   ", which the index does not list");
      }
    }
  }
}

}  // namespace dispel::io
