#include "dispel/jobs/job.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <utility>

#include "dispel/io/errors.hpp"
#include "dispel/io/ros1_bag.hpp"
#include "dispel/io/rosbag2.hpp"
#include "dispel/io/text.hpp"
#ifdef DISPEL_HAVE_MRPT_RAWLOG
#include "dispel/io/mrpt_rawlog.hpp"
#endif

namespace dispel::jobs {

void check_cancelled(const std::atomic<bool>* cancel) {
  if (cancel != nullptr && cancel->load()) throw JobCancelled();
}

namespace {

// A rosbag2 bag folder: read as a whole, where other inputs must be regular files.
bool is_bag_folder(const std::string& path) {
  std::error_code ec;
  return std::filesystem::is_directory(path, ec) &&
         std::filesystem::exists(std::filesystem::path(path) / "metadata.yaml", ec);
}

}  // namespace

void check_input_file(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) throw JobError(path + ": " + std::strerror(errno));
  if (!S_ISREG(st.st_mode) && !is_bag_folder(path)) {
    throw JobError(path + ": not a regular file (nor a rosbag2 bag folder with metadata.yaml)");
  }
}

void rethrow_as_job_error() {
  try {
    throw;
  } catch (const io::InputError& e) {
    throw JobError(e.what());
  } catch (const io::OutputError& e) {
    throw JobError(e.what());
  } catch (const std::invalid_argument& e) {
    throw JobError(e.what());
  }
}

namespace {

namespace fs = std::filesystem;

std::string file_type(const fs::file_status& st) {
  switch (st.type()) {
    case fs::file_type::directory:
      return "a directory";
    case fs::file_type::fifo:
      return "a FIFO";
    case fs::file_type::character:
      return "a character device";
    case fs::file_type::block:
      return "a block device";
    case fs::file_type::socket:
      return "a socket";
    default:
      return "not a regular file";
  }
}

std::string named(const FileArgument& f) {
  return (f.option.empty() ? "" : f.option + " ") + io::quote(f.path, 200);
}

// Where a file is or would be: for an existing file its inode decides (compared with
// fs::equivalent), for a file not yet written its directory's canonical path and its name.
struct Place {
  bool exists = false;
  bool special = false;  // A device or pipe: written in place.
  fs::path path;         // Canonical when it does not exist yet.
};

Place place_of(const FileArgument& f) {
  std::error_code ec;
  Place p;
  const fs::file_status st = fs::status(f.path, ec);
  p.exists = !ec && fs::exists(st);
  p.special = p.exists && !fs::is_regular_file(st) && !fs::is_directory(st);
  if (p.exists) {
    p.path = f.path;
    return p;
  }
  const fs::path given(f.path);
  fs::path parent = given.parent_path();
  if (parent.empty()) parent = ".";
  const fs::path dir = fs::weakly_canonical(parent, ec);
  p.path = (ec ? parent : dir) / given.filename();
  return p;
}

bool same_file(const Place& a, const Place& b) {
  if (a.exists != b.exists) return false;
  std::error_code ec;
  if (a.exists) return fs::equivalent(a.path, b.path, ec) && !ec;
  return a.path == b.path;
}

void check_output_place(const FileArgument& out) {
  std::error_code ec;
  const fs::file_status st = fs::status(out.path, ec);
  if (!ec && fs::is_directory(st)) throw JobError(named(out) + ": is a directory");
  if (!ec && fs::exists(st) && !fs::is_regular_file(st)) return;  // /dev/null: written in place.
  std::string name = out.path;  // "OUT/" names the bag folder OUT.
  while (name.size() > 1 && name.back() == '/') name.pop_back();
  fs::path parent = fs::path(name).parent_path();
  if (parent.empty()) parent = ".";
  const fs::file_status dir = fs::status(parent, ec);
  if (ec || !fs::exists(dir)) {
    throw JobError(named(out) + ": the directory " + io::quote(parent.string(), 200) +
                   " does not exist");
  }
  if (!fs::is_directory(dir)) {
    throw JobError(named(out) + ": " + io::quote(parent.string(), 200) + " is not a directory");
  }
  if (::access(parent.c_str(), W_OK | X_OK) != 0) {
    throw JobError(named(out) + ": cannot write in " + io::quote(parent.string(), 200) + " (" +
                   std::strerror(errno) + ")");
  }
}

}  // namespace

void check_files(const std::vector<FileArgument>& inputs,
                 const std::vector<FileArgument>& outputs) {
  std::vector<std::pair<const FileArgument*, Place>> in, out;
  for (const FileArgument& f : inputs) {
    if (f.path.empty()) continue;
    std::error_code ec;
    const fs::file_status st = fs::status(f.path, ec);
    if (ec || !fs::exists(st)) continue;  // The reader says "No such file" in its own words.
    if (!fs::is_regular_file(st) && !is_bag_folder(f.path)) {
      throw JobError(named(f) + ": not a regular file (" + file_type(st) + ")");
    }
    in.emplace_back(&f, place_of(f));
  }
  for (const FileArgument& f : outputs) {
    if (f.path.empty()) continue;
    check_output_place(f);
    out.emplace_back(&f, place_of(f));
  }
  for (std::size_t i = 0; i < out.size(); ++i) {
    const auto& [o, place] = out[i];
    for (const auto& [input, input_place] : in) {
      if (same_file(place, input_place)) {
        throw JobError(named(*o) + " is the same file as the input " + named(*input) +
                       "; the input would be overwritten");
      }
      // Nothing is written inside an input bag folder (its storage files, its metadata.yaml).
      std::error_code ec;
      const fs::path folder = fs::weakly_canonical(input->path, ec);
      const fs::path written = fs::weakly_canonical(o->path, ec);
      if (is_bag_folder(input->path) &&
          std::mismatch(folder.begin(), folder.end(), written.begin(), written.end()).first ==
              folder.end()) {
        throw JobError(named(*o) + " is inside the input bag folder " + named(*input) +
                       "; the input would be changed");
      }
    }
    if (place.special) continue;
    for (std::size_t j = 0; j < i; ++j) {
      if (same_file(place, out[j].second)) {
        throw JobError(named(*o) + " and " + named(*out[j].first) +
                       " are the same file; give each output its own");
      }
    }
  }
}

namespace {

using io::ends_with;

}  // namespace

std::unique_ptr<io::RecordingReader> open_recording(const std::string& path) {
  if (ends_with(path, ".rawlog") || ends_with(path, ".rawlog.gz")) {
#ifdef DISPEL_HAVE_MRPT_RAWLOG
    return as_job([&] { return std::make_unique<io::MrptRawlogReader>(path); });
#else
    throw JobError(path + ": this dispel was built without MRPT rawlogs (DISPEL_WITH_MRPT_RAWLOG)");
#endif
  }
  if (io::is_rosbag2_path(path)) {
    return as_job([&] { return std::make_unique<io::Rosbag2Reader>(path); });
  }
  return as_job([&] { return std::make_unique<io::Ros1BagReader>(path); });
}

bool writes_rosbag2(const std::string& path) {
  if (ends_with(path, ".mcap") || ends_with(path, ".db3")) return true;
  if (ends_with(path, ".bag") || path.empty()) return false;
  if (path.back() == '/') return true;
  // A name without an extension is a bag folder, as `ros2 bag record -o NAME` makes one, unless
  // it names something that is not a folder already (a device such as /dev/null, a pipe, a
  // file): that is written as before, a ROS 1 bag.
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (!ec && fs::exists(st) && !fs::is_directory(st)) return false;
  return fs::path(path).extension().empty();
}

std::unique_ptr<io::RecordingWriter> create_recording(const std::string& path,
                                                      Compression compression,
                                                      RecordingFormat format) {
  if (path.empty()) throw JobError("no output file given");
  if (format == RecordingFormat::kByName) {
    format = !writes_rosbag2(path)  ? RecordingFormat::kRos1
             : writes_sqlite3(path) ? RecordingFormat::kSqlite3
                                    : RecordingFormat::kMcap;
  }
  const bool rosbag2_name =
      ends_with(path, ".mcap") || ends_with(path, ".db3") || path.back() == '/';
  if (format == RecordingFormat::kRos1 && rosbag2_name) {
    throw JobError(path + ": the name says rosbag2, the format asked ROS 1: name the output .bag");
  }
  if (format != RecordingFormat::kRos1 && ends_with(path, ".bag")) {
    throw JobError(path +
                   ": the name says a ROS 1 bag, the format asked rosbag2: name the output "
                   ".mcap, .db3 or a folder");
  }
  if (format == RecordingFormat::kRos1) {
    if (compression == Compression::kZstd) {
      throw JobError(path + ": a ROS 1 bag compresses with bz2 or lz4, not zstd");
    }
    const io::BagCompression c = compression == Compression::kBz2   ? io::BagCompression::kBz2
                                 : compression == Compression::kLz4 ? io::BagCompression::kLz4
                                                                    : io::BagCompression::kNone;
    return as_job([&] { return std::make_unique<io::Ros1BagWriter>(path, c); });
  }
  const bool sqlite3 = format == RecordingFormat::kSqlite3;
  if (ends_with(path, sqlite3 ? ".mcap" : ".db3")) {
    throw JobError(path + ": the name says " + (sqlite3 ? "MCAP" : "sqlite3") +
                   " storage, the format asked " + (sqlite3 ? "sqlite3" : "MCAP") +
                   ": name the output .db3, .mcap or a folder to match");
  }
  if (compression == Compression::kBz2 || (sqlite3 && compression != Compression::kNone)) {
    throw JobError(path + (sqlite3 ? ": rosbag2 sqlite3 storage is not compressed"
                                   : ": a rosbag2 MCAP recording compresses its chunks with zstd "
                                     "or lz4, not bz2"));
  }
  const io::Rosbag2Compression c = compression == Compression::kZstd ? io::Rosbag2Compression::kZstd
                                   : compression == Compression::kLz4
                                       ? io::Rosbag2Compression::kLz4
                                       : io::Rosbag2Compression::kNone;
  const io::Rosbag2Storage storage =
      sqlite3 ? io::Rosbag2Storage::kSqlite3 : io::Rosbag2Storage::kMcap;
  return as_job([&] { return std::make_unique<io::Rosbag2Writer>(path, c, storage); });
}

bool writes_sqlite3(const std::string& path) { return ends_with(path, ".db3"); }

RecordingFormat recording_format_named(const std::string& name) {
  if (name == "ros1") return RecordingFormat::kRos1;
  if (name == "mcap") return RecordingFormat::kMcap;
  if (name == "sqlite3") return RecordingFormat::kSqlite3;
  return RecordingFormat::kByName;
}

void copy_or_leave_out(io::RecordingWriter& out, const io::RecordedMessage& message,
                       std::map<std::string, std::int64_t>& left_out) {
  if (out.can_copy(message)) {
    out.copy(message);
  } else {
    ++left_out[message.topic()];
  }
}

void copy_recording(io::RecordingReader& in, io::RecordingWriter& out,
                    std::map<std::string, std::int64_t>& left_out, std::int64_t& messages_in,
                    const std::atomic<bool>* cancel, const Progress& progress,
                    const std::function<void(const io::RecordedMessage&)>& each) {
  std::int64_t all_messages = 0;
  for (const auto& [name, info] : in.topics().all()) all_messages += info.messages;
  in.read({}, [&](const io::RecordedMessage& m) {
    check_cancelled(cancel);
    copy_or_leave_out(out, m, left_out);
    ++messages_in;
    if (progress && messages_in % 256 == 0) {
      progress(static_cast<double>(messages_in) /
               static_cast<double>(std::max<std::int64_t>(1, all_messages)));
    }
    if (each) each(m);
  });
}

std::string left_out_summary(const std::map<std::string, std::int64_t>& left_out) {
  if (left_out.empty()) return "";
  std::int64_t n = 0;
  std::vector<std::string> topics;
  for (const auto& [topic, count] : left_out) {
    n += count;
    topics.push_back(io::quote(topic, 60));
  }
  if (topics.size() > 8) {
    topics.resize(8);
    topics.emplace_back("...");
  }
  return std::to_string(n) + " messages left out on " + io::join_names(topics) +
         " (types that cannot be converted between recording formats)";
}

}  // namespace dispel::jobs
