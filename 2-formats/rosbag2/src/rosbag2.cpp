#include "dispel/io/rosbag2.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <optional>

#include "dispel/io/atomic_file.hpp"
#include "dispel/io/errors.hpp"
#include "dispel/io/ros2_messages.hpp"
#include "dispel/io/text.hpp"
#include "storage.hpp"

namespace dispel::io {
namespace {

namespace fs = std::filesystem;
using rosbag2::StoredTopic;

// @p path without the slashes at its end ("out/" names the folder "out").
std::string without_trailing_slashes(std::string path) {
  while (path.size() > 1 && path.back() == '/') path.pop_back();
  return path;
}

Stamp stamp_of(std::uint64_t ns) {
  return {static_cast<std::int64_t>(ns / 1000000000ULL),
          static_cast<std::uint32_t>(ns % 1000000000ULL)};
}

std::uint64_t ns_of(const Stamp& s) {
  if (s.sec < 0) return 0;
  return static_cast<std::uint64_t>(s.sec) * 1000000000ULL + s.nsec;
}

// One message of a file being read.
class Rosbag2Message final : public RecordedMessage {
 public:
  Rosbag2Message(const StoredTopic& topic, std::uint64_t ns, const std::uint8_t* data,
                 std::size_t size, const std::string& path)
      : topic_(topic), ns_(ns), data_(data), size_(size), path_(path) {}

  const StoredTopic& stored() const { return topic_; }
  std::uint64_t ns() const { return ns_; }
  const std::uint8_t* data() const { return data_; }
  std::size_t size() const { return size_; }

  const std::string& topic() const override { return topic_.name; }
  MessageKind kind() const override { return topic_.kind; }
  Stamp time() const override { return stamp_of(ns_); }
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
    if (kind != topic_.kind) return std::nullopt;
    try {
      return fn(data_, size_);
    } catch (const CdrError& e) {
      throw InputError(one_line(path_ + ": topic " + quote(topic_.name) + ", message at " +
                                    std::to_string(time().seconds()) + " s: cannot decode (" +
                                    e.what() + ")",
                                400));
    }
  }

  const StoredTopic& topic_;
  std::uint64_t ns_;
  const std::uint8_t* data_;
  std::size_t size_;
  const std::string& path_;
};

// The kind of a topic: one of the model's types only when its messages are CDR and its
// definition, if the file holds one, is ros2msg.
MessageKind kind_of(const StoredTopic& t) {
  if (t.serialization_format != "cdr" ||
      (!t.definition.empty() && t.definition_encoding != "ros2msg")) {
    return MessageKind::kOther;
  }
  return ros2_message_kind(t.type);
}

// The files of a bag folder, from its metadata.yaml; @p sqlite3 tells their storage.
std::vector<std::string> files_of_folder(const std::string& folder, bool& sqlite3) {
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
    if (storage != "mcap" && storage != "sqlite3") {
      throw InputError(one_line(meta.string() + ": storage " + quote(storage) +
                                    "; dispel reads rosbag2 bags stored as mcap or sqlite3",
                                400));
    }
    sqlite3 = storage == "sqlite3";
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
  bool sqlite3 = false;
  std::vector<std::unique_ptr<rosbag2::StorageReader>> files;
  Topics topics;
  Stamp begin;
  Stamp end;
};

Rosbag2Reader::Rosbag2Reader(const std::string& path) : impl_(std::make_unique<Impl>()) {
  impl_->path = path;
  impl_->sqlite3 = ends_with(path, ".db3");
  std::error_code ec;
  const std::vector<std::string> names = fs::is_directory(path, ec)
                                             ? files_of_folder(path, impl_->sqlite3)
                                             : std::vector<std::string>{path};
  std::map<std::string, TopicInfo> topics;
  bool first = true;
  for (const std::string& name : names) {
    auto file = impl_->sqlite3 ? rosbag2::open_sqlite3(name) : rosbag2::open_mcap(name);
    for (StoredTopic& t : file->topics()) {
      t.kind = kind_of(t);
      TopicInfo& info = topics[t.name];
      if (info.type.empty()) {
        info.type = t.type.empty() ? std::string("(no schema)") : t.type;
        info.kind = t.kind;
      }
      info.messages += static_cast<std::int64_t>(t.messages);
    }
    if (file->total_messages() > 0) {
      const Stamp b = stamp_of(file->start_ns());
      const Stamp e = stamp_of(file->end_ns());
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
std::string Rosbag2Reader::format_name() const {
  return impl_->sqlite3 ? "rosbag2 (sqlite3)" : "rosbag2 (mcap)";
}
const Topics& Rosbag2Reader::topics() const { return impl_->topics; }
Stamp Rosbag2Reader::begin_time() const { return impl_->begin; }
Stamp Rosbag2Reader::end_time() const { return impl_->end; }

void Rosbag2Reader::read(const std::vector<std::string>& topics,
                         const std::function<void(const RecordedMessage&)>& visit) {
  // The files of a folder follow each other in time (rosbag2 splits a recording in order).
  try {
    for (const auto& file : impl_->files) {
      const auto& stored = file->topics();
      file->read(
          [&](std::size_t i) {
            return topics.empty() ||
                   std::find(topics.begin(), topics.end(), stored[i].name) != topics.end();
          },
          [&](std::size_t i, std::uint64_t ns, const std::uint8_t* data, std::size_t size) {
            visit(Rosbag2Message(stored[i], ns, data, size, impl_->path));
          });
    }
  } catch (const StopReading&) {
  }
}

// ---------------------------------------------------------------------------------------------
// Writing

namespace {

// The version of metadata.yaml written (integer QoS policies, a list of files).
constexpr int kMetadataVersion = 5;

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
  bool sqlite3 = false;
  std::optional<AtomicFile> atomic;  // A single file.
  std::string temp_folder;           // A bag folder, while it is written.
  std::string file_name;             // The file inside the folder.
  std::unique_ptr<rosbag2::StorageWriter> storage;
  struct Topic {
    std::size_t index = 0;  // In the storage.
    StoredTopic info;       // Its messages counted.
  };
  std::map<std::string, Topic> topics;
  std::uint64_t messages = 0;
  std::uint64_t first_ns = 0;
  std::uint64_t last_ns = 0;
  bool finished = false;

  // The topic @p name, added as @p make() gives it when new (with the definition dispel knows
  // when the given one has none).
  template <typename Make>
  Topic& topic(const std::string& name, const std::string& type, const Make& make) {
    auto it = topics.find(name);
    if (it != topics.end()) {
      if (it->second.info.type != type) {
        throw OutputError(one_line(path + ": topic " + quote(name) + " written with two types, " +
                                       quote(it->second.info.type) + " and " + quote(type),
                                   400));
      }
      return it->second;
    }
    Topic t{0, make()};
    if (t.info.definition.empty() && t.info.kind != MessageKind::kOther) {
      const std::string& def = ros2_definition(t.info.kind);
      t.info.definition_encoding = "ros2msg";
      t.info.definition.assign(def.begin(), def.end());
    }
    t.info.messages = 0;
    t.index = storage->add_topic(t.info);
    return topics.emplace(name, std::move(t)).first->second;
  }

  void put(Topic& t, std::uint64_t ns, const std::uint8_t* data, std::size_t size) {
    storage->write(t.index, ns, data, size);
    if (messages == 0 || ns < first_ns) first_ns = ns;
    if (messages == 0 || ns > last_ns) last_ns = ns;
    ++messages;
    ++t.info.messages;
  }

  template <typename M>
  void write(const std::string& name, Stamp time, const M& message, MessageKind kind) {
    const std::string type = ros2_type_name(kind);
    Topic& t = topic(name, type, [&] {
      const rosbag2::Metadata qos = {{"offered_qos_profiles", qos_profiles(name)}};
      return StoredTopic{name, type, "cdr", qos, "", {}, kind, 0};
    });
    const std::vector<std::uint8_t> data = encode_ros2(message);
    put(t, ns_of(time), data.data(), data.size());
  }

  std::string metadata_yaml(const std::string& relative) const {
    YAML::Emitter y;
    y << YAML::BeginMap << YAML::Key << "rosbag2_bagfile_information" << YAML::Value
      << YAML::BeginMap;
    y << YAML::Key << "version" << YAML::Value << kMetadataVersion;
    y << YAML::Key << "storage_identifier" << YAML::Value << (sqlite3 ? "sqlite3" : "mcap");
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
      y << YAML::Key << "type" << YAML::Value << t.info.type;
      y << YAML::Key << "serialization_format" << YAML::Value << t.info.serialization_format;
      y << YAML::Key << "offered_qos_profiles" << YAML::Value << YAML::DoubleQuoted
        << rosbag2::value_of(t.info.metadata, "offered_qos_profiles");
      y << YAML::EndMap;
      y << YAML::Key << "message_count" << YAML::Value << t.info.messages << YAML::EndMap;
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

Rosbag2Writer::Rosbag2Writer(const std::string& path, Rosbag2Compression compression,
                             Rosbag2Storage storage)
    : impl_(std::make_unique<Impl>()) {
  Impl& w = *impl_;
  w.path = path;
  const auto failed = [&](const std::string& what) {
    throw OutputError(path + ": cannot write (" + what + ")");
  };
  const bool mcap_file = ends_with(path, ".mcap");
  const bool db3_file = ends_with(path, ".db3");
  w.sqlite3 = db3_file || (!mcap_file && storage == Rosbag2Storage::kSqlite3);
  if (w.sqlite3 && compression != Rosbag2Compression::kNone) {
    failed(
        "sqlite3 storage is not compressed: zstd and lz4 compress the chunks of MCAP storage "
        "only");
  }
  std::string file;
  if (mcap_file || db3_file) {
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
    // A folder of this run's own (OUT.partial.XXXXXX): nothing of anyone else's is ever
    // removed, and two runs writing one OUT do not meet until the rename.
    std::string pattern =
        without_trailing_slashes(fs::path(path).lexically_normal().string()) + ".partial.XXXXXX";
    if (::mkdtemp(pattern.data()) == nullptr) failed(std::strerror(errno));
    w.temp_folder = pattern;
    fs::permissions(w.temp_folder,  // mkdtemp makes it 0700; a bag folder is 0755.
                    fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                        fs::perms::others_read | fs::perms::others_exec,
                    ec);
    w.file_name = name + (w.sqlite3 ? "_0.db3" : "_0.mcap");
    file = (fs::path(w.temp_folder) / w.file_name).string();
  }
  try {
    if (w.sqlite3) {
      w.storage = rosbag2::create_sqlite3(file, path);
    } else {
      w.storage = rosbag2::create_mcap(
          file, path,
          compression == Rosbag2Compression::kZstd  ? mcap::Compression::kZstd
          : compression == Rosbag2Compression::kLz4 ? mcap::Compression::kLz4
                                                    : mcap::Compression::kNone);
    }
  } catch (...) {  // The destructor does not run for a constructor that throws.
    std::error_code ec;
    if (w.folder) fs::remove_all(w.temp_folder, ec);
    throw;
  }
}

Rosbag2Writer::~Rosbag2Writer() {
  Impl& w = *impl_;
  w.storage.reset();  // Closed before its file is removed.
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
  const StoredTopic& s = own->stored();
  Impl::Topic& t = impl_->topic(s.name, s.type, [&] { return s; });
  impl_->put(t, own->ns(), own->data(), own->size());
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
  const std::string text =
      w.metadata_yaml(w.folder ? w.file_name : fs::path(w.path).filename().string());
  // A sqlite3 file keeps the metadata too, the mapping under rosbag2_bagfile_information.
  w.storage->finish(YAML::Dump(YAML::Load(text)["rosbag2_bagfile_information"]), kMetadataVersion);
  if (!w.folder) {
    w.atomic->commit();
    w.finished = true;
    return;
  }
  // The metadata last, then the folder into place.
  write_file_atomically((fs::path(w.temp_folder) / "metadata.yaml").string(), text);
  std::error_code ec;
  fs::rename(w.temp_folder, without_trailing_slashes(w.path), ec);
  if (ec)
    throw OutputError(w.path + ": cannot move the bag folder into place (" + ec.message() + ")");
  w.finished = true;
}

}  // namespace dispel::io
