#pragma once
// `dispel sim` and `dispel eval`: thin shells around dispel::sim, dispel::io and dispel::eval.

#include <cstdint>
#include <string>

namespace dispel::apps {

struct SimOptions {
  std::string scenario;
  std::string output;
  std::uint64_t seed = 1;
  double duration_s = 0.0;  ///< 0: the scenario's.
};
int run_sim(const SimOptions& options);

struct EvalOptions {
  std::string truth;
  std::string result;
  std::string scan_topic = "/scan";
  bool json = false;
  std::string plot;  ///< Also draw the evaluation into this .png or .svg (empty: no picture).
  bool map = false;  ///< Also the map quality (jobs::MapQuality).
  double map_resolution_m = 0.05;
};
int run_eval(const EvalOptions& options);

}  // namespace dispel::apps
