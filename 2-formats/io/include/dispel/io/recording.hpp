#pragma once
/// @file
/// A recording as dispel sees it, whatever its format: topics of messages in time order, the few
/// message types dispel reads and writes in a form of its own, and the interfaces a format
/// implements to be read (RecordingReader) and written (RecordingWriter). ROS 1 bags implement
/// them in dispel::io_ros1_bags; a new format plugs in the same way (docs/architecture.md).

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "dispel/core/dynamic_filter.hpp"
#include "dispel/core/laser_scan.hpp"
#include "dispel/core/odometry_fusion.hpp"
#include "dispel/core/pose2.hpp"

namespace dispel::io {

/// A time stamp as recordings keep it: whole seconds and nanoseconds, exactly.
struct Stamp {
  std::int64_t sec = 0;
  std::uint32_t nsec = 0;  ///< In [0, 1e9).

  double seconds() const { return static_cast<double>(sec) + 1e-9 * static_cast<double>(nsec); }
  bool is_zero() const { return sec == 0 && nsec == 0; }
  /// The stamp nearest to @p seconds (rounded to the nanosecond).
  static Stamp from_seconds(double seconds);

  bool operator==(const Stamp& o) const { return sec == o.sec && nsec == o.nsec; }
  bool operator!=(const Stamp& o) const { return !(*this == o); }
  bool operator<(const Stamp& o) const { return sec < o.sec || (sec == o.sec && nsec < o.nsec); }
};

struct Header {
  std::uint32_t seq = 0;
  Stamp stamp;
  std::string frame_id;
};

/// sensor_msgs/LaserScan: the core's scan (stamp in seconds) and the fields it does not keep.
struct ScanMessage {
  Header header;
  LaserScan scan;  ///< scan.stamp_s is header.stamp in seconds.
  float angle_max = 0.0F;
  float time_increment = 0.0F;
  float scan_time = 0.0F;  ///< The period the scanner states; 0 when it states none.
};

/// nav_msgs/Odometry, its planar part: the pose of child_frame_id in header.frame_id, and the
/// covariances whole (row-major, x y z roll pitch yaw), so that they go through a conversion.
struct OdometryMessage {
  Header header;
  std::string child_frame_id;
  Pose2 pose;
  double v_mps = 0.0;    ///< twist.linear.x
  double vy_mps = 0.0;   ///< twist.linear.y
  double w_radps = 0.0;  ///< twist.angular.z
  std::array<double, 36> pose_covariance{};
  std::array<double, 36> twist_covariance{};
};

/// One transform of tf2_msgs/TFMessage, its planar part.
struct FrameTransform {
  Stamp stamp;
  std::string parent;
  std::string child;
  Pose2 child_in_parent;
};

/// tf2_msgs/TFMessage.
struct TransformsMessage {
  std::vector<FrameTransform> transforms;
};

/// sensor_msgs/JointState.
struct JointStateMessage {
  Header header;
  std::vector<std::string> names;
  std::vector<double> positions;
  std::vector<double> velocities;
};

/// sensor_msgs/Imu: what dispel uses of it.
struct ImuMessage {
  Header header;
  Eigen::Vector3d angular_velocity_radps = Eigen::Vector3d::Zero();
  bool has_orientation = false;  ///< false: orientation_covariance[0] = -1 (REP 145).
};

/// sensor_msgs/NavSatFix: what dispel uses of it.
struct NavSatFixMessage {
  Header header;
  int status = -1;  ///< -1 no fix, 0 fix, 1 SBAS, 2 GBAS (sensor_msgs/NavSatStatus).
  double latitude_deg = 0.0;
  double longitude_deg = 0.0;
};

/// The message types dispel understands; every other one is kOther (copied, never decoded).
enum class MessageKind : std::uint8_t {
  kLaserScan,
  kOdometry,
  kTransforms,
  kJointState,
  kImu,
  kNavSatFix,
  kOther,
};

/// The type's name in messages to the user, e.g. "sensor_msgs/LaserScan".
const char* message_kind_name(MessageKind kind);

/// A topic of a recording.
struct TopicInfo {
  std::string type;  ///< As the format names it ("sensor_msgs/LaserScan").
  MessageKind kind = MessageKind::kOther;
  std::int64_t messages = 0;
};

/// The topics of a recording by name, with questions the commands ask of them.
class Topics {
 public:
  Topics() = default;
  explicit Topics(std::map<std::string, TopicInfo> topics) : topics_(std::move(topics)) {}

  bool has(const std::string& topic) const { return topics_.count(topic) != 0; }
  bool has(const std::string& topic, MessageKind kind) const;
  /// The topics of @p kind, in name order.
  std::vector<std::string> of_kind(MessageKind kind) const;
  /// The same as "a, b, c", or "none": for error messages.
  std::string list(MessageKind kind) const;
  std::int64_t messages(const std::string& topic) const;
  const std::map<std::string, TopicInfo>& all() const { return topics_; }

 private:
  std::map<std::string, TopicInfo> topics_;
};

/// "a, b, c" of @p names, or "none".
std::string join_names(const std::vector<std::string>& names);

/// One message of a recording, as its reader holds it; decoded on request. Valid only during the
/// visit that gives it.
class RecordedMessage {
 public:
  virtual ~RecordedMessage() = default;
  virtual const std::string& topic() const = 0;
  virtual MessageKind kind() const = 0;
  /// When the recording received it.
  virtual Stamp time() const = 0;
  /// The message decoded, or std::nullopt when it is of another kind. @throws InputError naming
  /// the recording when it cannot be decoded (a truncated or corrupt file).
  virtual std::optional<ScanMessage> scan() const = 0;
  virtual std::optional<OdometryMessage> odometry() const = 0;
  virtual std::optional<TransformsMessage> transforms() const = 0;
  virtual std::optional<JointStateMessage> joint_state() const = 0;
  virtual std::optional<ImuMessage> imu() const = 0;
  virtual std::optional<NavSatFixMessage> nav_sat_fix() const = 0;
};

/// A message of one of the types dispel understands, decoded.
using DecodedPayload = std::variant<ScanMessage, OdometryMessage, TransformsMessage,
                                    JointStateMessage, ImuMessage, NavSatFixMessage>;

/// A message held decoded in memory (a format read whole, such as an MRPT rawlog, or a test's
/// recording); its kind follows its payload.
class DecodedMessage final : public RecordedMessage {
 public:
  DecodedMessage(std::string topic, Stamp time, DecodedPayload payload);
  const std::string& topic() const override { return topic_; }
  MessageKind kind() const override { return kind_; }
  Stamp time() const override { return time_; }
  std::optional<ScanMessage> scan() const override { return get<ScanMessage>(); }
  std::optional<OdometryMessage> odometry() const override { return get<OdometryMessage>(); }
  std::optional<TransformsMessage> transforms() const override { return get<TransformsMessage>(); }
  std::optional<JointStateMessage> joint_state() const override { return get<JointStateMessage>(); }
  std::optional<ImuMessage> imu() const override { return get<ImuMessage>(); }
  std::optional<NavSatFixMessage> nav_sat_fix() const override { return get<NavSatFixMessage>(); }

 private:
  template <typename T>
  std::optional<T> get() const {
    if (const T* p = std::get_if<T>(&payload_)) return *p;
    return std::nullopt;
  }
  std::string topic_;
  Stamp time_;
  MessageKind kind_;
  DecodedPayload payload_;
};

/// Thrown by a visitor of RecordingReader::read() to stop reading there: read() returns.
struct StopReading {};

/// A recording opened for reading.
class RecordingReader {
 public:
  virtual ~RecordingReader() = default;
  virtual const std::string& path() const = 0;
  /// "ROS 1 bag", for messages and statistics.
  virtual std::string format_name() const = 0;
  virtual const Topics& topics() const = 0;
  /// The receive times of the first and last message (both zero when there are none).
  virtual Stamp begin_time() const = 0;
  virtual Stamp end_time() const = 0;
  /// Calls @p visit for every message on @p topics (every topic when empty), in time order, until
  /// it throws StopReading. @throws InputError naming the recording when it cannot be read;
  /// whatever else @p visit throws goes through unchanged.
  virtual void read(const std::vector<std::string>& topics,
                    const std::function<void(const RecordedMessage&)>& visit) = 0;
};

/// A recording being written. Nothing appears under its name until finish() succeeds.
class RecordingWriter {
 public:
  virtual ~RecordingWriter() = default;
  /// Writes @p message unchanged (its bytes, type and metadata). It must come from a reader of
  /// the same format, or be of a kind write_decoded() converts. @throws OutputError
  virtual void copy(const RecordedMessage& message) = 0;
  /// True when copy() can write @p message: a message of the writer's own format, or one of a
  /// kind that is_convertible() (a job converting between formats leaves the others out, and
  /// says so).
  virtual bool can_copy(const RecordedMessage& message) const = 0;
  /// Writes a message at @p time. @throws OutputError
  virtual void write(const std::string& topic, Stamp time, const ScanMessage& message) = 0;
  virtual void write(const std::string& topic, Stamp time, const OdometryMessage& message) = 0;
  virtual void write(const std::string& topic, Stamp time, const TransformsMessage& message) = 0;
  virtual void write(const std::string& topic, Stamp time, const JointStateMessage& message) = 0;
  virtual void write(const std::string& topic, Stamp time, const ImuMessage& message) = 0;
  /// Completes the file and moves it into place. @throws OutputError
  virtual void finish() = 0;
  std::int64_t messages_written() const { return written_; }

 protected:
  std::int64_t written_ = 0;
};

/// Writes @p message through @p writer's typed write(), decoded by its kind, at its receive time:
/// how a writer copies a message of another format (a ROS 1 bag writer given an MRPT rawlog's
/// scan, say). @throws OutputError naming the topic for a kind the writer has no write() for
/// (kNavSatFix, kOther: their bytes mean nothing outside their own format); InputError when the
/// message cannot be decoded.
void write_decoded(RecordingWriter& writer, const RecordedMessage& message);
/// True for the kinds write_decoded() writes: every kind but kNavSatFix and kOther.
bool is_convertible(MessageKind kind);

/// A scan message for a scan of the core (the simulator's, a CARMEN log's): the header stamped
/// with scan.stamp_s in @p frame_id, angle_max from the beam count, no stated period.
ScanMessage scan_message(const LaserScan& scan, const std::string& frame_id);
/// An odometry message: @p pose of @p child_frame_id in @p frame_id at @p stamp_s, moving forward
/// at @p v_mps and turning at @p w_radps.
OdometryMessage odometry_message(double stamp_s, const std::string& frame_id,
                                 const std::string& child_frame_id, const Pose2& pose,
                                 double v_mps = 0.0, double w_radps = 0.0);
/// The odometry message of a fused estimate, as the odometry nodes publish it: its pose, forward,
/// lateral and yaw rates, and the variances it knows on the covariances' diagonals (x, y, yaw;
/// forward speed, yaw rate), 0 where it knows none.
OdometryMessage odometry_message(const OdometryEstimate& estimate, const std::string& frame_id,
                                 const std::string& child_frame_id);

/// The message written on <scan topic>_filtered: @p original with the filtered ranges (removed
/// beams NaN).
ScanMessage filtered_message(const ScanMessage& original, const FilterResult& result);
/// The message written on <scan topic>_labels: @p original whose intensities are the beam labels
/// (BeamLabel's values; a beam without one is labelled invalid).
ScanMessage labels_message(const ScanMessage& original, const FilterResult& result);

}  // namespace dispel::io
