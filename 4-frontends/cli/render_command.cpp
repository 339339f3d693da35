#include "render_command.hpp"

#include <cstdio>
#include <iostream>
#include <optional>
#include <tuple>

#include "cli_common.hpp"
#include "dispel/jobs/filter_job.hpp"

namespace dispel::apps {
int run_render(RenderCommandOptions options) {
  render::RenderResult result;
  std::optional<Interrupts> interrupts;
  try {
    if (!options.size.empty()) {
      std::tie(options.job.width_px, options.job.height_px) =
          render::parse_image_size(options.size);
    }
    interrupts.emplace();
    result = render::render_bag(options.job, interrupts->flag());
  } catch (const jobs::JobCancelled&) {
    std::cerr << "dispel render: interrupted; " << error_line(options.job.output)
              << " was not written\n";
    return 130;
  } catch (const std::exception& e) {
    std::cerr << "dispel render: " << error_line(e.what()) << "\n";
    return 1;
  }
  interrupts.reset();
  if (options.job.view == "scan") {
    std::printf("dispel render: scan %lld at %.2f s: %lld objects, %zu tracks\n",
                static_cast<long long>(options.job.scan_index), result.from_s,
                static_cast<long long>(result.objects), result.tracks.size());
  } else {
    std::printf(
        "dispel render: %lld scans from %.1f s to %.1f s%s: %lld points kept, %lld dynamic, %lld "
        "unknown%s%s\n",
        static_cast<long long>(result.scans_drawn), result.from_s, result.to_s,
        result.labelled ? "" : " (not filtered)", static_cast<long long>(result.points_kept),
        static_cast<long long>(result.points_dynamic),
        static_cast<long long>(result.points_unknown),
        result.points_removed_offline() > 0
            ? (", " + std::to_string(result.points_moved_later) + " moved at another time, " +
               std::to_string(result.points_vacated) + " place seen through, " +
               std::to_string(result.points_walked_legs) + " walked legs")
                  .c_str()
            : "",
        result.scans_without_pose > 0
            ? (", " + std::to_string(result.scans_without_pose) + " scans without a pose left out")
                  .c_str()
            : "");
  }
  std::printf("wrote %s (%dx%d)\n", options.job.output.c_str(), result.width_px, result.height_px);
  return 0;
}

}  // namespace dispel::apps
