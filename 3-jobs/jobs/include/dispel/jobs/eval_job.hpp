#pragma once
/// @file
/// `dispel eval`: compares a filtered recording with the simulator's ground truth.

#include <string>

#include "dispel/eval/beam_evaluation.hpp"
#include "dispel/jobs/job.hpp"

namespace dispel::jobs {

/// Reads /scan_truth and /scan_truth_actor from @p truth_bag and <scan_topic>_labels (or, when
/// absent, <scan_topic>_filtered: NaN = removed) from @p result_bag, pairs the scans by stamp,
/// and evaluates them. @throws JobError with a one-line message.
eval::Rates evaluate_bags(const std::string& truth_bag, const std::string& result_bag,
                          const std::string& scan_topic = "/scan");

}  // namespace dispel::jobs
