#include "bench_command.hpp"

#include <benchmark/benchmark.h>

#include <cstdio>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "cases.hpp"

namespace dispel::apps {
namespace {

struct Result {
  std::string name;
  long long beams = 0;
  double median_ns = 0.0;
};

// Collects the median of each case; in table mode also prints each line as it arrives.
class Collector : public benchmark::BenchmarkReporter {
 public:
  explicit Collector(bool stream) : stream_(stream) {}

  bool ReportContext(const Context&) override { return true; }

  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& run : runs) {
      if (run.error_occurred) {
        errors_.push_back(run.benchmark_name() + ": " + run.error_message);
        continue;
      }
      const bool median = run.run_type == Run::RT_Aggregate && run.aggregate_name == "median";
      const bool single = run.run_type == Run::RT_Iteration && run.repetitions <= 1;
      if (!median && !single) continue;
      Result r;
      r.name = run.run_name.function_name;
      const auto beams = run.counters.find("beams");
      r.beams = beams == run.counters.end() ? 0 : static_cast<long long>(beams->second.value);
      r.median_ns = run.GetAdjustedRealTime();  // The cases report in nanoseconds.
      if (stream_) print_row(r);
      results_.push_back(std::move(r));
    }
  }

  static void print_header() {
    std::printf("%-24s %10s %14s %12s\n", "algorithm", "beams", "median", "per beam");
  }

  static void print_row(const Result& r) {
    std::printf("%-24s %10lld %14s %9.2f ns\n", r.name.c_str(), r.beams,
                human_time(r.median_ns).c_str(), r.median_ns / static_cast<double>(r.beams));
    std::fflush(stdout);
  }

  const std::vector<Result>& results() const { return results_; }
  const std::vector<std::string>& errors() const { return errors_; }

 private:
  static std::string human_time(double ns) {
    char buffer[32];
    if (ns < 1e3) {
      std::snprintf(buffer, sizeof buffer, "%.0f ns", ns);
    } else if (ns < 1e6) {
      std::snprintf(buffer, sizeof buffer, "%.2f us", ns / 1e3);
    } else if (ns < 1e9) {
      std::snprintf(buffer, sizeof buffer, "%.2f ms", ns / 1e6);
    } else {
      std::snprintf(buffer, sizeof buffer, "%.2f s", ns / 1e9);
    }
    return buffer;
  }

  bool stream_;
  std::vector<Result> results_;
  std::vector<std::string> errors_;
};

const Result* find(const std::vector<Result>& results, const std::string& name, long long beams) {
  for (const Result& r : results) {
    if (r.name == name && r.beams == beams) return &r;
  }
  return nullptr;
}

// The figures the project's targets are stated in, when the run measured them.
void print_summary(const std::vector<Result>& results) {
  const Result* seg_small = find(results, "segmentation", 11000);
  const Result* ref_small = find(results, "reference_dbscan", 11000);
  const Result* grid_small = find(results, "reference_dbscan_grid", 11000);
  const Result* seg_100k = find(results, "segmentation", 100000);
  const Result* seg_1m = find(results, "segmentation", 1000000);
  const Result* seg_thesis = find(results, "segmentation", 1617);
  std::printf("\n");
  if (seg_thesis != nullptr) {
    std::printf("segmentation of a 1617-beam scan: %.2f us median\n", seg_thesis->median_ns / 1e3);
  }
  if (seg_small != nullptr && ref_small != nullptr) {
    std::printf("at 11000 beams segmentation is %.0fx faster than reference DBSCAN\n",
                ref_small->median_ns / seg_small->median_ns);
  }
  if (seg_small != nullptr && grid_small != nullptr) {
    std::printf("at 11000 beams segmentation is %.0fx faster than grid-indexed DBSCAN\n",
                grid_small->median_ns / seg_small->median_ns);
  }
  const Result* filter_thesis = find(results, "filter_pipeline", 1617);
  const Result* filter_100k = find(results, "filter_pipeline", 100000);
  const Result* filter_11k = find(results, "filter_pipeline", 11000);
  if (filter_thesis != nullptr) {
    std::printf("whole filter per 1617-beam scan: %.2f us median (the thesis's configuration)\n",
                filter_thesis->median_ns / 1e3);
  }
  if (const Result* d = find(results, "filter_pipeline_default", 1617)) {
    std::printf("whole filter per 1617-beam scan: %.2f us median (dispel's default)\n",
                d->median_ns / 1e3);
  }
  if (const Result* ct = find(results, "odometry_ct_step", 1)) {
    std::printf("one CT odometry step (predict + wheel update): %.2f us median\n",
                ct->median_ns / 1e3);
  }
  if (filter_11k != nullptr && filter_100k != nullptr) {
    std::printf("filter time from 11000 to 100000 beams grows %.2fx (linear: 9.1x)\n",
                filter_100k->median_ns / filter_11k->median_ns);
  }
  if (seg_100k != nullptr && seg_1m != nullptr) {
    std::printf("segmentation time from 100000 to 1000000 beams grows %.2fx (linear: 10x)\n",
                seg_1m->median_ns / seg_100k->median_ns);
  }
}

}  // namespace

int run_bench(const BenchOptions& options) {
  bench::register_benchmarks({options.repetitions, options.min_time_s});
  Collector collector(!options.json);
  if (!options.json) {
    std::printf("dispel bench: median wall time per call, %d repetitions of at least %.2f s\n",
                options.repetitions, options.min_time_s);
    Collector::print_header();
  }
  const std::size_t ran = benchmark::RunSpecifiedBenchmarks(&collector, options.filter);
  benchmark::ClearRegisteredBenchmarks();
  for (const std::string& e : collector.errors()) std::cerr << "dispel bench: " << e << "\n";
  if (ran == 0) {
    std::cerr << "dispel bench: no benchmark matches --filter '" << options.filter << "'\n";
    return 2;
  }
  if (!collector.errors().empty()) return 1;
  if (options.json) {
    nlohmann::ordered_json results = nlohmann::ordered_json::array();
    for (const Result& r : collector.results()) {
      results.push_back({{"name", r.name}, {"beams", r.beams}, {"median_ns", r.median_ns}});
    }
    std::cout << nlohmann::ordered_json{{"results", results}}.dump(2) << std::endl;
  } else {
    print_summary(collector.results());
  }
  return 0;
}

}  // namespace dispel::apps
