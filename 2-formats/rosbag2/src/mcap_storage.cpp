// rosbag2's MCAP storage (storage.hpp) over dispel's own MCAP code (mcap.hpp): a topic is a
// channel, its type and definition the channel's schema.

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <map>

#include "dispel/io/errors.hpp"
#include "dispel/io/text.hpp"
#include "storage.hpp"

namespace dispel::io::rosbag2 {
namespace {

class McapReader final : public StorageReader {
 public:
  explicit McapReader(const std::string& path) : file_(path) {
    if (file_.profile() != "ros2") {
      throw InputError(one_line(path + ": an MCAP file of profile " + quote(file_.profile()) +
                                    ", not a ROS 2 recording (profile \"ros2\")",
                                400));
    }
    for (const auto& [id, c] : file_.channels()) {
      const auto s = file_.schemas().find(c.schema_id);
      StoredTopic t{c.topic, "", c.message_encoding,  c.metadata,
                    "",      {}, MessageKind::kOther, file_.messages(id)};
      if (s != file_.schemas().end()) {
        t.type = s->second.name;
        t.definition_encoding = s->second.encoding;
        t.definition = s->second.data;
      }
      index_[id] = topics_.size();
      topics_.push_back(std::move(t));
    }
    if (total_messages() > 0) {
      start_ns_ = file_.start_time();
      end_ns_ = file_.end_time();
    }
  }

  void read(const std::function<bool(std::size_t)>& wanted,
            const std::function<void(std::size_t, std::uint64_t, const std::uint8_t*, std::size_t)>&
                visit) override {
    // A channel the summary did not list (defined only inside a chunk) has no topic here: its
    // messages are not given.
    file_.read(
        [&](std::uint16_t id) {
          const auto it = index_.find(id);
          return it != index_.end() && wanted(it->second);
        },
        [&](const mcap::MessageView& m) {
          visit(index_.at(m.channel_id), m.log_time, m.data, m.size);
        });
  }

 private:
  mcap::Reader file_;
  std::map<std::uint16_t, std::size_t> index_;  // Channel id to topic index.
};

class McapWriter final : public StorageWriter {
 public:
  McapWriter(const std::string& file, const std::string& name, mcap::Compression compression)
      : name_(name), out_(std::fopen(file.c_str(), "wb")) {
    if (out_ == nullptr) failed();
    try {
      mcap_ = std::make_unique<mcap::Writer>(out_, name, "ros2", compression);
    } catch (...) {  // The destructor does not run for a constructor that throws.
      std::fclose(out_);
      throw;
    }
  }
  ~McapWriter() override {
    mcap_.reset();
    if (out_ != nullptr) std::fclose(out_);
  }

  std::size_t add_topic(const StoredTopic& t) override {
    const std::string key = t.type + '\n' + t.definition_encoding + '\n' +
                            std::string(t.definition.begin(), t.definition.end());
    auto s = schema_ids_.find(key);
    if (s == schema_ids_.end()) {
      s = schema_ids_.emplace(key, mcap_->add_schema(t.type, t.definition_encoding, t.definition))
              .first;
    }
    channels_.push_back(mcap_->add_channel(s->second, t.name, t.serialization_format, t.metadata));
    return channels_.size() - 1;
  }

  void write(std::size_t topic, std::uint64_t ns, const std::uint8_t* data,
             std::size_t size) override {
    mcap_->write(channels_.at(topic), ns, ns, data, size);
  }

  void finish(const std::string& /*metadata*/, int /*metadata_version*/) override {
    mcap_->finish();
    const int closed = std::fclose(out_);
    out_ = nullptr;
    if (closed != 0) failed();
  }

 private:
  [[noreturn]] void failed() const {
    throw OutputError(name_ + ": cannot write (" + std::strerror(errno) + ")");
  }

  std::string name_;
  std::FILE* out_ = nullptr;
  std::unique_ptr<mcap::Writer> mcap_;
  std::map<std::string, std::uint16_t> schema_ids_;  // By type, encoding and definition.
  std::vector<std::uint16_t> channels_;              // By topic index.
};

}  // namespace

std::string value_of(const Metadata& metadata, const std::string& key) {
  for (const auto& [k, v] : metadata) {
    if (k == key) return v;
  }
  return "";
}

std::uint64_t StorageReader::total_messages() const {
  std::uint64_t n = 0;
  for (const StoredTopic& t : topics_) n += t.messages;
  return n;
}

std::unique_ptr<StorageReader> open_mcap(const std::string& path) {
  return std::make_unique<McapReader>(path);
}

std::unique_ptr<StorageWriter> create_mcap(const std::string& file, const std::string& name,
                                           mcap::Compression compression) {
  return std::make_unique<McapWriter>(file, name, compression);
}

}  // namespace dispel::io::rosbag2
