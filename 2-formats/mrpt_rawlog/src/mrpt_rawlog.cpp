#include "dispel/io/mrpt_rawlog.hpp"

#include <mrpt/io/CMemoryStream.h>
#include <mrpt/math/CMatrixB.h>
#include <mrpt/math/CMatrixD.h>
#include <mrpt/math/CMatrixF.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <set>
#include <utility>

#include "dispel/io/errors.hpp"
#include "dispel/io/text.hpp"

namespace dispel::io {
namespace {

// MRPT's time stamps count 100 ns since 1601-01-01 (mrpt::Clock); the Unix epoch is this many.
constexpr std::int64_t kTicksPerSecond = 10000000;
constexpr std::int64_t kUnixEpochTicks = 116444736000000000;

// A bool member that MRPT's deserialisation filled from the file: it copies the file's byte into
// the bool, so the bool can hold any byte (Debian's localization_demo.rawlog has 90 in
// CActionRobotMovement2D::hasVelocities), and loading it as a bool is undefined behaviour. Its
// byte is read instead: any byte but 0 is true, as MRPT's own code takes it.
static_assert(sizeof(bool) == 1, "a bool is one byte");
bool stored_flag(const bool& flag) {
  unsigned char byte = 0;
  std::memcpy(&byte, &flag, 1);
  return byte != 0;
}

bool has_stamp(const mrpt::Clock::time_point& t) { return t != mrpt::Clock::time_point(); }

// Seconds and ticks are split before the epochs' difference (a whole number of seconds) is taken
// off: a stored time of -2^63 ticks minus the difference overflowed (UBSan, a fuzzer input of CI's
// 30 s run).
static_assert(kUnixEpochTicks % kTicksPerSecond == 0, "the epochs differ by whole seconds");
Stamp to_stamp(const mrpt::Clock::time_point& t) {
  const std::int64_t ticks = t.time_since_epoch().count();
  std::int64_t sec = ticks / kTicksPerSecond;
  std::int64_t rest = ticks % kTicksPerSecond;
  if (rest < 0) {
    rest += kTicksPerSecond;
    --sec;
  }
  return {sec - kUnixEpochTicks / kTicksPerSecond, static_cast<std::uint32_t>(rest * 100)};
}

// The innermost "Message:" line of an MRPT exception (its text is several lines, with a call
// stack), or the first line of any other; printable characters only (a garbage file's bytes end
// up in MRPT's messages).
std::string one_line(const std::exception& e) {
  const std::string text = e.what();
  std::string line;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    std::string l = text.substr(start, end - start);
    const std::size_t m = l.find("Message:");
    if (m != std::string::npos) {
      line = l.substr(m + 8);
    } else if (line.empty() && l.find("====") == std::string::npos &&
               l.find_first_not_of(" \t") != std::string::npos) {
      line = l;
    }
    start = end + 1;
  }
  line.erase(0, std::min(line.find_first_not_of(" \t"), line.size()));
  for (char& c : line) {
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7F) c = '?';
  }
  constexpr std::size_t kMax = 200;
  if (line.size() > kMax) line = line.substr(0, kMax) + "...";
  return line.empty() ? std::string("unknown error") : line;
}

// The file's bytes, uncompressed when it is gzip-compressed (zlib reads a plain file as it is).
std::string read_file(const std::string& path) {
  {
    const std::ifstream probe(path, std::ios::binary);
    if (!probe) throw InputError(path + ": cannot open (" + std::strerror(errno) + ")");
  }
  gzFile f = gzopen(path.c_str(), "rb");
  if (f == nullptr) throw InputError(path + ": cannot open (" + std::strerror(errno) + ")");
  std::string bytes;
  char buffer[1 << 16];
  int n = 0;
  while ((n = gzread(f, buffer, sizeof buffer)) > 0) bytes.append(buffer, static_cast<size_t>(n));
  int code = Z_OK;
  const std::string message = gzerror(f, &code);
  gzclose(f);
  if (n < 0 || (code != Z_OK && code != Z_STREAM_END)) {
    throw InputError(path + ": not a readable MRPT rawlog (the gzip stream " +
                     (code == Z_BUF_ERROR ? std::string("ends early: the file is truncated")
                                          : "is corrupt: " + message) +
                     ")");
  }
  return bytes;
}

// A topic's name from an MRPT sensor label: letters, digits and '_' kept, others '_'.
std::string sanitised(const std::string& label) {
  std::string s = label;
  for (char& c : s) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9');
    if (!ok) c = '_';
  }
  return s;
}

ScanMessage scan_message_of(const mrpt::obs::CObservation2DRangeScan& s, const Stamp& stamp,
                            const std::string& frame, std::uint32_t seq) {
  ScanMessage m;
  m.header = {seq, stamp, frame};
  const std::size_t n = s.getScanSize();
  const double aperture = static_cast<double>(s.aperture);
  LaserScan& scan = m.scan;
  scan.stamp_s = stamp.seconds();
  scan.angle_min_rad = -aperture / 2.0;
  scan.angle_increment_rad = n > 1 ? aperture / static_cast<double>(n - 1) : 0.0;
  scan.range_min_m = 0.0F;
  scan.range_max_m = s.maxRange;
  scan.ranges_m.resize(n);
  // hasIntensity() returns a stored flag too (out of line, in MRPT): stored_flag reads the byte
  // it returned.
  const bool returned = s.hasIntensity();
  const bool intensity = stored_flag(returned);
  const bool right_to_left = stored_flag(s.rightToLeft);
  if (intensity) scan.intensities.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    // Right to left: beam k is at angle_min + k * increment. Otherwise the beams are mirrored:
    // MRPT's beam k is at +aperture/2 - k * increment, our beam n-1-k.
    const std::size_t i = right_to_left ? k : n - 1 - k;
    scan.ranges_m[k] =
        s.getScanRangeValidity(i) ? s.getScanRange(i) : std::numeric_limits<float>::quiet_NaN();
    if (intensity) scan.intensities[k] = static_cast<float>(s.getScanIntensity(i));
  }
  m.angle_max = static_cast<float>(n > 1 ? aperture / 2.0 : scan.angle_min_rad);
  return m;
}

std::uint32_t u32_at(const std::string& bytes, std::size_t at) {
  std::uint32_t v = 0;
  for (std::size_t k = 0; k < 4; ++k) {  // Little-endian, as MRPT stores it.
    v |= static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[at + k])) << (8 * k);
  }
  return v;
}

// The stored object's class name at @p pos (without its namespace), and where its version byte
// is; empty when there is no header of MRPT 2's form there.
std::pair<std::string, std::size_t> object_header(const std::string& bytes, std::size_t pos) {
  if (pos >= bytes.size()) return {};
  const auto head = static_cast<unsigned char>(bytes[pos]);
  if ((head & 0x80U) == 0) return {};
  const std::size_t version_at = pos + 1 + (head & 0x7FU);
  if (version_at >= bytes.size()) return {};
  std::string name = bytes.substr(pos + 1, head & 0x7FU);
  name.erase(std::min(name.find('\0'), name.size()));  // MRPT reads it up to its first NUL.
  const std::size_t colons = name.rfind("::");
  if (colons != std::string::npos) name.erase(0, colons + 2);
  return {name, version_at};
}

// MRPT sizes a container from the count it reads before it reads any element: a CSensoryFrame
// of 0x746e0001 observations had a deque of 31 GiB of pointers made and zeroed, page by page,
// from a 1.7 kB file (the fuzzer, in its first minute). The counts of the two containers a log's
// top level is made of are checked against the bytes left before MRPT reads the object: each
// element is an object of at least one byte. An object as MRPT 2 stores it: a byte 0x80 | the
// length of the class's name, the name, a version byte, the object's fields. The check's message,
// or empty when the object at @p pos is not one of these (MRPT reads and checks the rest).
std::string container_count_error(const std::string& bytes, std::size_t pos) {
  // MRPT 2 writes the class's full name (mrpt::obs::CSensoryFrame), older MRPT the short one.
  const auto [name, version_at] = object_header(bytes, pos);
  if (name.empty()) return {};
  const auto version = static_cast<unsigned char>(bytes[version_at]);
  std::size_t count_at = 0;
  const char* what = nullptr;
  if (name == "CSensoryFrame" && version == 2) {
    count_at = version_at + 1;
    what = "observations";
  } else if (name == "CActionCollection" && version == 0) {
    count_at = version_at + 1;
    what = "actions";
  } else {
    return {};
  }
  if (count_at + 4 > bytes.size()) return {};  // MRPT finds it cut (WholeReadsStream).
  const std::uint32_t count = u32_at(bytes, count_at);
  const std::size_t left = bytes.size() - (count_at + 4);
  if (count <= left) return {};
  return "a " + name + " of " + std::to_string(count) + " " + what + " in the " +
         std::to_string(left) + " bytes left";
}

// The stored objects, anywhere in the log's bytes, whose stored name contains @p key and names a
// class @p accept takes (a TRuntimeClassId), as MRPT resolves it: calls @p f(start, version_at,
// id) for each until it returns true, start the header byte (0x80 | the stored name's length) and
// version_at the byte after the whole stored name. MRPT takes the stored name as a C string, up to
// its first NUL, and looks it up in its class registry: the full name ("mrpt::math::CMatrixD"),
// else the name after its last "::" (older logs), which includes the names registered for old
// classes ("CMatrix", MRPT 1's CMatrixF). So every header byte up to 127 bytes before an occurrence
// of @p key is a candidate, and MRPT's own lookup (findRegisteredClass) says which class it makes.
// The fuzzer found each way round a check that spelt the names out: a 40-byte name, "CMatrixD" and
// a NUL; "CMatrix" and a NUL; 77 bytes of name ending "mrpt::math::CMatrix".
template <typename Accept, typename F>
void each_stored_object(const std::string& bytes, const std::string& key, const Accept& accept,
                        const F& f) {
  for (std::size_t at = bytes.find(key); at != std::string::npos; at = bytes.find(key, at + 1)) {
    const std::size_t first = at >= 127 ? at - 127 : 0;
    for (std::size_t start = at; start-- > first;) {
      const auto head = static_cast<unsigned char>(bytes[start]);
      const std::size_t stored = head & 0x7FU;
      const std::size_t version_at = start + 1 + stored;
      if ((head & 0x80U) == 0 || version_at < at + key.size() || version_at >= bytes.size()) {
        continue;
      }
      std::string name = bytes.substr(start + 1, stored);
      name.erase(std::min(name.find('\0'), name.size()));
      if (name.size() < at + key.size() - (start + 1)) continue;  // A NUL before the key's end.
      const mrpt::rtti::TRuntimeClassId* id = mrpt::rtti::findRegisteredClass(name);
      if (id != nullptr && accept(id) && f(start, version_at, id)) return;
    }
  }
}

// MRPT makes a matrix object's storage (rows x cols, with its aligned allocator) before it reads
// the values, and does not check the allocation: when it cannot be made MRPT writes through a
// null pointer (SIGSEGV, with or without ASan: a CMatrixD of 262144 x 1291845636 doubles, the
// mount pose of a scan, from the fuzzer). Every stored CMatrixD, CMatrixF and CMatrixB object
// (version 0: rows, cols, the values; CMatrixB stores the size of a bool before them) is found in
// the log's bytes, at any depth, and one with more values than the bytes after it refuses the log
// before MRPT reads any of it. (The 9 or more bytes of a matrix's header are not checked for where
// they stand; inside another field's bytes they would be a coincidence of 2^-72 per byte.) The
// check's message, or empty.
std::string oversized_matrix_error(const std::string& bytes) {
  struct Kind {
    const mrpt::rtti::TRuntimeClassId* id;
    const char* name;
    std::size_t value_bytes;
    std::size_t before_rows;  // Bytes between the version byte and the rows.
  };
  // MRPT 2's matrix classes (libs/math's registerAllClasses); each of their names contains
  // "CMatrix". A CMatrixB stores the size of a bool before its rows (4294963200 x 1024 bools was
  // the same SIGSEGV).
  const std::array<Kind, 3> kinds = {Kind{CLASS_ID(mrpt::math::CMatrixD), "CMatrixD", 8, 0},
                                     Kind{CLASS_ID(mrpt::math::CMatrixF), "CMatrixF", 4, 0},
                                     Kind{CLASS_ID(mrpt::math::CMatrixB), "CMatrixB", 1, 4}};
  const auto kind_of = [&](const mrpt::rtti::TRuntimeClassId* id) {
    return std::find_if(kinds.begin(), kinds.end(), [&](const Kind& k) { return k.id == id; });
  };
  std::string error;
  each_stored_object(
      bytes, "CMatrix", [&](const auto* id) { return kind_of(id) != kinds.end(); },
      [&](std::size_t start, std::size_t version_at, const mrpt::rtti::TRuntimeClassId* id) {
        const Kind& kind = *kind_of(id);
        const std::size_t rows_at = version_at + 1 + kind.before_rows;
        if (rows_at + 8 > bytes.size() || bytes[version_at] != 0) return false;
        const std::uint64_t rows = u32_at(bytes, rows_at);
        const std::uint64_t cols = u32_at(bytes, rows_at + 4);
        const std::uint64_t left = bytes.size() - (rows_at + 8);
        // rows * cols * value_bytes may not fit in 64 bits (2^32 * 2^32 * 8): divided instead.
        if (rows == 0 || cols <= left / kind.value_bytes / rows) return false;
        error = std::string("a ") + kind.name + " of " + std::to_string(rows) + " x " +
                std::to_string(cols) + " values at byte " + std::to_string(start) +
                ", more than the " + std::to_string(left) + " bytes after it";
        return true;
      });
  return error;
}

// Whether MRPT reads a stored object of class @p name as a @p base: the class is registered, is
// not abstract, and derives from @p base. Where MRPT reads a pointer to an object of a base class
// into its deepcopy_poly_ptr (a CActionCollection's actions, a CActionRobotMovement2D's pose
// change), it copies the object it read through the pointer without checking it: an abstract
// class (MRPT makes no object, so a null pointer; the fuzzer stored a "CAction" in a collection),
// the stored null pointer ("nullptr") and a class of another kind (its cast gives null) are a
// SIGSEGV. (The collections are read by ObjectReader, which checks the object MRPT made.)
bool makes_a(const std::string& name, const mrpt::rtti::TRuntimeClassId* base) {
  // MRPT takes the stored name as a C string: up to its first NUL.
  const mrpt::rtti::TRuntimeClassId* id = mrpt::rtti::findRegisteredClass(name.c_str());
  return id != nullptr && id->ptrCreateObject && id->derivedFrom(base);
}

// A CActionRobotMovement2D (versions 4 to 7: the estimation method, then for odometry the raw
// increment, a CPose2D, and the motion model's parameters; otherwise the pose change, a CPosePDF)
// that MRPT cannot read safely:
// - another estimation method than odometry with an object that is not a CPosePDF where the pose
//   change is: MRPT casts it to a CPosePDF, gets null, and copies through it (SIGSEGV, from the
//   fuzzer: the method of Debian's localization_demo's first action changed);
// - Thrun's motion model (1) with more than kMaxParticles particles: MRPT draws them all when it
//   reads the action (2^32 - 1 at most: hundreds of GiB).
// The check's message, or empty.
constexpr std::uint32_t kMaxParticles = 100000;
std::string movement_error(const std::string& bytes) {
  const auto* movement = CLASS_ID(mrpt::obs::CActionRobotMovement2D);
  std::string error;
  const auto check = [&](std::size_t start, std::size_t version_at) -> std::string {
    if (version_at + 5 > bytes.size()) return {};
    const auto version = static_cast<unsigned char>(bytes[version_at]);
    if (version < 4 || version > 7) return {};
    const std::uint32_t method = u32_at(bytes, version_at + 1);
    const auto [inner, inner_version_at] = object_header(bytes, version_at + 5);
    if (inner.empty()) return {};  // MRPT refuses what follows.
    if (method != 0) {
      if (makes_a(inner, CLASS_ID(mrpt::poses::CPosePDF))) return {};
      return "a CActionRobotMovement2D at byte " + std::to_string(start) +
             " of estimation method " + std::to_string(method) + " whose pose change is " +
             quote(inner.c_str()) + ", not a CPosePDF MRPT can make";  // The file's bytes.
    }
    // Odometry: a CPose2D of version 1 (3 doubles, the end byte), then the model (4 bytes), 6
    // floats, the number of particles.
    if (inner != "CPose2D" || bytes[inner_version_at] != 1) return {};
    const std::size_t model_at = inner_version_at + 1 + 24 + 1;
    if (model_at + 4 + 24 + 4 > bytes.size()) return {};
    const std::uint32_t model = u32_at(bytes, model_at);
    const std::uint32_t particles = u32_at(bytes, model_at + 4 + 24);
    if (model != 1 || particles <= kMaxParticles) return {};
    return "a CActionRobotMovement2D at byte " + std::to_string(start) + " asking for " +
           std::to_string(particles) + " particles of Thrun's motion model (more than " +
           std::to_string(kMaxParticles) + ")";
  };
  each_stored_object(
      bytes, "CActionRobotMovement2D", [&](const auto* id) { return id == movement; },
      [&](std::size_t start, std::size_t version_at, const auto* /*id*/) {
        error = check(start, version_at);
        return !error.empty();
      });
  return error;
}

// The log's bytes as MRPT reads them, except that a read the bytes left cannot fill reads
// nothing. MRPT takes a short read for a whole one (CArchive::ReadBuffer fails only when nothing
// was read) and keeps whatever the rest of the field held: a matrix whose columns were cut by the
// end of the log after 2 of their 4 bytes got the other 2 from the stack, and MRPT sized it as
// 29761129 x 29788296 doubles (the fuzzer; the SIGSEGV of the matrix check above, which skipped a
// header it took for one MRPT finds truncated). With nothing read, MRPT throws "(EOF?) Cannot read
// requested number of bytes from stream": every field cut by the end of the log, of any class, is
// a truncated log.
class WholeReadsStream : public mrpt::io::CMemoryStream {
 public:
  size_t Read(void* buffer, size_t count) override {
    if (count > getTotalBytesCount() - getPosition()) return 0;
    return CMemoryStream::Read(buffer, count);
  }
};

// Reads a log's next object for the converter. MRPT reads each object, except the two
// containers it reads through pointers it does not check or sizes from their counts:
// - a CActionCollection (version 0: the number of actions, the actions): each action is read
//   and checked here (makes_a), so that MRPT never copies through a null one;
// - a whole CRawlog (version 0, or 1 with a CObservationComment after the entries): its entries
//   are read as the log's own, so a collection or a count inside is checked as at the top
//   level; at most kMaxLogDepth of them inside each other (each read is a call deeper).
// Then the byte that ends every object MRPT 2 stores. Throws std::runtime_error with the message.
constexpr int kMaxLogDepth = 8;
struct ObjectReader {
  const std::string& bytes;
  mrpt::io::CMemoryStream& stream;
  mrpt::serialization::CArchive& archive;

  // Appends what the object holds for the converter to @p out: the object, or a collection's
  // actions, or a CRawlog's entries.
  void read(std::vector<mrpt::serialization::CSerializable::Ptr>& out, int depth) {
    const auto pos = static_cast<std::size_t>(stream.getPosition());
    if (depth > 0) {  // The top level's, with its own message, checked by the caller.
      const std::string count_error = container_count_error(bytes, pos);
      if (!count_error.empty()) throw std::runtime_error(count_error + " in a CRawlog");
    }
    const auto [name, version_at] = object_header(bytes, pos);
    const int version = name.empty() ? -1 : static_cast<unsigned char>(bytes[version_at]);
    const bool collection = name == "CActionCollection" && version == 0;
    const bool log = name == "CRawlog" && (version == 0 || version == 1);
    if (!collection && !log) {
      out.push_back(archive.ReadObject());
      if (!out.back()) throw std::runtime_error("a null object");
      return;
    }
    if (log && depth == kMaxLogDepth) {
      throw std::runtime_error("CRawlogs nested more than " + std::to_string(kMaxLogDepth) +
                               " deep");
    }
    stream.Seek(static_cast<std::uint64_t>(version_at) + 1);
    std::uint32_t count = 0;
    archive >> count;
    for (std::uint32_t k = 0; k < count; ++k) {
      if (log) {
        read(out, depth + 1);
        continue;
      }
      // The stored class's name, for the message: MRPT makes nothing of an abstract one.
      const std::string stored =
          object_header(bytes, static_cast<std::size_t>(stream.getPosition())).first;
      out.push_back(archive.ReadObject());
      if (!std::dynamic_pointer_cast<mrpt::obs::CAction>(out.back())) {
        throw std::runtime_error("action " + std::to_string(k) + " of a CActionCollection is " +
                                 (stored.empty() ? std::string("null") : quote(stored.c_str())) +
                                 ", not an action MRPT can make");
      }
    }
    if (log && version == 1) archive.ReadObject();  // The log's comment: not converted.
    constexpr std::uint8_t kObjectEnd = 0x88;
    std::uint8_t end = 0;
    archive >> end;
    if (end != kObjectEnd) throw std::runtime_error("a " + name + " goes on after its entries");
  }
};

constexpr const char* kOdomTopic = "/odom";
constexpr const char* kMountTopic = "/tf_static";

// Turns the rawlog's objects, in file order, into entries.
class Converter {
 public:
  explicit Converter(std::vector<DecodedMessage>& entries,
                     std::map<std::string, std::int64_t>& skipped)
      : entries_(entries), skipped_(skipped) {}

  void object(const mrpt::serialization::CSerializable::Ptr& obj) {
    if (auto actions = std::dynamic_pointer_cast<mrpt::obs::CActionCollection>(obj)) {
      for (std::size_t i = 0; i < actions->size(); ++i) action(actions->get(i));
    } else if (auto a = std::dynamic_pointer_cast<mrpt::obs::CAction>(obj)) {
      action(a);  // Of a collection ObjectReader read.
    } else if (auto frame = std::dynamic_pointer_cast<mrpt::obs::CSensoryFrame>(obj)) {
      sensory_frame(*frame);
    } else if (auto o = std::dynamic_pointer_cast<mrpt::obs::CObservation>(obj)) {
      observation(o);
    } else {
      skip(*obj);
    }
  }

  // An odometry increment with no sensory frame after it (the end of the log) is stated at its
  // action's stamp, or the last stamp seen.
  void finish() { state_pending(); }

 private:
  void skip(const mrpt::rtti::CObject& o) { ++skipped_[o.GetRuntimeClass()->className]; }

  void action(const mrpt::obs::CAction::Ptr& a) {
    const auto move = std::dynamic_pointer_cast<mrpt::obs::CActionRobotMovement2D>(a);
    if (!move) {
      skip(*a);
      return;
    }
    state_pending();  // The previous action, when no sensory frame came since.
    // The robot is at the identity where the log starts: state it at the first observation when
    // that comes before the first action (its scan then has a pose).
    if (!integrating_ && first_observation_) {
      odometry_entry(*first_observation_, Pose2{}, 0.0, 0.0);
    }
    integrating_ = true;
    if (!move->poseChange) {  // MRPT leaves none when it read no pose change.
      skip(*a);
      return;
    }
    const mrpt::poses::CPose2D d = move->poseChange->getMeanVal();
    pose_ = pose_ * Pose2{d.x(), d.y(), d.phi()};
    const bool velocities = stored_flag(move->hasVelocities);
    v_ = velocities ? move->velocityLocal.vx : 0.0;
    w_ = velocities ? move->velocityLocal.omega : 0.0;
    // MRPT's actions-observations convention: an action is the robot's motion from the previous
    // sensory frame to the next one (what CMetricMapBuilder::processActionObservation composes
    // before it inserts that frame), so the pose it leads to is the next frame's. Its own stamp
    // (MRPT's grabber puts it half-way between the two frames) would put the pose half a scan
    // early: 0.1 m at 1 m/s on Debian's wheelchair log.
    pending_ = true;
    pending_stamp_.reset();
    if (has_stamp(move->timestamp)) pending_stamp_ = to_stamp(move->timestamp);
  }

  void state_pending() {
    if (!pending_) return;
    if (pending_stamp_) {
      odometry_at(*pending_stamp_);
    } else if (last_stamp_) {
      odometry_at(*last_stamp_);
    }
    pending_ = false;
  }

  void sensory_frame(const mrpt::obs::CSensoryFrame& frame) {
    std::optional<Stamp> earliest;
    for (const auto& o : frame) {
      if (o && has_stamp(o->timestamp)) {
        const Stamp s = to_stamp(o->timestamp);
        if (!earliest || s < *earliest) earliest = s;
      }
    }
    if (pending_ && earliest) odometry_at(*earliest);
    for (const auto& o : frame) {
      if (o) observation(o);
    }
  }

  void observation(const mrpt::obs::CObservation::Ptr& o) {
    if (!has_stamp(o->timestamp)) {
      ++skipped_[std::string(o->GetRuntimeClass()->className) + " without a time stamp"];
      return;
    }
    const Stamp stamp = to_stamp(o->timestamp);
    last_stamp_ = stamp;
    if (!first_observation_) first_observation_ = stamp;
    if (auto scan = std::dynamic_pointer_cast<mrpt::obs::CObservation2DRangeScan>(o)) {
      laser(*scan, stamp);
    } else if (auto odom = std::dynamic_pointer_cast<mrpt::obs::CObservationOdometry>(o)) {
      const mrpt::poses::CPose2D& p = odom->odometry;
      const bool velocities = stored_flag(odom->hasVelocities);
      odometry_entry(stamp, Pose2{p.x(), p.y(), p.phi()}, velocities ? odom->velocityLocal.vx : 0.0,
                     velocities ? odom->velocityLocal.omega : 0.0);
    } else {
      skip(*o);
    }
  }

  void laser(const mrpt::obs::CObservation2DRangeScan& s, const Stamp& stamp) {
    const std::string name = s.sensorLabel.empty() ? std::string() : sanitised(s.sensorLabel);
    const std::string topic = "/" + (name.empty() ? std::string("scan") : name);
    const std::string frame = name.empty() ? std::string("laser") : name;
    const Pose2 mount{s.sensorPose.x(), s.sensorPose.y(), s.sensorPose.yaw()};
    const auto known = mounts_.find(frame);
    if (known == mounts_.end() || known->second.x_m != mount.x_m ||
        known->second.y_m != mount.y_m || known->second.yaw_rad != mount.yaw_rad) {
      mounts_[frame] = mount;
      TransformsMessage tf;
      tf.transforms.push_back({stamp, "base_link", frame, mount});
      entries_.emplace_back(kMountTopic, stamp, std::move(tf));
    }
    entries_.emplace_back(topic, stamp, scan_message_of(s, stamp, frame, seq_[topic]++));
  }

  void odometry_at(const Stamp& stamp) {
    pending_ = false;
    odometry_entry(stamp, pose_, v_, w_);
  }

  void odometry_entry(const Stamp& stamp, const Pose2& pose, double v, double w) {
    OdometryMessage m;
    m.header = {seq_[kOdomTopic]++, stamp, "odom"};
    m.child_frame_id = "base_link";
    m.pose = pose;
    m.v_mps = v;
    m.w_radps = w;
    entries_.emplace_back(kOdomTopic, stamp, std::move(m));
  }

  std::vector<DecodedMessage>& entries_;
  std::map<std::string, std::int64_t>& skipped_;
  std::map<std::string, Pose2> mounts_;  // By frame: the last mount stated.
  std::map<std::string, std::uint32_t> seq_;
  Pose2 pose_;  // The integrated odometry.
  double v_ = 0.0, w_ = 0.0;
  bool integrating_ = false;
  bool pending_ = false;  // pose_ has an increment not yet stated (no sensory frame since).
  std::optional<Stamp> pending_stamp_;  // Its action's stamp, if it had one.
  std::optional<Stamp> first_observation_, last_stamp_;
};

}  // namespace

struct MrptRawlogReader::Impl {
  std::string path;
  std::vector<DecodedMessage> entries;
  Topics topics;
  std::map<std::string, std::int64_t> skipped;
  std::int64_t skipped_count = 0;
};

MrptRawlogReader::MrptRawlogReader(const std::string& path) : impl_(std::make_unique<Impl>()) {
  impl_->path = path;
  const std::string bytes = read_file(path);
  // What MRPT would crash on or grow without bound from, refused before it reads anything.
  for (const std::string& error : {oversized_matrix_error(bytes), movement_error(bytes)}) {
    if (!error.empty()) throw InputError(path + ": not a readable MRPT rawlog (" + error + ")");
  }
  WholeReadsStream stream;
  stream.assignMemoryNotOwn(bytes.data(), bytes.size());
  auto archive = mrpt::serialization::archiveFrom(stream);
  Converter converter(impl_->entries, impl_->skipped);
  std::int64_t objects = 0;
  // The log ends where the bytes end: an error reading an object that starts before is a
  // truncated or corrupt log.
  while (stream.getPosition() < bytes.size()) {
    const std::string count_error =
        container_count_error(bytes, static_cast<std::size_t>(stream.getPosition()));
    if (!count_error.empty()) {
      throw InputError(path + ": not a readable MRPT rawlog (" +
                       (objects == 0 ? std::string()
                                     : "corrupt after " + std::to_string(objects) + " objects: ") +
                       count_error + ")");
    }
    std::vector<mrpt::serialization::CSerializable::Ptr> read;
    try {
      ObjectReader{bytes, stream, archive}.read(read, 0);
    } catch (const std::exception& e) {
      throw InputError(
          path + ": not a readable MRPT rawlog (" +
          (objects == 0 ? std::string()
                        : "truncated or corrupt after " + std::to_string(objects) + " objects: ") +
          one_line(e) + ")");
    }
    ++objects;
    for (const auto& obj : read) converter.object(obj);
  }
  if (objects == 0) throw InputError(path + ": not a readable MRPT rawlog (the file is empty)");
  converter.finish();

  std::stable_sort(
      impl_->entries.begin(), impl_->entries.end(),
      [](const DecodedMessage& a, const DecodedMessage& b) { return a.time() < b.time(); });
  std::map<std::string, TopicInfo> topics;
  for (const DecodedMessage& e : impl_->entries) {
    TopicInfo& info = topics[e.topic()];
    info.type = message_kind_name(e.kind());
    info.kind = e.kind();
    ++info.messages;
  }
  impl_->topics = Topics(std::move(topics));
  for (const auto& [name, count] : impl_->skipped) impl_->skipped_count += count;
}

MrptRawlogReader::~MrptRawlogReader() = default;

const std::string& MrptRawlogReader::path() const { return impl_->path; }
const Topics& MrptRawlogReader::topics() const { return impl_->topics; }

Stamp MrptRawlogReader::begin_time() const {
  return impl_->entries.empty() ? Stamp{} : impl_->entries.front().time();
}

Stamp MrptRawlogReader::end_time() const {
  return impl_->entries.empty() ? Stamp{} : impl_->entries.back().time();
}

void MrptRawlogReader::read(const std::vector<std::string>& topics,
                            const std::function<void(const RecordedMessage&)>& visit) {
  const std::set<std::string> wanted(topics.begin(), topics.end());
  for (const DecodedMessage& e : impl_->entries) {
    if (!wanted.empty() && wanted.count(e.topic()) == 0) continue;
    try {
      visit(e);
    } catch (const StopReading&) {
      return;
    }
  }
}

const std::map<std::string, std::int64_t>& MrptRawlogReader::skipped() const {
  return impl_->skipped;
}

std::int64_t MrptRawlogReader::skipped_count() const { return impl_->skipped_count; }

}  // namespace dispel::io
