#pragma once
// The benchmark cases shared by the Google Benchmark program (dispel_benchmarks) and
// `dispel bench`: one definition of what is measured, two ways to run it.

#include <cstdint>
#include <vector>

#include "dispel/core/laser_scan.hpp"

namespace dispel::bench {

/// A scan of a warehouse hall as the thesis's scanner would see it (275 deg field of view,
/// 40 m range) with @p beams beams: walls, racks, pillars and people, 1% dropouts. The scene is
/// the same for every size, so time per beam is comparable across sizes.
LaserScan hall_scan(std::int32_t beams);

/// @p frames scans of the same hall in which the people walk back and forth, for the filter.
std::vector<LaserScan> hall_sequence(std::int32_t beams, int frames);

/// How many times each case is repeated and for how long at least (seconds per repetition).
struct RunSettings {
  int repetitions = 5;
  double min_time_s = 0.2;
};

/// Registers every case with Google Benchmark. Names are "<algorithm>/<beams>", algorithm one of
/// segmentation, filter_pipeline (the whole dynamic filter per scan, the thesis's configuration),
/// filter_pipeline_default (the same with dispel's default configuration),
/// filter_pipeline_sparse (the default on a sparse log: every scan resets it), reference_dbscan
/// (brute force), reference_dbscan_grid, and odometry_ct_step / odometry_omni_step (one UKF
/// predict + wheel update; "beams" is 1). Each run sets the counter "beams".
void register_benchmarks(const RunSettings& settings);

}  // namespace dispel::bench
