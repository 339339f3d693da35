#include "render_command.hpp"

#include <atomic>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <tuple>

#include "dispel/jobs/filter_job.hpp"

namespace dispel::apps {
namespace {

std::atomic<bool> g_interrupted{false};

extern "C" void on_render_signal(int) { g_interrupted.store(true); }

}  // namespace

int run_render(RenderCommandOptions options) {
  render::RenderResult result;
  try {
    if (!options.size.empty()) {
      std::tie(options.job.width_px, options.job.height_px) =
          render::parse_image_size(options.size);
    }
    g_interrupted.store(false);
    std::signal(SIGINT, on_render_signal);
    std::signal(SIGTERM, on_render_signal);
    result = render::render_bag(options.job, &g_interrupted);
  } catch (const jobs::JobCancelled&) {
    std::cerr << "dispel render: interrupted; " << options.job.output << " was not written\n";
    return 130;
  } catch (const std::exception& e) {
    std::cerr << "dispel render: " << e.what() << "\n";
    return 1;
  }
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  if (options.job.view == "scan") {
    std::printf("dispel render: scan %lld at %.2f s: %lld objects, %zu tracks\n",
                static_cast<long long>(options.job.scan_index), result.from_s,
                static_cast<long long>(result.objects), result.tracks.size());
  } else {
    std::printf(
        "dispel render: %lld scans from %.1f s to %.1f s%s: %lld points kept, %lld dynamic, %lld "
        "unknown%s\n",
        static_cast<long long>(result.scans_drawn), result.from_s, result.to_s,
        result.labelled ? "" : " (not filtered)", static_cast<long long>(result.points_kept),
        static_cast<long long>(result.points_dynamic),
        static_cast<long long>(result.points_unknown),
        result.scans_without_pose > 0
            ? (", " + std::to_string(result.scans_without_pose) + " scans without a pose left out")
                  .c_str()
            : "");
  }
  std::printf("wrote %s (%dx%d)\n", options.job.output.c_str(), result.width_px, result.height_px);
  return 0;
}

}  // namespace dispel::apps
