#pragma once
/// @file
/// What every job (a recording in, a file out: dispel filter, odom, eval, sim, render, slam)
/// shares: its one error type, cancellation and progress, and the recording formats by file name.

#include <atomic>
#include <functional>
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
/// gzip-compressed), a ROS 1 bag otherwise. @throws JobError "<path>: not a readable ROS 1 bag
/// (...)" or "<path>: not a readable MRPT rawlog (...)" (a missing file too: callers that want "No
/// such file" say so first, check_input_file)
std::unique_ptr<io::RecordingReader> open_recording(const std::string& path);

/// How a recording is written.
enum class Compression { kNone, kBz2, kLz4 };

/// Starts a recording at @p path: a ROS 1 bag. Nothing appears there until its finish().
/// @throws JobError
std::unique_ptr<io::RecordingWriter> create_recording(const std::string& path,
                                                      Compression compression = Compression::kNone);

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
