#include "dispel/jobs/convert_job.hpp"

#include <memory>

namespace dispel::jobs {

ConvertJobStats run_convert_job(const ConvertJobOptions& o, const Progress& progress,
                                const std::atomic<bool>* cancel) {
  ConvertJobStats stats;
  const std::unique_ptr<io::RecordingReader> in = open_recording(o.input);
  stats.input_format = in->format_name();
  const std::unique_ptr<io::RecordingWriter> out =
      create_recording(o.output, o.compression, o.format);
  as_job([&] {
    copy_recording(*in, *out, stats.left_out, stats.messages_in, cancel, progress);
    out->finish();
  });
  stats.messages_out = out->messages_written();
  if (progress) progress(1.0);
  return stats;
}

}  // namespace dispel::jobs
