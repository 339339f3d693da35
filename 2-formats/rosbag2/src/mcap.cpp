#include "mcap.hpp"

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <queue>

#include "dispel/io/errors.hpp"
#include "dispel/io/text.hpp"

namespace dispel::io::mcap {
namespace {

constexpr std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};

enum Op : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

constexpr std::size_t kRecordHead = 9;   // opcode, uint64 length
constexpr std::size_t kFooterBody = 20;  // summary_start, summary_offset_start, summary_crc

// A little-endian uint64 at @p p (a record's length, after its opcode).
std::uint64_t u64_at(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(p[i]) << (8 * i);
  return v;
}

std::uint32_t crc32_of(std::uint32_t crc, const std::uint8_t* p, std::size_t n) {
  while (n > 0) {
    const uInt step = static_cast<uInt>(std::min<std::size_t>(n, 1U << 30));
    crc = static_cast<std::uint32_t>(::crc32(crc, p, step));
    p += step;
    n -= step;
  }
  return crc;
}

// Reads the fields of one record's body, bounds checked; errors say what was cut short.
class Fields {
 public:
  Fields(const std::uint8_t* p, std::size_t n) : p_(p), n_(n) {}
  template <typename T>
  T num(const char* what) {
    need(sizeof(T), what);
    T v = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i)
      v |= static_cast<T>(static_cast<T>(p_[at_ + i]) << (8 * i));
    at_ += sizeof(T);
    return v;
  }
  std::string str(const char* what) {
    const std::uint32_t len = num<std::uint32_t>(what);
    need(len, what);
    std::string s(reinterpret_cast<const char*>(p_ + at_), len);
    at_ += len;
    return s;
  }
  std::vector<std::uint8_t> bytes32(const char* what) {
    const std::uint32_t len = num<std::uint32_t>(what);
    need(len, what);
    std::vector<std::uint8_t> b(p_ + at_, p_ + at_ + len);
    at_ += len;
    return b;
  }
  // A uint32 byte length, then that many bytes: a sub-reader.
  Fields sub32(const char* what) {
    const std::uint32_t len = num<std::uint32_t>(what);
    need(len, what);
    Fields f(p_ + at_, len);
    at_ += len;
    return f;
  }
  const std::uint8_t* rest(std::size_t* size) {
    *size = n_ - at_;
    const std::uint8_t* r = p_ + at_;
    at_ = n_;
    return r;
  }
  bool done() const { return at_ >= n_; }
  std::size_t at() const { return at_; }

 private:
  void need(std::size_t k, const char* what) const {
    if (k > n_ - at_) throw std::length_error(std::string(what) + " runs past its record");
  }
  const std::uint8_t* p_;
  std::size_t n_;
  std::size_t at_ = 0;
};

// Walks the records of a buffer: opcode, body.
template <typename Fn>
void each_record(const std::uint8_t* p, std::size_t n, Fn&& fn) {
  std::size_t at = 0;
  while (at < n) {
    if (n - at < kRecordHead) throw std::length_error("a record header is cut short");
    const std::uint8_t op = p[at];
    const std::uint64_t len = u64_at(p + at + 1);
    if (len > n - at - kRecordHead) throw std::length_error("a record runs past its end");
    fn(op, Fields(p + at + kRecordHead, static_cast<std::size_t>(len)), at);
    at += kRecordHead + static_cast<std::size_t>(len);
  }
}

Schema parse_schema(Fields f) {
  Schema s;
  s.id = f.num<std::uint16_t>("schema id");
  s.name = f.str("schema name");
  s.encoding = f.str("schema encoding");
  s.data = f.bytes32("schema data");
  return s;
}

Channel parse_channel(Fields f) {
  Channel c;
  c.id = f.num<std::uint16_t>("channel id");
  c.schema_id = f.num<std::uint16_t>("channel schema id");
  c.topic = f.str("channel topic");
  c.message_encoding = f.str("channel message encoding");
  Fields m = f.sub32("channel metadata");
  while (!m.done()) {
    std::string k = m.str("metadata key");
    std::string v = m.str("metadata value");
    c.metadata.emplace_back(std::move(k), std::move(v));
  }
  return c;
}

MessageView parse_message(Fields f) {
  MessageView m;
  m.channel_id = f.num<std::uint16_t>("message channel id");
  m.sequence = f.num<std::uint32_t>("message sequence");
  m.log_time = f.num<std::uint64_t>("message log time");
  m.publish_time = f.num<std::uint64_t>("message publish time");
  m.data = f.rest(&m.size);
  return m;
}

std::string reason() { return std::strerror(errno); }

}  // namespace

const char* compression_name(Compression c) {
  return c == Compression::kZstd ? "zstd" : c == Compression::kLz4 ? "lz4" : "";
}

// ---------------------------------------------------------------------------------------------
// Reader

Reader::Reader(std::string path) : path_(std::move(path)) {
  file_.reset(std::fopen(path_.c_str(), "rb"));
  if (file_ == nullptr) throw InputError(path_ + ": cannot open (" + reason() + ")");
  if (std::fseek(file_.get(), 0, SEEK_END) != 0)
    throw InputError(path_ + ": cannot read (" + reason() + ")");
  const long end = std::ftell(file_.get());
  if (end < 0) throw InputError(path_ + ": cannot read (" + reason() + ")");
  size_ = static_cast<std::uint64_t>(end);
  constexpr std::uint64_t kSmallest = 8 + kRecordHead + kFooterBody + 8;
  if (size_ < 8 || std::memcmp(bytes_at(0, 8, "the magic").data(), kMagic, 8) != 0) {
    throw InputError(path_ + ": not an MCAP file (no MCAP magic at its start)");
  }
  if (size_ < kSmallest ||
      std::memcmp(bytes_at(size_ - 8, 8, "the magic").data(), kMagic, 8) != 0) {
    throw InputError(path_ +
                     ": MCAP file without its end (no footer and closing magic); it is "
                     "truncated or was not closed by its writer");
  }
  const std::uint64_t footer_at = size_ - 8 - kRecordHead - kFooterBody;
  const std::vector<std::uint8_t> footer =
      bytes_at(footer_at, kRecordHead + kFooterBody, "the footer");
  const std::uint64_t footer_len = u64_at(footer.data() + 1);
  if (footer[0] != kFooter || footer_len != kFooterBody)
    corrupt("no footer record before the closing magic");
  Fields ff(footer.data() + kRecordHead, kFooterBody);
  const auto summary_start = ff.num<std::uint64_t>("summary start");
  (void)ff.num<std::uint64_t>("summary offset start");
  const auto summary_crc = ff.num<std::uint32_t>("summary crc");

  // The header record, right after the magic.
  const std::vector<std::uint8_t> head = bytes_at(8, kRecordHead, "the header record");
  const std::uint64_t head_len = u64_at(head.data() + 1);
  if (head[0] != kHeader || footer_at < 8 + kRecordHead || head_len > footer_at - 8 - kRecordHead)
    corrupt("no header record after the magic");
  try {
    const std::vector<std::uint8_t> body = bytes_at(8 + kRecordHead, head_len, "the header record");
    Fields h(body.data(), body.size());
    profile_ = h.str("header profile");
  } catch (const std::length_error& e) {
    corrupt(std::string("the header record: ") + e.what());
  }

  data_end_ = footer_at;
  if (summary_start != 0) {
    if (summary_start < 8 + kRecordHead + head_len || summary_start > footer_at) {
      corrupt("the footer's summary start " + std::to_string(summary_start) +
              " is outside the file");
    }
    data_end_ = summary_start;
    if (summary_crc != 0) {
      const std::vector<std::uint8_t> s =
          bytes_at(summary_start, footer_at - summary_start, "the summary");
      std::uint32_t crc = crc32_of(0, s.data(), s.size());
      crc = crc32_of(crc, footer.data(), kRecordHead + 16);
      if (crc != summary_crc)
        corrupt("the summary's CRC does not match (the file was altered or cut)");
    }
    read_summary(summary_start, footer_at);
  }
  if (!indexed_) scan_data_section();
}

Reader::~Reader() = default;

std::uint64_t Reader::messages(std::uint16_t channel_id) const {
  const auto it = counts_.find(channel_id);
  return it == counts_.end() ? 0 : it->second;
}

void Reader::corrupt(const std::string& what) const {
  throw InputError(one_line(path_ + ": corrupt MCAP file: " + what, 400));
}

std::vector<std::uint8_t> Reader::bytes_at(std::uint64_t offset, std::uint64_t size,
                                           const char* what) {
  if (offset > size_ || size > size_ - offset) {
    corrupt(std::string(what) + " at byte " + std::to_string(offset) +
            " runs past the end of the file");
  }
  std::vector<std::uint8_t> out(static_cast<std::size_t>(size));
  if (std::fseek(file_.get(), static_cast<long>(offset), SEEK_SET) != 0 ||
      (size > 0 && std::fread(out.data(), 1, out.size(), file_.get()) != out.size())) {
    throw InputError(path_ + ": cannot read (" + reason() + ")");
  }
  return out;
}

void Reader::read_summary(std::uint64_t summary_start, std::uint64_t footer_at) {
  const std::vector<std::uint8_t> s =
      bytes_at(summary_start, footer_at - summary_start, "the summary");
  bool have_statistics = false;
  try {
    each_record(s.data(), s.size(), [&](std::uint8_t op, Fields f, std::size_t) {
      if (op == kSchema) {
        Schema x = parse_schema(f);
        schemas_[x.id] = std::move(x);
      } else if (op == kChannel) {
        Channel c = parse_channel(f);
        channels_[c.id] = std::move(c);
      } else if (op == kStatistics) {
        have_statistics = true;
        (void)f.num<std::uint64_t>("message count");
        (void)f.num<std::uint16_t>("schema count");
        (void)f.num<std::uint32_t>("channel count");
        (void)f.num<std::uint32_t>("attachment count");
        (void)f.num<std::uint32_t>("metadata count");
        (void)f.num<std::uint32_t>("chunk count");
        start_time_ = f.num<std::uint64_t>("message start time");
        end_time_ = f.num<std::uint64_t>("message end time");
        Fields m = f.sub32("channel message counts");
        while (!m.done()) {
          const auto id = m.num<std::uint16_t>("channel id");
          counts_[id] = m.num<std::uint64_t>("channel message count");
        }
      } else if (op == kChunkIndex) {
        ChunkIndex c{};
        c.start_time = f.num<std::uint64_t>("chunk start time");
        c.end_time = f.num<std::uint64_t>("chunk end time");
        c.offset = f.num<std::uint64_t>("chunk offset");
        c.length = f.num<std::uint64_t>("chunk length");
        if (c.offset < 8 || c.offset > data_end_ || c.length > data_end_ - c.offset) {
          throw std::length_error("a chunk index points outside the data section (chunk at byte " +
                                  std::to_string(c.offset) + ")");
        }
        chunks_.push_back(c);
      }
    });
  } catch (const std::length_error& e) {
    corrupt(std::string("in the summary: ") + e.what());
  }
  // One index per chunk: a chunk indexed twice is read once.
  std::sort(chunks_.begin(), chunks_.end(),
            [](const ChunkIndex& a, const ChunkIndex& b) { return a.offset < b.offset; });
  chunks_.erase(
      std::unique(chunks_.begin(), chunks_.end(),
                  [](const ChunkIndex& a, const ChunkIndex& b) { return a.offset == b.offset; }),
      chunks_.end());
  // Indexed reading needs the statistics (the counts) and a chunk index for every chunk; a file
  // without statistics is read from its data section (as is one whose messages are outside
  // chunks but whose summary has no chunk index).
  indexed_ = have_statistics && (!chunks_.empty() || start_time_ == 0);
  std::uint64_t total = 0;
  for (const auto& [id, n] : counts_) total += n;
  if (indexed_ && chunks_.empty() && total > 0) indexed_ = false;
  for (const auto& [id, c] : channels_) {
    if (c.schema_id != 0 && schemas_.count(c.schema_id) == 0) {
      corrupt("channel " + std::to_string(id) + " names schema " + std::to_string(c.schema_id) +
              ", which the summary does not have");
    }
  }
}

std::vector<std::uint8_t> Reader::chunk_records(std::uint64_t offset, std::uint64_t length) {
  const std::vector<std::uint8_t> rec = bytes_at(offset, length, "a chunk");
  const std::string at = " (chunk at byte " + std::to_string(offset) + ")";
  if (rec.size() < kRecordHead || rec[0] != kChunk)
    corrupt("no chunk record where the index points" + at);
  Fields f(rec.data() + kRecordHead, rec.size() - kRecordHead);
  std::uint64_t uncompressed_size = 0;
  std::uint32_t uncompressed_crc = 0;
  std::string compression;
  const std::uint8_t* data = nullptr;
  std::uint64_t data_size = 0;
  try {
    (void)f.num<std::uint64_t>("chunk start time");
    (void)f.num<std::uint64_t>("chunk end time");
    uncompressed_size = f.num<std::uint64_t>("chunk uncompressed size");
    uncompressed_crc = f.num<std::uint32_t>("chunk uncompressed crc");
    compression = f.str("chunk compression");
    data_size = f.num<std::uint64_t>("chunk records length");
    std::size_t rest = 0;
    data = f.rest(&rest);
    if (data_size > rest) throw std::length_error("the chunk's records run past its record");
  } catch (const std::length_error& e) {
    corrupt(e.what() + at);
  }
  // A chunk never holds more than 1 GiB here: a larger size is a corrupt field, not a chunk.
  if (uncompressed_size > (1ULL << 30)) {
    corrupt("a chunk of " + std::to_string(uncompressed_size) + " bytes" + at);
  }
  // The size a chunk claims is checked against what its data can hold before anything is
  // allocated: a few bytes must not buy a gigabyte.
  if (compression.empty() && data_size != uncompressed_size) {
    corrupt("an uncompressed chunk's sizes differ" + at);
  }
  if (compression == "zstd" &&
      ZSTD_getFrameContentSize(data, static_cast<std::size_t>(data_size)) != uncompressed_size) {
    corrupt("a zstd chunk's frame does not hold the size the chunk states" + at);
  }
  if (compression == "lz4" && uncompressed_size > 255 * data_size + 64) {  // LZ4's best ratio.
    corrupt("an lz4 chunk states more than its data can hold" + at);
  }
  std::vector<std::uint8_t> out(static_cast<std::size_t>(uncompressed_size));
  if (compression.empty()) {
    std::copy(data, data + data_size, out.begin());
  } else if (compression == "zstd") {
    const std::size_t n =
        ZSTD_decompress(out.data(), out.size(), data, static_cast<std::size_t>(data_size));
    if (ZSTD_isError(n) != 0 || n != out.size()) {
      corrupt(std::string("a zstd chunk does not decompress (") +
              (ZSTD_isError(n) != 0 ? ZSTD_getErrorName(n) : "wrong size") + ")" + at);
    }
  } else if (compression == "lz4") {
    LZ4F_dctx* ctx = nullptr;
    if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION)) != 0) {
      throw InputError(path_ + ": cannot decompress lz4 (no memory)");
    }
    std::size_t done_out = 0;
    std::size_t done_in = 0;
    std::size_t hint = 1;
    while (hint != 0 && done_in < data_size) {
      std::size_t out_n = out.size() - done_out;
      std::size_t in_n = static_cast<std::size_t>(data_size) - done_in;
      hint = LZ4F_decompress(ctx, out.data() + done_out, &out_n, data + done_in, &in_n, nullptr);
      if (LZ4F_isError(hint) != 0) {
        const std::string name = LZ4F_getErrorName(hint);
        LZ4F_freeDecompressionContext(ctx);
        corrupt("an lz4 chunk does not decompress (" + name + ")" + at);
      }
      if (in_n == 0 && out_n == 0) break;
      done_out += out_n;
      done_in += in_n;
    }
    LZ4F_freeDecompressionContext(ctx);
    if (hint != 0 || done_out != out.size()) corrupt("an lz4 chunk is cut short" + at);
  } else {
    corrupt("a chunk compressed with " + quote(compression) + ", which dispel does not read" + at);
  }
  if (uncompressed_crc != 0 && crc32_of(0, out.data(), out.size()) != uncompressed_crc) {
    corrupt("a chunk's CRC does not match" + at);
  }
  return out;
}

void Reader::scan_data_section() {
  // No usable index: walk the data section once for the schemas, channels, counts and times
  // (holding no message).
  counts_.clear();
  start_time_ = 0;
  end_time_ = 0;
  bool first = true;
  read_linear([](std::uint16_t) { return false; }, {},
              [&](const MessageView& m) {
                ++counts_[m.channel_id];
                if (first || m.log_time < start_time_) start_time_ = m.log_time;
                if (first || m.log_time > end_time_) end_time_ = m.log_time;
                first = false;
              });
}

void Reader::take_records(const std::uint8_t* p, std::size_t n, std::uint64_t base,
                          const std::function<void(const MessageView&, std::size_t)>& on_message) {
  try {
    each_record(p, n, [&](std::uint8_t op, Fields f, std::size_t at) {
      if (op == kSchema) {
        Schema s = parse_schema(f);
        schemas_.emplace(s.id, std::move(s));
      } else if (op == kChannel) {
        Channel c = parse_channel(f);
        channels_.emplace(c.id, std::move(c));
      } else if (op == kMessage) {
        const MessageView m = parse_message(f);
        if (channels_.count(m.channel_id) == 0) {
          throw std::length_error("a message on channel " + std::to_string(m.channel_id) +
                                  ", which was not defined before it");
        }
        on_message(m, at);
      } else if (op == kChunk) {
        throw std::length_error("a chunk inside a chunk");
      }
    });
  } catch (const std::length_error& e) {  // The byte named only when there is an error.
    throw std::length_error(e.what() + std::string(" (in the record or chunk at byte ") +
                            std::to_string(base) + ")");
  }
}

void Reader::read_linear(const std::function<bool(std::uint16_t)>& wanted,
                         const std::function<void(const MessageView&)>& visit,
                         const std::function<void(const MessageView&)>& observe) {
  // Messages outside an index are collected, sorted by time (stable) and given in order.
  struct Held {
    MessageView m;
    std::size_t buffer;
  };
  std::vector<std::vector<std::uint8_t>> buffers;
  std::vector<Held> held;
  // A buffer is kept only while it holds a message wanted.
  const auto take = [&](std::uint64_t base) {
    const std::size_t buffer = buffers.size() - 1;
    bool keep = false;
    take_records(buffers.back().data(), buffers.back().size(), base,
                 [&](const MessageView& m, std::size_t) {
                   if (observe) observe(m);
                   if (!wanted(m.channel_id)) return;
                   held.push_back({m, buffer});
                   keep = true;
                 });
    if (!keep) buffers.back() = {};
  };
  std::uint64_t at = 8;
  buffers.reserve(64);
  try {
    while (at < data_end_) {
      const std::vector<std::uint8_t> head = bytes_at(at, kRecordHead, "a record header");
      const std::uint64_t len = u64_at(head.data() + 1);
      // Checked so that nothing wraps: a record head cut by the end of the data section, or a
      // length of nearly 2^64, would otherwise loop for ever.
      if (data_end_ - at < kRecordHead || len > data_end_ - at - kRecordHead) {
        throw std::length_error("a record at byte " + std::to_string(at) +
                                " runs past the data section");
      }
      if (head[0] == kDataEnd) break;
      if (head[0] == kChunk) {
        buffers.push_back(chunk_records(at, kRecordHead + len));
        take(at);
      } else if (head[0] == kSchema || head[0] == kChannel || head[0] == kMessage) {
        buffers.push_back(bytes_at(at, kRecordHead + len, "a record"));
        take(at);
      }
      at += kRecordHead + len;
    }
  } catch (const std::length_error& e) {
    corrupt(e.what());
  }
  std::stable_sort(held.begin(), held.end(),
                   [](const Held& a, const Held& b) { return a.m.log_time < b.m.log_time; });
  for (const Held& h : held) visit(h.m);
}

void Reader::read_indexed(const std::function<bool(std::uint16_t)>& wanted,
                          const std::function<void(const MessageView&)>& visit) {
  std::vector<ChunkIndex> order = chunks_;
  std::stable_sort(order.begin(), order.end(), [](const ChunkIndex& a, const ChunkIndex& b) {
    return a.start_time < b.start_time || (a.start_time == b.start_time && a.offset < b.offset);
  });
  struct Pending {
    std::uint64_t time;
    std::uint64_t offset;  // The chunk's, then the position in it: equal times in file order.
    std::size_t at;
    std::size_t chunk;  // Order of loading: the buffer it points into.
    MessageView m;
  };
  const auto later = [](const Pending& a, const Pending& b) {
    return a.time > b.time ||
           (a.time == b.time && (a.offset > b.offset || (a.offset == b.offset && a.at > b.at)));
  };
  std::priority_queue<Pending, std::vector<Pending>, decltype(later)> pending(later);
  std::map<std::size_t, std::pair<std::vector<std::uint8_t>, std::size_t>> loaded;  // buffer, left
  std::size_t next = 0;
  while (next < order.size() || !pending.empty()) {
    // Load every chunk that may hold a message before the earliest pending one.
    while (next < order.size() &&
           (pending.empty() || order[next].start_time <= pending.top().time)) {
      std::vector<std::uint8_t> records = chunk_records(order[next].offset, order[next].length);
      std::size_t count = 0;
      const std::size_t slot = next;
      try {
        take_records(records.data(), records.size(), order[next].offset,
                     [&](const MessageView& m, std::size_t at) {
                       if (!wanted(m.channel_id)) return;
                       pending.push({m.log_time, order[next].offset, at, slot, m});
                       ++count;
                     });
      } catch (const std::length_error& e) {
        corrupt(e.what());
      }
      // The views point into the buffer: move it into place without reallocating its data.
      if (count > 0) loaded.emplace(slot, std::make_pair(std::move(records), count));
      ++next;
    }
    if (pending.empty()) continue;
    const Pending p = pending.top();
    pending.pop();
    visit(p.m);
    auto it = loaded.find(p.chunk);
    if (--it->second.second == 0) loaded.erase(it);
  }
}

void Reader::read(const std::function<bool(std::uint16_t)>& wanted,
                  const std::function<void(const MessageView&)>& visit) {
  if (indexed_) {
    read_indexed(wanted, visit);
  } else {
    read_linear(wanted, visit);
  }
}

// ---------------------------------------------------------------------------------------------
// Writer

namespace {

template <typename T>
void add(std::vector<std::uint8_t>& b, T v) {
  for (std::size_t i = 0; i < sizeof(T); ++i) {
    b.push_back(static_cast<std::uint8_t>(static_cast<std::uint64_t>(v) >> (8 * i)));
  }
}
void add_str(std::vector<std::uint8_t>& b, const std::string& s) {
  add<std::uint32_t>(b, static_cast<std::uint32_t>(s.size()));
  b.insert(b.end(), s.begin(), s.end());
}
// A record: opcode, length, body.
std::vector<std::uint8_t> record(std::uint8_t op, const std::vector<std::uint8_t>& body) {
  std::vector<std::uint8_t> r;
  r.reserve(kRecordHead + body.size());
  r.push_back(op);
  add<std::uint64_t>(r, body.size());
  r.insert(r.end(), body.begin(), body.end());
  return r;
}
std::vector<std::uint8_t> schema_record(const Schema& s) {
  std::vector<std::uint8_t> b;
  add<std::uint16_t>(b, s.id);
  add_str(b, s.name);
  add_str(b, s.encoding);
  add<std::uint32_t>(b, static_cast<std::uint32_t>(s.data.size()));
  b.insert(b.end(), s.data.begin(), s.data.end());
  return record(kSchema, b);
}
std::vector<std::uint8_t> channel_record(const Channel& c) {
  std::vector<std::uint8_t> b;
  add<std::uint16_t>(b, c.id);
  add<std::uint16_t>(b, c.schema_id);
  add_str(b, c.topic);
  add_str(b, c.message_encoding);
  std::vector<std::uint8_t> m;
  for (const auto& [k, v] : c.metadata) {
    add_str(m, k);
    add_str(m, v);
  }
  add<std::uint32_t>(b, static_cast<std::uint32_t>(m.size()));
  b.insert(b.end(), m.begin(), m.end());
  return record(kChannel, b);
}

}  // namespace

struct Writer::Impl {
  std::FILE* out = nullptr;
  std::string name;
  Compression compression = Compression::kNone;
  std::size_t chunk_bytes = 0;
  std::uint64_t written = 0;
  std::uint32_t data_crc = 0;
  std::vector<Schema> schemas;
  std::vector<Channel> channels;
  std::map<std::uint16_t, std::uint64_t> counts;
  std::uint64_t messages = 0;
  std::uint64_t start_time = 0;
  std::uint64_t end_time = 0;
  std::uint32_t chunk_count = 0;
  std::vector<std::uint8_t> chunk;  // Records of the chunk being filled.
  std::uint64_t chunk_start = 0;
  std::uint64_t chunk_end = 0;
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> chunk_index;
  std::vector<std::uint8_t> chunk_indexes;  // Chunk index records, for the summary.
  std::uint32_t chunk_index_records = 0;

  [[noreturn]] void failed() const {
    throw OutputError(name + ": cannot write (" + reason() + ")");
  }

  // Writes bytes; those of the data section count in its CRC (Data End record).
  void put(const std::uint8_t* p, std::size_t n, bool data_section = true) {
    if (n > 0 && std::fwrite(p, 1, n, out) != n) failed();
    if (data_section) data_crc = crc32_of(data_crc, p, n);
    written += n;
  }
  void put(const std::vector<std::uint8_t>& b, bool data_section = true) {
    put(b.data(), b.size(), data_section);
  }

  std::vector<std::uint8_t> compressed() const {
    if (compression == Compression::kZstd) {
      std::vector<std::uint8_t> z(ZSTD_compressBound(chunk.size()));
      const std::size_t n = ZSTD_compress(z.data(), z.size(), chunk.data(), chunk.size(), 3);
      if (ZSTD_isError(n) != 0) {
        throw OutputError(name + ": cannot compress a chunk with zstd (" + ZSTD_getErrorName(n) +
                          ")");
      }
      z.resize(n);
      return z;
    }
    if (compression == Compression::kLz4) {
      std::vector<std::uint8_t> z(LZ4F_compressFrameBound(chunk.size(), nullptr));
      const std::size_t n =
          LZ4F_compressFrame(z.data(), z.size(), chunk.data(), chunk.size(), nullptr);
      if (LZ4F_isError(n) != 0) {
        throw OutputError(name + ": cannot compress a chunk with lz4 (" + LZ4F_getErrorName(n) +
                          ")");
      }
      z.resize(n);
      return z;
    }
    return chunk;
  }

  void flush_chunk() {
    if (chunk.empty()) return;
    const std::uint64_t chunk_at = written;
    const std::vector<std::uint8_t> data = compressed();
    std::vector<std::uint8_t> body;
    body.reserve(data.size() + 64);
    add<std::uint64_t>(body, chunk_start);
    add<std::uint64_t>(body, chunk_end);
    add<std::uint64_t>(body, chunk.size());
    add<std::uint32_t>(body, crc32_of(0, chunk.data(), chunk.size()));
    add_str(body, compression_name(compression));
    add<std::uint64_t>(body, data.size());
    body.insert(body.end(), data.begin(), data.end());
    put(record(kChunk, body));
    const std::uint64_t chunk_length = written - chunk_at;
    // Message indexes, one per channel, in channel order.
    const std::uint64_t indexes_at = written;
    std::vector<std::uint8_t> offsets;
    for (const auto& [channel, entries] : chunk_index) {
      add<std::uint16_t>(offsets, channel);
      add<std::uint64_t>(offsets, written);
      std::vector<std::uint8_t> b;
      add<std::uint16_t>(b, channel);
      add<std::uint32_t>(b, static_cast<std::uint32_t>(entries.size() * 16));
      for (const auto& [time, offset] : entries) {
        add<std::uint64_t>(b, time);
        add<std::uint64_t>(b, offset);
      }
      put(record(kMessageIndex, b));
    }
    std::vector<std::uint8_t> ci;
    add<std::uint64_t>(ci, chunk_start);
    add<std::uint64_t>(ci, chunk_end);
    add<std::uint64_t>(ci, chunk_at);
    add<std::uint64_t>(ci, chunk_length);
    add<std::uint32_t>(ci, static_cast<std::uint32_t>(offsets.size()));
    ci.insert(ci.end(), offsets.begin(), offsets.end());
    add<std::uint64_t>(ci, written - indexes_at);
    add_str(ci, compression_name(compression));
    add<std::uint64_t>(ci, data.size());
    add<std::uint64_t>(ci, chunk.size());
    const std::vector<std::uint8_t> r = record(kChunkIndex, ci);
    chunk_indexes.insert(chunk_indexes.end(), r.begin(), r.end());
    ++chunk_index_records;
    ++chunk_count;
    chunk.clear();
    chunk_index.clear();
  }
};

Writer::Writer(std::FILE* out, std::string name, const std::string& profile,
               Compression compression, std::size_t chunk_bytes)
    : impl_(std::make_unique<Impl>()) {
  impl_->out = out;
  impl_->name = std::move(name);
  impl_->compression = compression;
  impl_->chunk_bytes = chunk_bytes;
  impl_->put(kMagic, 8);
  std::vector<std::uint8_t> h;
  add_str(h, profile);
  add_str(h, "dispel");
  impl_->put(record(kHeader, h));
}

Writer::~Writer() = default;

std::uint16_t Writer::add_schema(const std::string& name, const std::string& encoding,
                                 const std::vector<std::uint8_t>& data) {
  if (impl_->schemas.size() >= 65535) throw OutputError(impl_->name + ": more than 65535 types");
  Schema s{static_cast<std::uint16_t>(impl_->schemas.size() + 1), name, encoding, data};
  impl_->put(schema_record(s));
  impl_->schemas.push_back(std::move(s));
  return impl_->schemas.back().id;
}

std::uint16_t Writer::add_channel(
    std::uint16_t schema_id, const std::string& topic, const std::string& message_encoding,
    const std::vector<std::pair<std::string, std::string>>& metadata) {
  if (impl_->channels.size() >= 65535) throw OutputError(impl_->name + ": more than 65535 topics");
  Channel c{static_cast<std::uint16_t>(impl_->channels.size()), schema_id, topic, message_encoding,
            metadata};
  impl_->put(channel_record(c));
  impl_->channels.push_back(std::move(c));
  return impl_->channels.back().id;
}

void Writer::write(std::uint16_t channel_id, std::uint64_t log_time, std::uint64_t publish_time,
                   const std::uint8_t* data, std::size_t size) {
  Impl& w = *impl_;
  if (w.chunk.empty()) {
    w.chunk_start = log_time;
    w.chunk_end = log_time;
  }
  w.chunk_start = std::min(w.chunk_start, log_time);
  w.chunk_end = std::max(w.chunk_end, log_time);
  w.chunk_index[channel_id].emplace_back(log_time, w.chunk.size());
  w.chunk.push_back(kMessage);
  add<std::uint64_t>(w.chunk, 2 + 4 + 8 + 8 + size);
  add<std::uint16_t>(w.chunk, channel_id);
  add<std::uint32_t>(w.chunk, static_cast<std::uint32_t>(w.counts[channel_id]));
  add<std::uint64_t>(w.chunk, log_time);
  add<std::uint64_t>(w.chunk, publish_time);
  w.chunk.insert(w.chunk.end(), data, data + size);
  if (w.messages == 0 || log_time < w.start_time) w.start_time = log_time;
  if (w.messages == 0 || log_time > w.end_time) w.end_time = log_time;
  ++w.counts[channel_id];
  ++w.messages;
  if (w.chunk.size() >= w.chunk_bytes) w.flush_chunk();
}

void Writer::finish() {
  Impl& w = *impl_;
  w.flush_chunk();
  std::vector<std::uint8_t> end;
  add<std::uint32_t>(end, w.data_crc);
  w.put(record(kDataEnd, end), false);

  // The summary: each group of records, then where each group is (summary offsets), the footer.
  const std::uint64_t summary_start = w.written;
  std::uint32_t crc = 0;
  const auto put_summary = [&](const std::vector<std::uint8_t>& b) {
    crc = crc32_of(crc, b.data(), b.size());
    w.put(b, false);
  };
  std::vector<std::pair<std::uint8_t, std::pair<std::uint64_t, std::uint64_t>>> groups;
  const auto group = [&](std::uint8_t op, const std::vector<std::uint8_t>& records) {
    if (records.empty()) return;
    groups.push_back({op, {w.written, records.size()}});
    put_summary(records);
  };
  std::vector<std::uint8_t> schemas;
  for (const Schema& s : w.schemas) {
    const auto r = schema_record(s);
    schemas.insert(schemas.end(), r.begin(), r.end());
  }
  group(kSchema, schemas);
  std::vector<std::uint8_t> channels;
  for (const Channel& c : w.channels) {
    const auto r = channel_record(c);
    channels.insert(channels.end(), r.begin(), r.end());
  }
  group(kChannel, channels);
  std::vector<std::uint8_t> st;
  add<std::uint64_t>(st, w.messages);
  add<std::uint16_t>(st, static_cast<std::uint16_t>(w.schemas.size()));
  add<std::uint32_t>(st, static_cast<std::uint32_t>(w.channels.size()));
  add<std::uint32_t>(st, 0);  // attachments
  add<std::uint32_t>(st, 0);  // metadata
  add<std::uint32_t>(st, w.chunk_count);
  add<std::uint64_t>(st, w.start_time);
  add<std::uint64_t>(st, w.end_time);
  std::vector<std::uint8_t> counts;
  for (const auto& [id, n] : w.counts) {
    add<std::uint16_t>(counts, id);
    add<std::uint64_t>(counts, n);
  }
  add<std::uint32_t>(st, static_cast<std::uint32_t>(counts.size()));
  st.insert(st.end(), counts.begin(), counts.end());
  group(kStatistics, record(kStatistics, st));
  group(kChunkIndex, w.chunk_indexes);
  const std::uint64_t offsets_start = w.written;
  for (const auto& [op, where] : groups) {
    std::vector<std::uint8_t> b;
    b.push_back(op);
    add<std::uint64_t>(b, where.first);
    add<std::uint64_t>(b, where.second);
    put_summary(record(kSummaryOffset, b));
  }
  std::vector<std::uint8_t> footer;
  footer.push_back(kFooter);
  add<std::uint64_t>(footer, kFooterBody);
  add<std::uint64_t>(footer, summary_start);
  add<std::uint64_t>(footer, offsets_start);
  crc = crc32_of(crc, footer.data(), footer.size());
  add<std::uint32_t>(footer, crc);
  w.put(footer, false);
  w.put(kMagic, 8, false);
  if (std::fflush(w.out) != 0) w.failed();
}

}  // namespace dispel::io::mcap
