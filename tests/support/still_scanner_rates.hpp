#pragma once
// Walls kept and walkers removed on a recording from a scanner that does not move (the shipped
// leg_tracker demo), without annotations. A beam that sees the room returns the same range all
// the time: a wall beam is one whose valid ranges over the whole recording spread (10th to 90th
// percentile) under 5 cm and that is valid in 90 % of the scans; in a scan it counts when its
// range is within 5 cm of its median. A walker beam is one more than 30 cm nearer than its
// beam's 90th percentile. The first 20 scans (2 s, while tracks settle) are left out.
// tools/static_recording_eval.py applies the same rule to a bag from the command line.
#include <sensor_msgs/LaserScan.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

namespace dispel::test {

struct WallsAndWalkers {
  std::int64_t wall_beams = 0, walls_kept = 0, walker_beams = 0, walkers_removed = 0;
  double walls_kept_rate() const {
    return static_cast<double>(walls_kept) / static_cast<double>(wall_beams);
  }
  double walkers_removed_rate() const {
    return static_cast<double>(walkers_removed) / static_cast<double>(walker_beams);
  }
};

// @p removed(k, i): whether beam i of scan k of @p scans was removed.
template <typename Removed>
WallsAndWalkers walls_and_walkers(const std::vector<sensor_msgs::LaserScan>& scans,
                                  Removed removed) {
  WallsAndWalkers out;
  if (scans.empty()) return out;
  const std::size_t n = scans.front().ranges.size();
  std::vector<float> median(n, NAN), p90(n, NAN);
  std::vector<bool> wall(n, false);
  for (std::size_t i = 0; i < n; ++i) {
    std::vector<float> v;
    for (const auto& s : scans) {
      const float r = s.ranges[i];
      if (std::isfinite(r) && r >= s.range_min && r <= s.range_max) v.push_back(r);
    }
    if (v.size() < scans.size() / 2) continue;
    std::sort(v.begin(), v.end());
    median[i] = v[v.size() / 2];
    p90[i] = v[v.size() * 9 / 10];
    wall[i] = v.size() >= scans.size() * 9 / 10 && v[v.size() * 9 / 10] - v[v.size() / 10] < 0.05F;
  }
  for (std::size_t k = 20; k < scans.size(); ++k) {
    for (std::size_t i = 0; i < n; ++i) {
      const float r = scans[k].ranges[i];
      if (!std::isfinite(r)) continue;
      if (wall[i] && std::abs(r - median[i]) < 0.05F) {
        ++out.wall_beams;
        out.walls_kept += removed(k, i) ? 0 : 1;
      } else if (std::isfinite(p90[i]) && r < p90[i] - 0.3F) {
        ++out.walker_beams;
        out.walkers_removed += removed(k, i) ? 1 : 0;
      }
    }
  }
  return out;
}

// What tools/static_recording_eval.py (run by /usr/bin/python3, which has python3-rosbag) says
// of @p labels_topic in @p bag, in its printed precision: the rates to 4 decimals and the beam
// counts. Nothing when it fails or prints something else.
struct PrintedWallsAndWalkers {
  double walls_kept = 0.0, walkers_removed = 0.0;
  long wall_beams = 0, walker_beams = 0;
  std::string printed;
};
inline std::optional<PrintedWallsAndWalkers> static_recording_eval_py(
    const std::string& source_dir, const std::string& bag, const std::string& labels_topic) {
  const std::string command = "/usr/bin/python3 " + source_dir +
                              "/tools/static_recording_eval.py '" + bag + "' " + labels_topic +
                              " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return std::nullopt;
  PrintedWallsAndWalkers out;
  std::array<char, 512> line{};
  while (std::fgets(line.data(), static_cast<int>(line.size()), pipe) != nullptr) {
    out.printed += line.data();
  }
  if (pclose(pipe) != 0) return std::nullopt;
  if (std::sscanf(out.printed.c_str(),
                  "walls kept %lf (%ld beams), walkers removed %lf (%ld beams)", &out.walls_kept,
                  &out.wall_beams, &out.walkers_removed, &out.walker_beams) != 4) {
    return std::nullopt;
  }
  return out;
}

}  // namespace dispel::test
