#include "dispel/jobs/convert_job.hpp"

#include <algorithm>
#include <memory>

namespace dispel::jobs {

ConvertJobStats run_convert_job(const ConvertJobOptions& o, const Progress& progress,
                                const std::atomic<bool>* cancel) {
  ConvertJobStats stats;
  const std::unique_ptr<io::RecordingReader> in = open_recording(o.input);
  stats.input_format = in->format_name();
  std::int64_t all_messages = 0;
  for (const auto& [name, info] : in->topics().all()) all_messages += info.messages;
  const std::unique_ptr<io::RecordingWriter> out =
      create_recording(o.output, o.compression, o.format);
  as_job([&] {
    in->read({}, [&](const io::RecordedMessage& m) {
      check_cancelled(cancel);
      copy_or_leave_out(*out, m, stats.left_out);
      ++stats.messages_in;
      if (progress && stats.messages_in % 256 == 0) {
        progress(static_cast<double>(stats.messages_in) /
                 static_cast<double>(std::max<std::int64_t>(1, all_messages)));
      }
    });
    out->finish();
  });
  stats.messages_out = out->messages_written();
  if (progress) progress(1.0);
  return stats;
}

}  // namespace dispel::jobs
