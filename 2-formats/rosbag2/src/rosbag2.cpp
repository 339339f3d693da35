#include "dispel/io/rosbag2.hpp"

#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <optional>

#include "dispel/io/atomic_file.hpp"
#include "dispel/io/errors.hpp"
#include "dispel/io/ros2_messages.hpp"
#include "dispel/io/text.hpp"
#include "mcap.hpp"

namespace dispel::io {
namespace {

namespace fs = std::filesystem;

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

Stamp stamp_of(std::uint64_t ns) {
  return {static_cast<std::int64_t>(ns / 1000000000ULL),
          static_cast<std::uint32_t>(ns % 1000000000ULL)};
}

std::uint64_t ns_of(const Stamp& s) {
  if (s.sec < 0) return 0;
  return static_cast<std::uint64_t>(s.sec) * 1000000000ULL + s.nsec;
}

// One message of an MCAP file being read.
class Rosbag2Message final : public RecordedMessage {
 public:
  Rosbag2Message(const mcap::MessageView& m, const mcap::Channel& channel,
                 const mcap::Schema* schema, MessageKind kind, const std::string& path)
      : m_(m), channel_(channel), schema_(schema), kind_(kind), path_(path) {}

  const mcap::MessageView& view() const { return m_; }
  const mcap::Channel& channel() const { return channel_; }
  const mcap::Schema* schema() const { return schema_; }

  const std::string& topic() const override { return channel_.topic; }
  MessageKind kind() const override { return kind_; }
  Stamp time() const override { return stamp_of(m_.log_time); }
  std::optional<ScanMessage> scan() const override {
    return decode(MessageKind::kLaserScan, decode_ros2_scan);
  }
  std::optional<OdometryMessage> odometry() const override {
    return decode(MessageKind::kOdometry, decode_ros2_odometry);
  }
  std::optional<TransformsMessage> transforms() const override {
    return decode(MessageKind::kTransforms, decode_ros2_transforms);
  }
  std::optional<JointStateMessage> joint_state() const override {
    return decode(MessageKind::kJointState, decode_ros2_joint_state);
  }
  std::optional<ImuMessage> imu() const override {
    return decode(MessageKind::kImu, decode_ros2_imu);
  }
  std::optional<NavSatFixMessage> nav_sat_fix() const override {
    return decode(MessageKind::kNavSatFix, decode_ros2_nav_sat_fix);
  }

 private:
  template <typename Fn>
  auto decode(MessageKind kind, Fn fn) const -> std::optional<decltype(fn(nullptr, 0))> {
    if (kind != kind_) return std::nullopt;
    try {
      return fn(m_.data, m_.size);
    } catch (const CdrError& e) {
      throw InputError(one_line(path_ + ": topic " + quote(channel_.topic) + ", message at " +
                                    std::to_string(time().seconds()) + " s: cannot decode (" +
                                    e.what() + ")",
                                400));
    }
  }

  const mcap::MessageView& m_;
  const mcap::Channel& channel_;
  const mcap::Schema* schema_;
  MessageKind kind_;
  const std::string& path_;
};

// The kind of a channel: one of the model's types only when its schema is ros2msg and its
// messages are CDR.
MessageKind kind_of(const mcap::Channel& c, const mcap::Schema* s) {
  if (s == nullptr || c.message_encoding != "cdr" || s->encoding != "ros2msg") {
    return MessageKind::kOther;
  }
  return ros2_message_kind(s->name);
}

// The .mcap files of a bag folder, from its metadata.yaml.
std::vector<std::string> files_of_folder(const std::string& folder) {
  const fs::path meta = fs::path(folder) / "metadata.yaml";
  std::error_code ec;
  if (!fs::exists(meta, ec)) {
    throw InputError(folder + ": a folder without metadata.yaml, not a rosbag2 bag folder");
  }
  const std::string text = read_regular_file(meta.string(), "bag metadata file");
  YAML::Node info;
  try {
    info = YAML::Load(text)["rosbag2_bagfile_information"];
  } catch (const YAML::Exception& e) {
    throw InputError(one_line(meta.string() + ": not valid YAML (" + e.what() + ")", 400));
  }
  if (!info || !info.IsMap()) {
    throw InputError(meta.string() + ": no rosbag2_bagfile_information mapping");
  }
  std::vector<std::string> files;
  try {
    const std::string storage =
        info["storage_identifier"] ? info["storage_identifier"].as<std::string>() : "";
    if (storage != "mcap") {
      throw InputError(one_line(meta.string() + ": storage " + quote(storage) +
                                    "; dispel reads rosbag2 bags stored as mcap",
                                400));
    }
    const std::string compression =
        info["compression_format"] ? info["compression_format"].as<std::string>() : "";
    if (!compression.empty()) {
      throw InputError(one_line(meta.string() + ": the bag is compressed file by file (" +
                                    quote(compression) +
                                    "); dispel reads MCAP's own chunk compression only",
                                400));
    }
    const YAML::Node paths = info["relative_file_paths"];
    if (!paths || !paths.IsSequence() || paths.size() == 0) {
      throw InputError(meta.string() + ": relative_file_paths names no file");
    }
    for (const YAML::Node& p : paths) {
      const std::string name = p.as<std::string>();
      if (name.empty() || fs::path(name).is_absolute() || name.find("..") != std::string::npos) {
        throw InputError(one_line(
            meta.string() + ": file " + quote(name) + " is not a name inside the bag folder", 400));
      }
      files.push_back((fs::path(folder) / name).string());
    }
  } catch (const YAML::Exception& e) {
    throw InputError(one_line(meta.string() + ": " + e.what(), 400));
  }
  return files;
}

}  // namespace

bool is_rosbag2_path(const std::string& path) {
  std::error_code ec;
  return ends_with(path, ".mcap") || ends_with(path, ".db3") || fs::is_directory(path, ec);
}

// ---------------------------------------------------------------------------------------------
// Reading

struct Rosbag2Reader::Impl {
  std::string path;
  std::vector<std::unique_ptr<mcap::Reader>> files;
  Topics topics;
  Stamp begin;
  Stamp end;
};

Rosbag2Reader::Rosbag2Reader(const std::string& path) : impl_(std::make_unique<Impl>()) {
  impl_->path = path;
  std::error_code ec;
  std::vector<std::string> names;
  if (fs::is_directory(path, ec)) {
    names = files_of_folder(path);
  } else if (ends_with(path, ".db3")) {
    throw InputError(path +
                     ": a rosbag2 sqlite3 file; this dispel reads rosbag2 bags stored as "
                     "mcap only (convert with `ros2 bag convert`)");
  } else {
    names = {path};
  }
  std::map<std::string, TopicInfo> topics;
  bool first = true;
  for (const std::string& name : names) {
    auto file = std::make_unique<mcap::Reader>(name);
    if (file->profile() != "ros2") {
      throw InputError(one_line(name + ": an MCAP file of profile " + quote(file->profile()) +
                                    ", not a ROS 2 recording (profile \"ros2\")",
                                400));
    }
    for (const auto& [id, c] : file->channels()) {
      const auto s = file->schemas().find(c.schema_id);
      const mcap::Schema* schema = s == file->schemas().end() ? nullptr : &s->second;
      TopicInfo& t = topics[c.topic];
      if (t.type.empty()) {
        t.type = schema != nullptr ? schema->name : std::string("(no schema)");
        t.kind = kind_of(c, schema);
      }
      t.messages += static_cast<std::int64_t>(file->messages(id));
    }
    std::uint64_t total = 0;
    for (const auto& [id, c] : file->channels()) total += file->messages(id);
    if (total > 0) {
      const Stamp b = stamp_of(file->start_time());
      const Stamp e = stamp_of(file->end_time());
      if (first || b < impl_->begin) impl_->begin = b;
      if (first || impl_->end < e) impl_->end = e;
      first = false;
    }
    impl_->files.push_back(std::move(file));
  }
  impl_->topics = Topics(std::move(topics));
}

Rosbag2Reader::~Rosbag2Reader() = default;

const std::string& Rosbag2Reader::path() const { return impl_->path; }
const Topics& Rosbag2Reader::topics() const { return impl_->topics; }
Stamp Rosbag2Reader::begin_time() const { return impl_->begin; }
Stamp Rosbag2Reader::end_time() const { return impl_->end; }

void Rosbag2Reader::read(const std::vector<std::string>& topics,
                         const std::function<void(const RecordedMessage&)>& visit) {
  // The files of a folder follow each other in time (rosbag2 splits a recording in order).
  try {
    for (const auto& file : impl_->files) {
      std::map<std::uint16_t, std::pair<const mcap::Schema*, MessageKind>> kinds;
      for (const auto& [id, c] : file->channels()) {
        const auto s = file->schemas().find(c.schema_id);
        const mcap::Schema* schema = s == file->schemas().end() ? nullptr : &s->second;
        kinds[id] = {schema, kind_of(c, schema)};
      }
      const auto wanted = [&](std::uint16_t id) {
        if (topics.empty()) return true;
        const std::string& topic = file->channels().at(id).topic;
        for (const std::string& t : topics) {
          if (t == topic) return true;
        }
        return false;
      };
      file->read(wanted, [&](const mcap::MessageView& m) {
        const auto k = kinds.find(m.channel_id);
        const mcap::Channel& c = file->channels().at(m.channel_id);
        const Rosbag2Message message(m, c, k == kinds.end() ? nullptr : k->second.first,
                                     k == kinds.end() ? MessageKind::kOther : k->second.second,
                                     impl_->path);
        visit(message);
      });
    }
  } catch (const StopReading&) {
  }
}

// ---------------------------------------------------------------------------------------------
// Writing

namespace {

// The QoS that rosbag2 records for a topic (offered_qos_profiles, its YAML layout of Humble):
// reliable, volatile, keep last 10; /tf_static transient local, keep last 1, as tf2 offers it.
std::string qos_profiles(const std::string& topic) {
  const bool latched = topic == "/tf_static";
  const std::string infinite = "\n    sec: 2147483647\n    nsec: 4294967295";
  return std::string("- history: 1\n  depth: ") + (latched ? "1" : "10") +
         "\n  reliability: 1\n  durability: " + (latched ? "1" : "2") + "\n  deadline:" + infinite +
         "\n  lifespan:" + infinite + "\n  liveliness: 1\n  liveliness_lease_duration:" + infinite +
         "\n  avoid_ros_namespace_conventions: false";
}

}  // namespace

struct Rosbag2Writer::Impl {
  std::string path;
  bool folder = false;
  std::optional<AtomicFile> atomic;  // A single .mcap file.
  std::string temp_folder;           // A bag folder, while it is written.
  std::string file_name;             // The .mcap file inside the folder.
  std::FILE* out = nullptr;
  std::unique_ptr<mcap::Writer> mcap;
  std::map<std::string, std::uint16_t> schema_ids;  // By name + definition.
  struct Topic {
    std::uint16_t channel = 0;
    std::string type;
    std::string qos;
    std::uint64_t messages = 0;
  };
  std::map<std::string, Topic> topics;
  std::uint64_t messages = 0;
  std::uint64_t first_ns = 0;
  std::uint64_t last_ns = 0;
  bool finished = false;

  Topic& topic(const std::string& name, const std::string& type, const std::string& encoding,
               const std::vector<std::uint8_t>& definition,
               const std::vector<std::pair<std::string, std::string>>& metadata) {
    auto it = topics.find(name);
    if (it != topics.end()) {
      if (it->second.type != type) {
        throw OutputError(one_line(path + ": topic " + quote(name) + " written with two types, " +
                                       quote(it->second.type) + " and " + quote(type),
                                   400));
      }
      return it->second;
    }
    const std::string key =
        type + '\n' + encoding + '\n' + std::string(definition.begin(), definition.end());
    auto s = schema_ids.find(key);
    if (s == schema_ids.end()) {
      s = schema_ids.emplace(key, mcap->add_schema(type, encoding, definition)).first;
    }
    std::string qos;
    for (const auto& [k, v] : metadata) {
      if (k == "offered_qos_profiles") qos = v;
    }
    Topic t;
    t.channel = mcap->add_channel(s->second, name, "cdr", metadata);
    t.type = type;
    t.qos = qos;
    return topics.emplace(name, t).first->second;
  }

  void put(Topic& t, Stamp time, const std::vector<std::uint8_t>& data) {
    put(t, ns_of(time), data.data(), data.size());
  }
  void put(Topic& t, std::uint64_t ns, const std::uint8_t* data, std::size_t size) {
    mcap->write(t.channel, ns, ns, data, size);
    if (messages == 0 || ns < first_ns) first_ns = ns;
    if (messages == 0 || ns > last_ns) last_ns = ns;
    ++messages;
    ++t.messages;
  }

  template <typename M>
  void write(const std::string& name, Stamp time, const M& message, MessageKind kind) {
    const std::string& def = ros2_definition(kind);
    Topic& t = topic(name, ros2_type_name(kind), "ros2msg",
                     std::vector<std::uint8_t>(def.begin(), def.end()),
                     {{"offered_qos_profiles", qos_profiles(name)}});
    put(t, time, encode_ros2(message));
  }

  std::string metadata_yaml(const std::string& relative) const {
    YAML::Emitter y;
    y << YAML::BeginMap << YAML::Key << "rosbag2_bagfile_information" << YAML::Value
      << YAML::BeginMap;
    y << YAML::Key << "version" << YAML::Value << 5;
    y << YAML::Key << "storage_identifier" << YAML::Value << "mcap";
    const std::uint64_t duration = messages == 0 ? 0 : last_ns - first_ns;
    y << YAML::Key << "duration" << YAML::Value << YAML::BeginMap << YAML::Key << "nanoseconds"
      << YAML::Value << duration << YAML::EndMap;
    y << YAML::Key << "starting_time" << YAML::Value << YAML::BeginMap << YAML::Key
      << "nanoseconds_since_epoch" << YAML::Value << first_ns << YAML::EndMap;
    y << YAML::Key << "message_count" << YAML::Value << messages;
    y << YAML::Key << "topics_with_message_count" << YAML::Value << YAML::BeginSeq;
    for (const auto& [name, t] : topics) {
      y << YAML::BeginMap << YAML::Key << "topic_metadata" << YAML::Value << YAML::BeginMap;
      y << YAML::Key << "name" << YAML::Value << name;
      y << YAML::Key << "type" << YAML::Value << t.type;
      y << YAML::Key << "serialization_format" << YAML::Value << "cdr";
      y << YAML::Key << "offered_qos_profiles" << YAML::Value << YAML::DoubleQuoted << t.qos;
      y << YAML::EndMap;
      y << YAML::Key << "message_count" << YAML::Value << t.messages << YAML::EndMap;
    }
    y << YAML::EndSeq;
    y << YAML::Key << "compression_format" << YAML::Value << YAML::DoubleQuoted << "";
    y << YAML::Key << "compression_mode" << YAML::Value << YAML::DoubleQuoted << "";
    y << YAML::Key << "relative_file_paths" << YAML::Value << YAML::BeginSeq << relative
      << YAML::EndSeq;
    y << YAML::Key << "files" << YAML::Value << YAML::BeginSeq << YAML::BeginMap;
    y << YAML::Key << "path" << YAML::Value << relative;
    y << YAML::Key << "starting_time" << YAML::Value << YAML::BeginMap << YAML::Key
      << "nanoseconds_since_epoch" << YAML::Value << first_ns << YAML::EndMap;
    y << YAML::Key << "duration" << YAML::Value << YAML::BeginMap << YAML::Key << "nanoseconds"
      << YAML::Value << duration << YAML::EndMap;
    y << YAML::Key << "message_count" << YAML::Value << messages << YAML::EndMap << YAML::EndSeq;
    y << YAML::EndMap << YAML::EndMap;
    return std::string(y.c_str()) + "\n";
  }
};

Rosbag2Writer::Rosbag2Writer(const std::string& path, Rosbag2Compression compression)
    : impl_(std::make_unique<Impl>()) {
  Impl& w = *impl_;
  w.path = path;
  const auto failed = [&](const std::string& what) {
    throw OutputError(path + ": cannot write (" + what + ")");
  };
  std::string file;
  if (ends_with(path, ".mcap")) {
    w.atomic.emplace(path);
    file = w.atomic->temp_path();
  } else {
    w.folder = true;
    std::error_code ec;
    std::string name = fs::path(path).filename().string();
    if (name.empty()) name = fs::path(path).parent_path().filename().string();
    if (fs::exists(path, ec)) {
      failed("it exists already; a bag folder is never replaced: remove it or name another");
    }
    w.temp_folder = (fs::path(path).lexically_normal().string());
    while (!w.temp_folder.empty() && w.temp_folder.back() == '/') w.temp_folder.pop_back();
    w.temp_folder += ".partial";
    fs::remove_all(w.temp_folder, ec);
    if (!fs::create_directory(w.temp_folder, ec)) failed(ec.message());
    w.file_name = name + "_0.mcap";
    file = (fs::path(w.temp_folder) / w.file_name).string();
  }
  w.out = std::fopen(file.c_str(), "wb");
  if (w.out == nullptr) failed(std::strerror(errno));
  const mcap::Compression c = compression == Rosbag2Compression::kZstd  ? mcap::Compression::kZstd
                              : compression == Rosbag2Compression::kLz4 ? mcap::Compression::kLz4
                                                                        : mcap::Compression::kNone;
  w.mcap = std::make_unique<mcap::Writer>(w.out, path, "ros2", c);
}

Rosbag2Writer::~Rosbag2Writer() {
  Impl& w = *impl_;
  if (w.out != nullptr) std::fclose(w.out);
  if (!w.finished && w.folder && !w.temp_folder.empty()) {
    std::error_code ec;
    fs::remove_all(w.temp_folder, ec);
  }
}

bool Rosbag2Writer::can_copy(const RecordedMessage& message) const {
  return dynamic_cast<const Rosbag2Message*>(&message) != nullptr || is_convertible(message.kind());
}

void Rosbag2Writer::copy(const RecordedMessage& message) {
  const auto* own = dynamic_cast<const Rosbag2Message*>(&message);
  if (own == nullptr) {
    write_decoded(*this, message);
    return;
  }
  const mcap::Schema* s = own->schema();
  static const std::vector<std::uint8_t> kNone;
  Impl::Topic& t = impl_->topic(own->topic(), s != nullptr ? s->name : std::string(),
                                s != nullptr ? s->encoding : std::string(),
                                s != nullptr ? s->data : kNone, own->channel().metadata);
  impl_->put(t, own->view().log_time, own->view().data, own->view().size);
  ++written_;
}

void Rosbag2Writer::write(const std::string& topic, Stamp time, const ScanMessage& message) {
  impl_->write(topic, time, message, MessageKind::kLaserScan);
  ++written_;
}
void Rosbag2Writer::write(const std::string& topic, Stamp time, const OdometryMessage& message) {
  impl_->write(topic, time, message, MessageKind::kOdometry);
  ++written_;
}
void Rosbag2Writer::write(const std::string& topic, Stamp time, const TransformsMessage& message) {
  impl_->write(topic, time, message, MessageKind::kTransforms);
  ++written_;
}
void Rosbag2Writer::write(const std::string& topic, Stamp time, const JointStateMessage& message) {
  impl_->write(topic, time, message, MessageKind::kJointState);
  ++written_;
}
void Rosbag2Writer::write(const std::string& topic, Stamp time, const ImuMessage& message) {
  impl_->write(topic, time, message, MessageKind::kImu);
  ++written_;
}

void Rosbag2Writer::finish() {
  Impl& w = *impl_;
  w.mcap->finish();
  const int closed = std::fclose(w.out);
  w.out = nullptr;
  if (closed != 0) throw OutputError(w.path + ": cannot write (" + std::strerror(errno) + ")");
  if (!w.folder) {
    w.atomic->commit();
    w.finished = true;
    return;
  }
  // The metadata last, then the folder into place.
  const std::string meta = (fs::path(w.temp_folder) / "metadata.yaml").string();
  std::FILE* m = std::fopen(meta.c_str(), "wb");
  if (m == nullptr) throw OutputError(meta + ": cannot write (" + std::strerror(errno) + ")");
  const std::string text = w.metadata_yaml(w.file_name);
  const bool ok = std::fwrite(text.data(), 1, text.size(), m) == text.size();
  if (std::fclose(m) != 0 || !ok) {
    throw OutputError(meta + ": cannot write (" + std::strerror(errno) + ")");
  }
  std::error_code ec;
  std::string target = w.path;
  while (target.size() > 1 && target.back() == '/') target.pop_back();
  fs::rename(w.temp_folder, target, ec);
  if (ec)
    throw OutputError(w.path + ": cannot move the bag folder into place (" + ec.message() + ")");
  w.finished = true;
}

}  // namespace dispel::io
