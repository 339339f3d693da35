#include "dispel/io/ros1_bag.hpp"

#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <map>
#include <optional>

#include "dispel/io/atomic_file.hpp"
#include "dispel/io/errors.hpp"
#include "dispel/io/ros1_messages.hpp"

namespace dispel::io {
namespace {

MessageKind kind_of(const std::string& datatype) {
  static const std::map<std::string, MessageKind> kinds = {
      {"sensor_msgs/LaserScan", MessageKind::kLaserScan},
      {"nav_msgs/Odometry", MessageKind::kOdometry},
      {"tf2_msgs/TFMessage", MessageKind::kTransforms},
      {"sensor_msgs/JointState", MessageKind::kJointState},
      {"sensor_msgs/Imu", MessageKind::kImu},
      {"sensor_msgs/NavSatFix", MessageKind::kNavSatFix}};
  const auto it = kinds.find(datatype);
  return it == kinds.end() ? MessageKind::kOther : it->second;
}

[[noreturn]] void unreadable(const std::string& path, const std::exception& e) {
  throw InputError(path + ": cannot read the recording (" + e.what() +
                   "); it may be truncated or corrupt");
}

// Runs a call into the bag library on a bag being read; its errors name the recording.
template <typename Fn>
auto reading(const std::string& path, Fn&& fn) -> decltype(fn()) {
  try {
    return fn();
  } catch (const std::exception& e) {
    unreadable(path, e);
  }
}

// One message of a bag being read.
class Ros1Message final : public RecordedMessage {
 public:
  Ros1Message(const rosbag::MessageInstance& m, const std::string& path, MessageKind kind)
      : m_(m), path_(path), kind_(kind), topic_(m.getTopic()) {}

  const rosbag::MessageInstance& instance() const { return m_; }
  const std::string& topic() const override { return topic_; }
  MessageKind kind() const override { return kind_; }
  Stamp time() const override { return to_stamp(m_.getTime()); }
  std::optional<ScanMessage> scan() const override {
    return decode<sensor_msgs::LaserScan>(MessageKind::kLaserScan);
  }
  std::optional<OdometryMessage> odometry() const override {
    return decode<nav_msgs::Odometry>(MessageKind::kOdometry);
  }
  std::optional<TransformsMessage> transforms() const override {
    return decode<tf2_msgs::TFMessage>(MessageKind::kTransforms);
  }
  std::optional<JointStateMessage> joint_state() const override {
    return decode<sensor_msgs::JointState>(MessageKind::kJointState);
  }
  std::optional<ImuMessage> imu() const override {
    return decode<sensor_msgs::Imu>(MessageKind::kImu);
  }
  std::optional<NavSatFixMessage> nav_sat_fix() const override {
    return decode<sensor_msgs::NavSatFix>(MessageKind::kNavSatFix);
  }

 private:
  template <typename RosMessage>
  auto decode(MessageKind kind) const -> std::optional<decltype(to_message(RosMessage{}))> {
    if (kind_ != kind) return std::nullopt;
    const auto msg = reading(path_, [&] { return m_.instantiate<RosMessage>(); });
    if (!msg) return std::nullopt;
    return to_message(*msg);
  }

  const rosbag::MessageInstance& m_;
  const std::string& path_;
  MessageKind kind_;
  std::string topic_;
};

}  // namespace

struct Ros1BagReader::Impl {
  std::string path;
  rosbag::Bag bag;
  Topics topics;
  Stamp begin, end;
};

Ros1BagReader::Ros1BagReader(const std::string& path) : impl_(std::make_unique<Impl>()) {
  impl_->path = path;
  try {
    impl_->bag.open(path, rosbag::bagmode::Read);
  } catch (const std::exception& e) {
    throw InputError(path + ": not a readable ROS 1 bag (" + e.what() + ")");
  }
  reading(path, [&] {
    std::map<std::string, TopicInfo> topics;
    rosbag::View all(impl_->bag);
    for (const rosbag::ConnectionInfo* c : all.getConnections()) {
      topics[c->topic] = {c->datatype, kind_of(c->datatype), 0};
    }
    for (auto& [topic, info] : topics) {
      info.messages =
          static_cast<std::int64_t>(rosbag::View(impl_->bag, rosbag::TopicQuery(topic)).size());
    }
    impl_->topics = Topics(std::move(topics));
    if (all.size() > 0) {
      impl_->begin = to_stamp(all.getBeginTime());
      impl_->end = to_stamp(all.getEndTime());
    }
  });
}

Ros1BagReader::~Ros1BagReader() = default;

const std::string& Ros1BagReader::path() const { return impl_->path; }
const Topics& Ros1BagReader::topics() const { return impl_->topics; }
Stamp Ros1BagReader::begin_time() const { return impl_->begin; }
Stamp Ros1BagReader::end_time() const { return impl_->end; }

void Ros1BagReader::read(const std::vector<std::string>& topics,
                         const std::function<void(const RecordedMessage&)>& visit) {
  const std::string& path = impl_->path;
  // Only the bag library's calls are guarded: what visit throws goes through as it is.
  std::optional<rosbag::View> view;
  reading(path, [&] {
    if (topics.empty()) {
      view.emplace(impl_->bag);
    } else {
      view.emplace(impl_->bag, rosbag::TopicQuery(topics));
    }
  });
  rosbag::View::iterator it = reading(path, [&] { return view->begin(); });
  while (!reading(path, [&] { return it == view->end(); })) {
    const rosbag::MessageInstance& m =
        reading(path, [&]() -> rosbag::MessageInstance& { return *it; });
    const Ros1Message message(m, path, impl_->topics.all().at(m.getTopic()).kind);
    try {
      visit(message);
    } catch (const StopReading&) {
      return;
    }
    reading(path, [&] { ++it; });
  }
}

struct Ros1BagWriter::Impl {
  explicit Impl(const std::string& p) : path(p), file(p) {}
  std::string path;
  AtomicFile file;
  rosbag::Bag bag;
  bool open = false;

  template <typename Fn>
  void writing(Fn&& fn) {
    try {
      fn();
    } catch (const std::exception& e) {
      throw OutputError(path + ": cannot write the bag (" + e.what() + ")");
    }
  }
  template <typename RosMessage>
  void write(const std::string& topic, Stamp time, const RosMessage& msg) {
    writing([&] { bag.write(topic, to_ros_time(time), msg); });
  }
};

Ros1BagWriter::Ros1BagWriter(const std::string& path, BagCompression compression)
    : impl_(std::make_unique<Impl>(path)) {
  try {
    impl_->bag.open(impl_->file.temp_path(), rosbag::bagmode::Write);
  } catch (const std::exception& e) {
    throw OutputError(path + ": cannot write (" + e.what() + ")");
  }
  impl_->open = true;
  switch (compression) {
    case BagCompression::kBz2:
      impl_->bag.setCompression(rosbag::compression::BZ2);
      break;
    case BagCompression::kLz4:
      impl_->bag.setCompression(rosbag::compression::LZ4);
      break;
    case BagCompression::kNone:
      break;
  }
}

Ros1BagWriter::~Ros1BagWriter() {
  if (!impl_->open) return;
  try {
    impl_->bag.close();  // Flushes; the file is then removed by AtomicFile.
  } catch (...) {        // A destructor must not throw (it may run while an error unwinds).
  }
}

void Ros1BagWriter::copy(const RecordedMessage& message) {
  const auto* m = dynamic_cast<const Ros1Message*>(&message);
  if (m == nullptr) {  // Another format's message: written from its decoded form.
    try {
      write_decoded(*this, message);
    } catch (const OutputError& e) {
      const std::string what = e.what();
      // write() names the bag already; write_decoded's own error names only the topic.
      if (what.rfind(impl_->path + ":", 0) == 0) throw;
      throw OutputError(impl_->path + ": " + what);
    }
    return;  // write() counted it.
  }
  const rosbag::MessageInstance& i = m->instance();
  impl_->writing([&] { impl_->bag.write(i.getTopic(), i.getTime(), i, i.getConnectionHeader()); });
  ++written_;
}

void Ros1BagWriter::write(const std::string& topic, Stamp time, const ScanMessage& message) {
  impl_->write(topic, time, to_ros(message));
  ++written_;
}

void Ros1BagWriter::write(const std::string& topic, Stamp time, const OdometryMessage& message) {
  impl_->write(topic, time, to_ros(message));
  ++written_;
}

void Ros1BagWriter::write(const std::string& topic, Stamp time, const TransformsMessage& message) {
  impl_->write(topic, time, to_ros(message));
  ++written_;
}

void Ros1BagWriter::write(const std::string& topic, Stamp time, const JointStateMessage& message) {
  impl_->write(topic, time, to_ros(message));
  ++written_;
}

void Ros1BagWriter::write(const std::string& topic, Stamp time, const ImuMessage& message) {
  impl_->write(topic, time, to_ros(message));
  ++written_;
}

void Ros1BagWriter::finish() {
  impl_->writing([&] { impl_->bag.close(); });
  impl_->open = false;
  try {
    impl_->file.commit();
  } catch (const std::exception& e) {
    throw OutputError(impl_->path + ": " + e.what());
  }
}

}  // namespace dispel::io
