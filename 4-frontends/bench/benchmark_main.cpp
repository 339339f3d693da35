// The Google Benchmark program: every dispel benchmark case, with Google Benchmark's own flags
// (--benchmark_filter, --benchmark_format=json, ...). `dispel bench` runs the same cases.
#include <benchmark/benchmark.h>

#include "cases.hpp"

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  dispel::bench::register_benchmarks(dispel::bench::RunSettings{});
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
