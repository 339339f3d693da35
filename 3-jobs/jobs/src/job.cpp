#include "dispel/jobs/job.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>

#include "dispel/io/errors.hpp"
#include "dispel/io/ros1_bag.hpp"
#ifdef DISPEL_HAVE_MRPT_RAWLOG
#include "dispel/io/mrpt_rawlog.hpp"
#endif

namespace dispel::jobs {

void check_cancelled(const std::atomic<bool>* cancel) {
  if (cancel != nullptr && cancel->load()) throw JobCancelled();
}

void check_input_file(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) throw JobError(path + ": " + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) throw JobError(path + ": not a regular file");
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

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

std::unique_ptr<io::RecordingReader> open_recording(const std::string& path) {
  if (ends_with(path, ".rawlog") || ends_with(path, ".rawlog.gz")) {
#ifdef DISPEL_HAVE_MRPT_RAWLOG
    return as_job([&] { return std::make_unique<io::MrptRawlogReader>(path); });
#else
    throw JobError(path + ": this dispel was built without MRPT rawlogs (DISPEL_WITH_MRPT_RAWLOG)");
#endif
  }
  return as_job([&] { return std::make_unique<io::Ros1BagReader>(path); });
}

std::unique_ptr<io::RecordingWriter> create_recording(const std::string& path,
                                                      Compression compression) {
  if (path.empty()) throw JobError("no output file given");
  const io::BagCompression c = compression == Compression::kBz2   ? io::BagCompression::kBz2
                               : compression == Compression::kLz4 ? io::BagCompression::kLz4
                                                                  : io::BagCompression::kNone;
  return as_job([&] { return std::make_unique<io::Ros1BagWriter>(path, c); });
}

}  // namespace dispel::jobs
