// Fuzz target: an MRPT rawlog through dispel's reader (MrptRawlogReader: the gzip stream checked
// whole, then MRPT's own deserialisation of each object), as `dispel filter` and `dispel odom`
// open a .rawlog or .rawlog.gz (jobs::open_recording): the topics, the time span, every message
// read and decoded. A rawlog dispel refuses must be refused with an InputError of one line.

#include <cstddef>
#include <cstdint>

#include "dispel/io/errors.hpp"
#include "dispel/io/mrpt_rawlog.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // The reader takes plain and gzip-compressed logs alike, whatever the name.
  const std::string path = dispel::fuzz::temp_folder().write("input.rawlog", data, size);
  try {
    dispel::io::MrptRawlogReader log(path);
    std::size_t decoded = 0;
    for (const auto& [topic, info] : log.topics().all()) decoded += topic.size() + info.type.size();
    decoded += static_cast<std::size_t>(log.begin_time().sec + log.end_time().sec);
    decoded += static_cast<std::size_t>(log.skipped_count());
    log.read({}, [&](const dispel::io::RecordedMessage& m) {
      decoded += static_cast<std::size_t>(m.time().nsec);
      if (const auto s = m.scan()) decoded += s->scan.ranges_m.size() + s->scan.intensities.size();
      if (const auto o = m.odometry()) decoded += o->child_frame_id.size();
      if (const auto t = m.transforms()) decoded += t->transforms.size();
    });
    volatile std::size_t sink = decoded;
    (void)sink;
  } catch (const dispel::io::InputError& e) {
    dispel::fuzz::check_message(e.what());
  }
  return 0;
}
