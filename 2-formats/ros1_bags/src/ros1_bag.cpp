#include "dispel/io/ros1_bag.hpp"

#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <vector>

#include "bag_check.hpp"
#include "dispel/io/atomic_file.hpp"
#include "dispel/io/errors.hpp"
#include "dispel/io/ros1_messages.hpp"
#include "dispel/io/text.hpp"

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

// The bag library's messages quote what it read (a record's field names, a type): one line, cut.
[[noreturn]] void unreadable(const std::string& path, const std::exception& e) {
  throw InputError(one_line(path + ": cannot read the recording (" + one_line(e.what(), 200) +
                            "); it may be truncated or corrupt"));
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
    // A message of another definition of the type (its MD5 sum differs) is not deserialised
    // (instantiate() gives none): its layout is not the one checked below.
    if (!m_.isType<RosMessage>()) return std::nullopt;
    // The deserialiser trusts the message's array lengths: they are checked first.
    std::vector<std::uint8_t> data;
    reading(path_, [&] {
      data.resize(m_.size());
      ros::serialization::OStream out(data.data(), static_cast<std::uint32_t>(data.size()));
      m_.write(out);
    });
    check_message_lengths(path_, topic_, time(), kind, data.data(), data.size());
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

Ros1BagReader::Ros1BagReader(const std::string& path) {
  // The bag library trusts the bag's lengths and offsets: a corrupt one crashed it (SIGSEGV) or
  // made it allocate without bound. They are checked first: InputError "corrupt bag: ...". (Before
  // a rosbag::Bag is made: making one loads the bag library's plugins, 30 ms under ASan.)
  check_bag_structure(path);
  impl_ = std::make_unique<Impl>();
  impl_->path = path;
  try {
    impl_->bag.open(path, rosbag::bagmode::Read);
  } catch (const std::exception& e) {
    throw InputError(
        one_line(path + ": not a readable ROS 1 bag (" + one_line(e.what(), 200) + ")"));
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

namespace {

// A bag the library could not close (a full disk, a file-size limit, /dev/full): its close()
// throws on every call, and rosbag::Bag's destructor calls close() again, throws from a
// destructor and aborts the program. Such a bag is never destroyed: it is kept here (reachable,
// so leak checkers stay quiet) and its file is deleted by AtomicFile. Its memory and file
// descriptor are held until the process ends; a program writes few bags.
void abandon(std::unique_ptr<rosbag::Bag> bag) {
  static std::mutex mutex;
  static auto* const kept = new std::vector<std::unique_ptr<rosbag::Bag>>();
  const std::lock_guard<std::mutex> lock(mutex);
  kept->push_back(std::move(bag));
}

// What the bag library's error leaves out: why the system refused the write.
std::string with_reason(const std::string& what, int error) {
  if (error == ENOSPC || error == EFBIG || error == EIO || error == EDQUOT || error == EACCES ||
      error == ENOENT || error == EROFS || error == EISDIR || error == ENOTDIR) {
    return what + ": " + std::strerror(error);
  }
  return what;
}

// A bag holds receive times from 1 ns (ros::TIME_MIN) to 2^32 - 1 s; a time outside is refused,
// never wrapped or clamped onto another time.
ros::Time bag_time(const std::string& path, const std::string& topic, const Stamp& t) {
  constexpr std::int64_t kMax = std::numeric_limits<std::uint32_t>::max();
  if (t.sec < 0 || t.sec > kMax || t.is_zero()) {
    char seconds[32];
    std::snprintf(seconds, sizeof seconds, "%.10g", t.seconds());
    throw OutputError(path + ": cannot write " + topic.substr(0, 80) + " at " + seconds +
                      " s: a ROS 1 bag holds times from 1 ns to 4294967295 s");
  }
  return ros::Time(static_cast<std::uint32_t>(t.sec), t.nsec);
}

}  // namespace

struct Ros1BagWriter::Impl {
  explicit Impl(const std::string& p) : path(p), file(p), bag(std::make_unique<rosbag::Bag>()) {}
  ~Impl() {
    if (open) {
      try {
        bag->close();  // Flushes; the file is then removed by AtomicFile.
      } catch (...) {  // A destructor must not throw (it may run while an error unwinds).
        abandon(std::move(bag));
      }
    } else if (failed) {
      abandon(std::move(bag));
    }
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  std::string path;
  AtomicFile file;
  std::unique_ptr<rosbag::Bag> bag;
  bool open = false;
  bool failed = false;  ///< A write failed: the bag cannot be closed cleanly any more.

  template <typename Fn>
  void writing(Fn&& fn) {
    if (failed) throw OutputError(path + ": cannot write the bag (an earlier write failed)");
    errno = 0;
    try {
      fn();
    } catch (const std::exception& e) {
      const int error = errno;
      failed = true;
      open = false;
      throw OutputError(path + ": cannot write the bag (" + with_reason(e.what(), error) + ")");
    }
  }
  template <typename RosMessage>
  void write(const std::string& topic, Stamp time, const RosMessage& msg) {
    const ros::Time t = bag_time(path, topic, time);  // Before the write: the bag stays good.
    writing([&] { bag->write(topic, t, msg); });
  }
};

Ros1BagWriter::Ros1BagWriter(const std::string& path, BagCompression compression)
    : impl_(std::make_unique<Impl>(path)) {
  errno = 0;
  try {
    impl_->bag->open(impl_->file.temp_path(), rosbag::bagmode::Write);
  } catch (const std::exception& e) {
    const int error = errno;
    impl_->failed = true;
    throw OutputError(path + ": cannot write (" + with_reason(e.what(), error) + ")");
  }
  impl_->open = true;
  switch (compression) {
    case BagCompression::kBz2:
      impl_->bag->setCompression(rosbag::compression::BZ2);
      break;
    case BagCompression::kLz4:
      impl_->bag->setCompression(rosbag::compression::LZ4);
      break;
    case BagCompression::kNone:
      break;
  }
}

Ros1BagWriter::~Ros1BagWriter() = default;

bool Ros1BagWriter::can_copy(const RecordedMessage& message) const {
  return dynamic_cast<const Ros1Message*>(&message) != nullptr || is_convertible(message.kind());
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
  impl_->writing([&] { impl_->bag->write(i.getTopic(), i.getTime(), i, i.getConnectionHeader()); });
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
  errno = 0;
  impl_->writing([&] { impl_->bag->close(); });
  impl_->open = false;
  try {
    impl_->file.commit();
  } catch (const std::exception& e) {
    throw OutputError(impl_->path + ": " + e.what());
  }
}

}  // namespace dispel::io
