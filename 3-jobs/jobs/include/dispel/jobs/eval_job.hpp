#pragma once
/// @file
/// `dispel eval`: compares a filtered recording with the simulator's ground truth.

#include <optional>
#include <string>

#include "dispel/eval/beam_evaluation.hpp"
#include "dispel/eval/map_quality.hpp"
#include "dispel/jobs/job.hpp"

namespace dispel::jobs {

/// Reads /scan_truth and /scan_truth_actor from @p truth_bag and <scan_topic>_labels (or, when
/// absent, <scan_topic>_filtered: NaN = removed) from @p result_bag, pairs the scans by stamp,
/// and evaluates them. @throws JobError with a one-line message.
eval::Rates evaluate_bags(const std::string& truth_bag, const std::string& result_bag,
                          const std::string& scan_topic = "/scan");

/// The maps the scans make, as occupancy grids from the true sensor pose of each beam
/// (/ground_truth of the truth bag, the mount on its /tf_static, the beam's own time within the
/// sweep): the oracle's (only the beams on static things), the result's (every return it kept)
/// and the raw scans' (every return), each compared with the oracle's.
struct MapQuality {
  eval::MapComparison result;  ///< The result's map against the oracle's.
  eval::MapComparison raw;     ///< The unfiltered scans' map against the oracle's.
  double resolution_m = 0.0;
  std::int64_t scans = 0;  ///< Scans drawn into the maps (those with a true pose).
};

struct Evaluation {
  eval::Rates rates;
  std::optional<MapQuality> map;
};

/// evaluate_bags(), and with @p map the map quality too. @throws JobError with a one-line
/// message (also for an invalid grid configuration, or a truth bag without /ground_truth).
Evaluation evaluate_recordings(const std::string& truth_bag, const std::string& result_bag,
                               const std::string& scan_topic,
                               const std::optional<eval::OccupancyGridConfig>& map);

}  // namespace dispel::jobs
