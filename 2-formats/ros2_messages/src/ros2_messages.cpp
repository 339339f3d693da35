#include "dispel/io/ros2_messages.hpp"

#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <type_traits>

namespace dispel::io {
namespace {

// ---------------------------------------------------------------------------------------------
// CDR (XCDR1): a 4-byte encapsulation header {0, kind, options, options}, kind 0 big-endian or
// 1 little-endian; then the fields, each primitive aligned to its size (8 at most) counted from
// the end of the header; strings as uint32 length (with the terminating NUL) and the bytes;
// sequences as uint32 count and the elements; fixed arrays as the elements alone.
constexpr std::size_t kEncapsulation = 4;

bool host_is_little_endian() {
  const std::uint16_t one = 1;
  std::uint8_t first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

class CdrReader {
 public:
  CdrReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {
    if (size < kEncapsulation) {
      throw CdrError("message of " + std::to_string(size) + " bytes, shorter than its CDR header");
    }
    if (data[0] != 0 || data[1] > 1) {
      throw CdrError("encapsulation " + std::to_string(data[0]) + "," + std::to_string(data[1]) +
                     " is not plain CDR (XCDR1, 0,0 or 0,1)");
    }
    swap_ = (data[1] == 1) != host_is_little_endian();
    at_ = kEncapsulation;
  }

  template <typename T>
  T read() {
    static_assert(std::is_arithmetic_v<T>);
    align(sizeof(T));
    need(sizeof(T), "a number");
    T value;
    std::uint8_t bytes[sizeof(T)];
    std::memcpy(bytes, data_ + at_, sizeof(T));
    if (swap_) {
      for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
    }
    std::memcpy(&value, bytes, sizeof(T));
    at_ += sizeof(T);
    return value;
  }

  std::string string() {
    const std::uint32_t n = read<std::uint32_t>();
    need(n, "a string");
    if (n == 0) return {};  // Some writers give no NUL for an empty string.
    std::string s(reinterpret_cast<const char*>(data_ + at_), n - 1);
    at_ += n;
    return s;
  }

  /// A sequence's count, checked against what is left (each element at least @p min_bytes).
  std::size_t count(std::size_t min_bytes) {
    const std::uint32_t n = read<std::uint32_t>();
    if (min_bytes > 0 && static_cast<std::size_t>(n) > (size_ - at_) / min_bytes) {
      throw CdrError("a sequence of " + std::to_string(n) + " elements at byte " +
                     std::to_string(at_) + " is longer than the message (" + std::to_string(size_) +
                     " bytes)");
    }
    return n;
  }

  template <typename T>
  std::vector<T> sequence() {
    const std::size_t n = count(sizeof(T));
    std::vector<T> out(n);
    if (n == 0) return out;
    align(sizeof(T));
    need(n * sizeof(T), "a sequence");
    if (!swap_) {
      std::memcpy(out.data(), data_ + at_, n * sizeof(T));
      at_ += n * sizeof(T);
    } else {
      for (T& v : out) v = read<T>();
    }
    return out;
  }

  template <std::size_t N>
  std::array<double, N> doubles() {
    std::array<double, N> out{};
    for (double& v : out) v = read<double>();
    return out;
  }

  Stamp time() {
    const std::int32_t sec = read<std::int32_t>();
    const std::uint32_t nsec = read<std::uint32_t>();
    if (nsec >= 1000000000U) {
      throw CdrError("a time with " + std::to_string(nsec) + " nanoseconds (at most 999999999)");
    }
    return {sec, nsec};
  }

  Header header() {
    Header h;
    h.stamp = time();
    h.frame_id = string();
    return h;
  }

 private:
  void align(std::size_t n) {
    const std::size_t offset = at_ - kEncapsulation;
    const std::size_t pad = (n - offset % n) % n;
    need(pad, "padding");
    at_ += pad;
  }
  void need(std::size_t n, const char* what) const {
    if (n > size_ - at_) {
      throw CdrError(std::string("message cut short: ") + what + " of " + std::to_string(n) +
                     " bytes at byte " + std::to_string(at_) + " of " + std::to_string(size_));
    }
  }

  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t at_ = 0;
  bool swap_ = false;
};

class CdrWriter {
 public:
  CdrWriter() {
    out_.reserve(256);
    out_ = {0, host_is_little_endian() ? std::uint8_t{1} : std::uint8_t{0}, 0, 0};
  }

  template <typename T>
  void write(T value) {
    static_assert(std::is_arithmetic_v<T>);
    align(sizeof(T));
    const std::size_t at = out_.size();
    out_.resize(at + sizeof(T));
    std::memcpy(out_.data() + at, &value, sizeof(T));
  }

  void string(const std::string& s) {
    write<std::uint32_t>(static_cast<std::uint32_t>(s.size() + 1));
    out_.insert(out_.end(), s.begin(), s.end());
    out_.push_back(0);
  }

  template <typename T>
  void sequence(const std::vector<T>& values) {
    write<std::uint32_t>(static_cast<std::uint32_t>(values.size()));
    if (values.empty()) return;
    align(sizeof(T));
    const std::size_t at = out_.size();
    out_.resize(at + values.size() * sizeof(T));
    std::memcpy(out_.data() + at, values.data(), values.size() * sizeof(T));
  }

  void zeros(std::size_t doubles, double first = 0.0) {
    for (std::size_t i = 0; i < doubles; ++i) write<double>(i == 0 ? first : 0.0);
  }

  void time(const Stamp& s) {
    const Stamp c = ros2_clamped(s);
    write<std::int32_t>(static_cast<std::int32_t>(c.sec));
    write<std::uint32_t>(c.nsec);
  }

  void header(const Header& h) {
    time(h.stamp);
    string(h.frame_id);
  }

  void planar(const Pose2& p) {  // geometry_msgs Point or Vector3, then Quaternion.
    write<double>(p.x_m);
    write<double>(p.y_m);
    write<double>(0.0);
    quaternion(p.yaw_rad);
  }

  void quaternion(double yaw_rad) {
    write<double>(0.0);
    write<double>(0.0);
    write<double>(std::sin(0.5 * yaw_rad));
    write<double>(std::cos(0.5 * yaw_rad));
  }

  std::vector<std::uint8_t> take() { return std::move(out_); }

 private:
  void align(std::size_t n) {
    const std::size_t offset = out_.size() - kEncapsulation;
    out_.resize(out_.size() + (n - offset % n) % n, 0);
  }
  std::vector<std::uint8_t> out_;
};

double yaw_of(double x, double y, double z, double w) {
  return std::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
}

// Point/Vector3 then Quaternion, planar part.
Pose2 read_planar(CdrReader& r) {
  const double x = r.read<double>();
  const double y = r.read<double>();
  (void)r.read<double>();
  const double qx = r.read<double>();
  const double qy = r.read<double>();
  const double qz = r.read<double>();
  const double qw = r.read<double>();
  return {x, y, yaw_of(qx, qy, qz, qw)};
}

// ---------------------------------------------------------------------------------------------
// Definitions (ros2msg), the fields of ROS 2's common_interfaces.

std::string with(const std::string& top, std::initializer_list<const char*> dependencies);

const std::map<std::string, std::string>& msg_texts() {
  static const std::map<std::string, std::string> texts = {
      {"builtin_interfaces/Time", "int32 sec\nuint32 nanosec"},
      {"std_msgs/Header", "builtin_interfaces/Time stamp\nstring frame_id"},
      {"geometry_msgs/Point", "float64 x\nfloat64 y\nfloat64 z"},
      {"geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z"},
      {"geometry_msgs/Quaternion", "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1"},
      {"geometry_msgs/Pose", "Point position\nQuaternion orientation"},
      {"geometry_msgs/PoseWithCovariance", "Pose pose\nfloat64[36] covariance"},
      {"geometry_msgs/Twist", "Vector3  linear\nVector3  angular"},
      {"geometry_msgs/TwistWithCovariance", "Twist twist\nfloat64[36] covariance"},
      {"geometry_msgs/Transform", "Vector3 translation\nQuaternion rotation"},
      {"geometry_msgs/TransformStamped",
       "std_msgs/Header header\nstring child_frame_id\nTransform transform"},
      {"sensor_msgs/NavSatStatus",
       "int8 STATUS_NO_FIX =  -1\nint8 STATUS_FIX =      0\nint8 STATUS_SBAS_FIX = 1\n"
       "int8 STATUS_GBAS_FIX = 2\nint8 status\nuint16 SERVICE_GPS =     1\n"
       "uint16 SERVICE_GLONASS = 2\nuint16 SERVICE_COMPASS = 4\nuint16 SERVICE_GALILEO = 8\n"
       "uint16 service"},
  };
  return texts;
}

std::string with(const std::string& top, std::initializer_list<const char*> dependencies) {
  // Each text ends in a newline, so a blank line comes before each separator, as in rosbag2.
  std::string out = top + "\n";
  for (const char* d : dependencies) {
    out += "\n" + std::string(80, '=') + "\nMSG: " + d + "\n" + msg_texts().at(d) + "\n";
  }
  return out;
}

struct TypeInfo {
  MessageKind kind;
  const char* name;
  std::string definition;
};

const std::array<TypeInfo, 6>& types() {
  static const std::array<TypeInfo, 6> t = {{
      {MessageKind::kLaserScan, "sensor_msgs/msg/LaserScan",
       with("std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\nfloat32 "
            "angle_increment\nfloat32 time_increment\nfloat32 scan_time\nfloat32 range_min\n"
            "float32 range_max\nfloat32[] ranges\nfloat32[] intensities",
            {"std_msgs/Header", "builtin_interfaces/Time"})},
      {MessageKind::kOdometry, "nav_msgs/msg/Odometry",
       with("std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance "
            "pose\ngeometry_msgs/TwistWithCovariance twist",
            {"std_msgs/Header", "builtin_interfaces/Time", "geometry_msgs/PoseWithCovariance",
             "geometry_msgs/Pose", "geometry_msgs/Point", "geometry_msgs/Quaternion",
             "geometry_msgs/TwistWithCovariance", "geometry_msgs/Twist", "geometry_msgs/Vector3"})},
      {MessageKind::kTransforms, "tf2_msgs/msg/TFMessage",
       with("geometry_msgs/TransformStamped[] transforms",
            {"geometry_msgs/TransformStamped", "std_msgs/Header", "builtin_interfaces/Time",
             "geometry_msgs/Transform", "geometry_msgs/Vector3", "geometry_msgs/Quaternion"})},
      {MessageKind::kJointState, "sensor_msgs/msg/JointState",
       with("std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\n"
            "float64[] effort",
            {"std_msgs/Header", "builtin_interfaces/Time"})},
      {MessageKind::kImu, "sensor_msgs/msg/Imu",
       with("std_msgs/Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] "
            "orientation_covariance\ngeometry_msgs/Vector3 angular_velocity\nfloat64[9] "
            "angular_velocity_covariance\ngeometry_msgs/Vector3 linear_acceleration\n"
            "float64[9] linear_acceleration_covariance",
            {"std_msgs/Header", "builtin_interfaces/Time", "geometry_msgs/Quaternion",
             "geometry_msgs/Vector3"})},
      {MessageKind::kNavSatFix, "sensor_msgs/msg/NavSatFix",
       with("uint8 COVARIANCE_TYPE_UNKNOWN = 0\nuint8 COVARIANCE_TYPE_APPROXIMATED = 1\n"
            "uint8 COVARIANCE_TYPE_DIAGONAL_KNOWN = 2\nuint8 COVARIANCE_TYPE_KNOWN = 3\n"
            "std_msgs/Header header\nNavSatStatus status\nfloat64 latitude\nfloat64 longitude\n"
            "float64 altitude\nfloat64[9] position_covariance\nuint8 position_covariance_type",
            {"std_msgs/Header", "builtin_interfaces/Time", "sensor_msgs/NavSatStatus"})},
  }};
  return t;
}

template <typename T, typename F>
T decode(const std::uint8_t* data, std::size_t size, F&& body) {
  CdrReader r(data, size);
  return body(r);
}

}  // namespace

const char* ros2_type_name(MessageKind kind) {
  for (const TypeInfo& t : types()) {
    if (t.kind == kind) return t.name;
  }
  return nullptr;
}

MessageKind ros2_message_kind(const std::string& type_name) {
  for (const TypeInfo& t : types()) {
    if (type_name == t.name) return t.kind;
  }
  return MessageKind::kOther;
}

const std::string& ros2_definition(MessageKind kind) {
  static const std::string none;
  for (const TypeInfo& t : types()) {
    if (t.kind == kind) return t.definition;
  }
  return none;
}

Stamp ros2_clamped(const Stamp& s) {
  constexpr std::int64_t kMin = std::numeric_limits<std::int32_t>::min();
  constexpr std::int64_t kMax = std::numeric_limits<std::int32_t>::max();
  if (s.sec < kMin) return {kMin, 0};
  if (s.sec > kMax) return {kMax, 999999999};
  return s;
}

ScanMessage decode_ros2_scan(const std::uint8_t* data, std::size_t size) {
  return decode<ScanMessage>(data, size, [](CdrReader& r) {
    ScanMessage m;
    m.header = r.header();
    m.scan.stamp_s = m.header.stamp.seconds();
    m.scan.angle_min_rad = r.read<float>();
    m.angle_max = r.read<float>();
    m.scan.angle_increment_rad = r.read<float>();
    m.time_increment = r.read<float>();
    m.scan.time_increment_s = m.time_increment;
    m.scan_time = r.read<float>();
    m.scan.range_min_m = r.read<float>();
    m.scan.range_max_m = r.read<float>();
    m.scan.ranges_m = r.sequence<float>();
    m.scan.intensities = r.sequence<float>();
    return m;
  });
}

OdometryMessage decode_ros2_odometry(const std::uint8_t* data, std::size_t size) {
  return decode<OdometryMessage>(data, size, [](CdrReader& r) {
    OdometryMessage m;
    m.header = r.header();
    m.child_frame_id = r.string();
    m.pose = read_planar(r);
    m.pose_covariance = r.doubles<36>();
    m.v_mps = r.read<double>();
    m.vy_mps = r.read<double>();
    (void)r.read<double>();
    (void)r.read<double>();
    (void)r.read<double>();
    m.w_radps = r.read<double>();
    m.twist_covariance = r.doubles<36>();
    return m;
  });
}

TransformsMessage decode_ros2_transforms(const std::uint8_t* data, std::size_t size) {
  return decode<TransformsMessage>(data, size, [](CdrReader& r) {
    TransformsMessage m;
    // A TransformStamped is at least 4+4+4+4 (stamp, two empty strings) + 56 (Vector3,
    // Quaternion) bytes long.
    const std::size_t n = r.count(72);
    m.transforms.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
      FrameTransform t;
      const Header h = r.header();
      t.stamp = h.stamp;
      t.parent = h.frame_id;
      t.child = r.string();
      t.child_in_parent = read_planar(r);
      m.transforms.push_back(std::move(t));
    }
    return m;
  });
}

Stamp decode_ros2_clock(const std::uint8_t* data, std::size_t size) {
  return decode<Stamp>(data, size, [](CdrReader& r) { return r.time(); });
}

JointStateMessage decode_ros2_joint_state(const std::uint8_t* data, std::size_t size) {
  return decode<JointStateMessage>(data, size, [](CdrReader& r) {
    JointStateMessage m;
    m.header = r.header();
    const std::size_t n = r.count(4);
    m.names.reserve(n);
    for (std::size_t i = 0; i < n; ++i) m.names.push_back(r.string());
    m.positions = r.sequence<double>();
    m.velocities = r.sequence<double>();
    (void)r.sequence<double>();  // effort
    return m;
  });
}

ImuMessage decode_ros2_imu(const std::uint8_t* data, std::size_t size) {
  return decode<ImuMessage>(data, size, [](CdrReader& r) {
    ImuMessage m;
    m.header = r.header();
    (void)r.doubles<4>();  // orientation
    const std::array<double, 9> orientation_covariance = r.doubles<9>();
    m.has_orientation = orientation_covariance[0] != -1.0;
    const double x = r.read<double>();
    const double y = r.read<double>();
    const double z = r.read<double>();
    m.angular_velocity_radps = {x, y, z};
    (void)r.doubles<9>();
    (void)r.doubles<3>();
    (void)r.doubles<9>();
    return m;
  });
}

NavSatFixMessage decode_ros2_nav_sat_fix(const std::uint8_t* data, std::size_t size) {
  return decode<NavSatFixMessage>(data, size, [](CdrReader& r) {
    NavSatFixMessage m;
    m.header = r.header();
    m.status = r.read<std::int8_t>();
    (void)r.read<std::uint16_t>();  // service
    m.latitude_deg = r.read<double>();
    m.longitude_deg = r.read<double>();
    (void)r.read<double>();  // altitude
    (void)r.doubles<9>();
    (void)r.read<std::uint8_t>();
    return m;
  });
}

std::vector<std::uint8_t> encode_ros2(const ScanMessage& m) {
  CdrWriter w;
  w.header(m.header);
  w.write<float>(static_cast<float>(m.scan.angle_min_rad));
  w.write<float>(m.angle_max);
  w.write<float>(static_cast<float>(m.scan.angle_increment_rad));
  w.write<float>(m.time_increment);
  w.write<float>(m.scan_time);
  w.write<float>(m.scan.range_min_m);
  w.write<float>(m.scan.range_max_m);
  w.sequence(m.scan.ranges_m);
  w.sequence(m.scan.intensities);
  return w.take();
}

std::vector<std::uint8_t> encode_ros2(const OdometryMessage& m) {
  CdrWriter w;
  w.header(m.header);
  w.string(m.child_frame_id);
  w.planar(m.pose);
  for (double c : m.pose_covariance) w.write<double>(c);
  w.write<double>(m.v_mps);
  w.write<double>(m.vy_mps);
  w.zeros(3);
  w.write<double>(m.w_radps);
  for (double c : m.twist_covariance) w.write<double>(c);
  return w.take();
}

std::vector<std::uint8_t> encode_ros2(const TransformsMessage& m) {
  CdrWriter w;
  w.write<std::uint32_t>(static_cast<std::uint32_t>(m.transforms.size()));
  for (const FrameTransform& t : m.transforms) {
    w.time(t.stamp);
    w.string(t.parent);
    w.string(t.child);
    w.planar(t.child_in_parent);
  }
  return w.take();
}

std::vector<std::uint8_t> encode_ros2_diagnostics(
    const Stamp& stamp, const std::vector<pipeline::DiagnosticStatus>& status) {
  CdrWriter w;
  w.header(Header{0, stamp, ""});
  w.write<std::uint32_t>(static_cast<std::uint32_t>(status.size()));
  for (const pipeline::DiagnosticStatus& s : status) {
    w.write<std::uint8_t>(static_cast<std::uint8_t>(s.level));
    w.string(s.name);
    w.string(s.message);
    w.string(s.hardware_id);
    w.write<std::uint32_t>(static_cast<std::uint32_t>(s.values.size()));
    for (const auto& [key, value] : s.values) {
      w.string(key);
      w.string(value);
    }
  }
  return w.take();
}

std::vector<std::uint8_t> encode_ros2(const JointStateMessage& m) {
  CdrWriter w;
  w.header(m.header);
  w.write<std::uint32_t>(static_cast<std::uint32_t>(m.names.size()));
  for (const std::string& n : m.names) w.string(n);
  w.sequence(m.positions);
  w.sequence(m.velocities);
  w.sequence(std::vector<double>{});
  return w.take();
}

std::vector<std::uint8_t> encode_ros2(const ImuMessage& m) {
  CdrWriter w;
  w.header(m.header);
  w.quaternion(0.0);
  w.zeros(9, m.has_orientation ? 0.0 : -1.0);  // REP 145: -1 says there is no orientation.
  w.write<double>(m.angular_velocity_radps.x());
  w.write<double>(m.angular_velocity_radps.y());
  w.write<double>(m.angular_velocity_radps.z());
  w.zeros(9);
  w.zeros(3);
  w.zeros(9);
  return w.take();
}

}  // namespace dispel::io
