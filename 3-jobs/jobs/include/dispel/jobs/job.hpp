#pragma once
/// @file
/// What every job (a recording in, a file out: dispel filter, odom, eval, sim, render, slam)
/// shares: its one error type, cancellation and progress, and the recording formats by file name.

#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "dispel/io/recording.hpp"

namespace dispel::jobs {

/// A recording, file or configuration that cannot be processed; what() is one line naming it.
class JobError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Thrown when the job's cancel flag became true; no output is written.
class JobCancelled : public std::runtime_error {
 public:
  JobCancelled() : std::runtime_error("interrupted") {}
};

/// Called now and then with the fraction done, in [0, 1].
using Progress = std::function<void(double)>;

/// @throws JobCancelled when @p cancel is set and true.
void check_cancelled(const std::atomic<bool>* cancel);

/// @throws JobError "<path>: <reason>" unless @p path is a regular file that exists.
void check_input_file(const std::string& path);

/// A file a command reads or writes, with the option that names it ("-o", "--stats", "input").
struct FileArgument {
  std::string option;
  std::string path;
};

/// Checks, before any work, the files of one command:
/// - every input that exists is a regular file (a directory or a FIFO is refused by its type,
///   never opened; a missing input is left to the reader, which names it);
/// - every output's directory exists and is writable, and the output is not a directory;
/// - no output is the same file as an input or as another output: the same inode for files that
///   exist (std::filesystem::equivalent), the same canonical directory and name for outputs not
///   yet written. A device or pipe output (/dev/null) is written in place and may repeat.
/// Empty paths are skipped. @throws JobError naming the option(s) and the file
void check_files(const std::vector<FileArgument>& inputs, const std::vector<FileArgument>& outputs);

/// Opens a recording by its file's name: an MRPT rawlog for ".rawlog" or ".rawlog.gz" (plain or
/// gzip-compressed), a rosbag2 recording for a folder or a ".mcap" file, a ROS 1 bag otherwise.
/// @throws JobError "<path>: not a readable ROS 1 bag
/// (...)" or "<path>: not a readable MRPT rawlog (...)" (a missing file too: callers that want "No
/// such file" say so first, check_input_file)
std::unique_ptr<io::RecordingReader> open_recording(const std::string& path);

/// How a recording is written.
enum class Compression { kNone, kBz2, kLz4, kZstd };

/// True when create_recording() writes rosbag2 at @p path: a name ending in ".mcap" or ".db3" (one
/// file, MCAP or sqlite3), in "/" or without an extension (a bag folder; unless it names a file,
/// device or pipe that exists). Anything else is a ROS 1 bag.
bool writes_rosbag2(const std::string& path);

/// True for a name ending in ".db3": rosbag2 sqlite3, which is never compressed.
bool writes_sqlite3(const std::string& path);

/// The format of a recording to write: by its name (writes_rosbag2(): ".db3" sqlite3, other
/// rosbag2 names MCAP, else ROS 1), or as asked (`--format`).
enum class RecordingFormat { kByName, kRos1, kMcap, kSqlite3 };
/// "ros1", "mcap", "sqlite3" as a RecordingFormat; anything else kByName.
RecordingFormat recording_format_named(const std::string& name);

/// Starts a recording at @p path in @p format (a rosbag2 storage asked for writes a bag folder
/// unless the name ends in its own extension; a name with the other one is refused). bz2 is ROS 1's
/// only compression, zstd MCAP's only; sqlite3 is not compressed. Nothing appears there until its
/// finish(). @throws JobError
std::unique_ptr<io::RecordingWriter> create_recording(
    const std::string& path, Compression compression = Compression::kNone,
    RecordingFormat format = RecordingFormat::kByName);

/// Copies @p message to @p out when it can (RecordingWriter::can_copy); else counts it under its
/// topic in @p left_out: a message of a type that cannot be converted between formats.
void copy_or_leave_out(io::RecordingWriter& out, const io::RecordedMessage& message,
                       std::map<std::string, std::int64_t>& left_out);
/// Reads every message of @p in, in time order, and copies it to @p out (copy_or_leave_out),
/// then gives it to @p each when there is one; counts into @p messages_in, reports @p progress
/// every 256 messages, stops with JobCancelled when @p cancel is set. Does not finish @p out.
void copy_recording(io::RecordingReader& in, io::RecordingWriter& out,
                    std::map<std::string, std::int64_t>& left_out, std::int64_t& messages_in,
                    const std::atomic<bool>* cancel, const Progress& progress,
                    const std::function<void(const io::RecordedMessage&)>& each = {});
/// "N messages on /a, /b (types that cannot be converted between formats)", or "" for none.
std::string left_out_summary(const std::map<std::string, std::int64_t>& left_out);

/// The current exception (an io error or std::invalid_argument) as JobError.
[[noreturn]] void rethrow_as_job_error();

/// Runs @p fn; the errors of dispel::io (InputError, ConfigError, OutputError) and a bad value
/// the core refuses (std::invalid_argument) come out as JobError with the same message.
template <typename Fn>
auto as_job(Fn&& fn) -> decltype(fn()) {
  try {
    return fn();
  } catch (const JobError&) {
    throw;
  } catch (const JobCancelled&) {
    throw;
  } catch (...) {
    rethrow_as_job_error();
  }
}

}  // namespace dispel::jobs
