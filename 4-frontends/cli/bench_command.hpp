#pragma once
// `dispel bench`: runs the benchmark cases of bench/cases.hpp and reports median times.

#include <string>

namespace dispel::apps {

struct BenchOptions {
  bool json = false;         ///< Print {"results": [...]} instead of a table.
  std::string filter = ".";  ///< Regular expression on case names ("segmentation/1617").
  int repetitions = 5;       ///< Repetitions per case; the median is reported.
  double min_time_s = 0.2;   ///< Minimum time per repetition, seconds.
};

/// Runs the benchmarks and prints the results on stdout. Returns the process exit code.
int run_bench(const BenchOptions& options);

}  // namespace dispel::apps
