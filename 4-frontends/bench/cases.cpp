#include "cases.hpp"

#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "dispel/core/dynamic_filter.hpp"
#include "dispel/core/free_space_map.hpp"
#include "dispel/core/odometry_fusion.hpp"
#include "dispel/core/pose2.hpp"
#include "dispel/core/reference_dbscan.hpp"
#include "dispel/core/segmentation.hpp"
#include "dispel/sim/raycast.hpp"

namespace dispel::bench {
namespace {

constexpr double kDeg = kPi / 180.0;

sim::World hall() {
  sim::World world;
  // A 36 x 24 m hall; the scanner stands off-centre.
  world.segments = {{{-12.0, -8.0}, {24.0, -8.0}},
                    {{24.0, -8.0}, {24.0, 16.0}},
                    {{24.0, 16.0}, {-12.0, 16.0}},
                    {{-12.0, 16.0}, {-12.0, -8.0}}};
  // Two rows of racks with gaps between them.
  for (int k = 0; k < 5; ++k) {
    const double x = 2.0 + 4.0 * k;
    world.segments.push_back({{x, 3.0}, {x + 3.0, 3.0}});
    world.segments.push_back({{x, -4.0}, {x + 3.0, -4.0}});
  }
  for (int k = 0; k < 4; ++k) {
    world.circles.push_back({{-6.0 + 8.0 * k, 10.0}, 0.25});  // Pillars.
  }
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int p = 0; p < 8; ++p) {  // People: two legs each.
    const double bearing = (-120.0 + 240.0 * u(rng)) * kDeg;
    const double range = 1.0 + 6.0 * u(rng);
    const Eigen::Vector2d c(range * std::cos(bearing), range * std::sin(bearing));
    const double heading = 2.0 * kPi * u(rng);
    const Eigen::Vector2d side(0.1 * std::cos(heading), 0.1 * std::sin(heading));
    world.circles.push_back({c + side, 0.06});
    world.circles.push_back({c - side, 0.06});
  }
  return world;
}

}  // namespace

std::vector<LaserScan> hall_sequence(std::int32_t beams, int frames) {
  // The hall's people walk back and forth (one period over the sequence), so that the sequence
  // can be replayed in a loop without anyone jumping.
  const sim::World base = hall();
  std::vector<sim::Circle> legs(base.circles.end() - 16, base.circles.end());
  const double fov = 275.0 * kDeg;
  const sim::ScanGeometry geometry{-fov / 2.0, fov / (beams - 1), beams, 0.05F, 40.0F};
  std::vector<LaserScan> out;
  for (int f = 0; f < frames; ++f) {
    const double phase = 2.0 * kPi * f / frames;
    sim::World world = base;
    world.circles.resize(world.circles.size() - legs.size());
    for (std::size_t l = 0; l < legs.size(); ++l) {
      const double heading = 0.7 * static_cast<double>(l / 2);  // Both legs of a person alike.
      const Eigen::Vector2d dir(std::cos(heading), std::sin(heading));
      world.circles.push_back({legs[l].center + 1.5 * std::sin(phase) * dir, legs[l].radius_m});
    }
    out.push_back(sim::raycast(world, Pose2{}, geometry));
  }
  return out;
}

LaserScan hall_scan(std::int32_t beams) {
  const double fov = 275.0 * kDeg;
  const sim::ScanGeometry geometry{-fov / 2.0, fov / (beams - 1), beams, 0.05F, 40.0F};
  LaserScan scan = sim::raycast(hall(), Pose2{0.0, 0.0, 0.0}, geometry);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (float& r : scan.ranges_m) {
    if (u(rng) < 0.01) r = std::nanf("");
  }
  return scan;
}

namespace {

// One scan per size, built on first use.
const LaserScan& cached_scan(std::int32_t beams) {
  static std::map<std::int32_t, LaserScan> cache;
  auto it = cache.find(beams);
  if (it == cache.end()) it = cache.emplace(beams, hall_scan(beams)).first;
  return it->second;
}

void segmentation(benchmark::State& state) {
  const LaserScan& scan = cached_scan(static_cast<std::int32_t>(state.range(0)));
  Segmenter segmenter{SegmentationConfig{}};
  Segmentation out;
  segmenter.segment(scan, out);  // Builds the direction table once, as in a stream of scans.
  for (auto _ : state) {
    segmenter.segment(scan, out);
    benchmark::DoNotOptimize(out.objects.data());
    benchmark::ClobberMemory();
  }
  state.counters["beams"] = static_cast<double>(scan.size());
  state.counters["objects"] = static_cast<double>(out.objects.size());
}

// The whole filter on a stream of scans: segmentation, tracking, classification, output; with the
// thesis's configuration or dispel's default (which adds the free-space grid).
template <bool kDefaultConfig>
void filter_pipeline(benchmark::State& state) {
  static std::map<std::int32_t, std::vector<LaserScan>> cache;
  const auto beams = static_cast<std::int32_t>(state.range(0));
  auto it = cache.find(beams);
  if (it == cache.end()) it = cache.emplace(beams, hall_sequence(beams, 100)).first;
  std::vector<LaserScan>& frames = it->second;
  DynamicFilter filter{kDefaultConfig ? DynamicFilterConfig{} : thesis_config()};
  FilterResult out;
  double stamp = 0.0;
  std::size_t k = 0;
  std::size_t objects = 0;
  for (std::size_t warm = 0; warm < frames.size(); ++warm, ++k) {  // Tracks settle first.
    frames[k % frames.size()].stamp_s = stamp += 0.05;
    filter.process(frames[k % frames.size()], Pose2{}, out);
  }
  for (auto _ : state) {
    LaserScan& scan = frames[k++ % frames.size()];
    scan.stamp_s = stamp += 0.05;
    filter.process(scan, Pose2{}, out);
    objects += out.segmentation.objects.size();
    benchmark::DoNotOptimize(out.labels.data());
  }
  state.counters["beams"] = beams;
  state.counters["objects"] =
      static_cast<double>(objects) / static_cast<double>(state.iterations());
}

// A sparse log on a robot that drives: every scan comes 2 s after the previous one (past
// max_time_gap_s, so each resets the filter) and 3 m farther on, with dispel's default. What a
// reset costs: the tracks, the registration's map and the free-space grid start afresh.
void filter_pipeline_sparse(benchmark::State& state) {
  const auto beams = static_cast<std::int32_t>(state.range(0));
  const std::vector<LaserScan> frames = hall_sequence(beams, 20);
  DynamicFilter filter{DynamicFilterConfig{}};
  FilterResult out;
  double stamp = 0.0;
  double x = 0.0;
  std::size_t k = 0;
  for (auto _ : state) {
    LaserScan scan = frames[k++ % frames.size()];
    scan.stamp_s = stamp += 2.0;
    filter.process(scan, Pose2{x += 3.0, 0.0, 0.0}, out);
    benchmark::DoNotOptimize(out.labels.data());
  }
  state.counters["beams"] = beams;
}

// The free-space grid alone (FreeSpaceMap::add_scan, dispel's default): each scan's beams traced
// cell by cell from the scanner, which drives along the hall at 1 m/s and 20 Hz, so that the
// window scrolls and new tiles are started as in a recording.
void free_space_add_scan(benchmark::State& state) {
  const auto beams = static_cast<std::int32_t>(state.range(0));
  const std::vector<LaserScan> frames = hall_sequence(beams, 100);
  FreeSpaceMap map{FreeSpaceConfig{}};
  double stamp = 0.0;
  double x = 0.0;
  std::size_t k = 0;
  for (auto _ : state) {
    LaserScan scan = frames[k++ % frames.size()];
    scan.stamp_s = stamp += 0.05;
    map.add_scan(scan, Pose2{x += 0.05, 0.0, 0.0});
    benchmark::ClobberMemory();
  }
  state.counters["beams"] = beams;
  state.counters["tiles_started"] =
      static_cast<double>(map.take_tiles_started()) / static_cast<double>(state.iterations());
}

template <NeighbourSearch kSearch>
void dbscan(benchmark::State& state) {
  const LaserScan& scan = cached_scan(static_cast<std::int32_t>(state.range(0)));
  const SegmentationConfig config;
  DbscanResult out;
  for (auto _ : state) {
    out = reference_dbscan(scan, config, kSearch);
    benchmark::DoNotOptimize(out.beam_labels.data());
  }
  state.counters["beams"] = static_cast<double>(scan.size());
  state.counters["objects"] = out.cluster_count;
}

// One odometry fusion step: predict to the measurement's time stamp and fuse one wheel
// measurement (50 Hz, noisy wheels on a gentle curve). The counter "beams" is 1 so that
// `dispel bench` reports the time per step.
template <OdometryModel kModel>
void odometry_step(benchmark::State& state) {
  OdometryConfig config;
  config.model = kModel;
  OdometryFusion filter(config);
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.003);
  std::vector<std::pair<double, double>> wheels(1024);
  for (auto& w : wheels) w = {0.45 + noise(rng), 0.55 + noise(rng)};
  double t = 0.0;
  std::size_t k = 0;
  for (auto _ : state) {
    const auto& [left, right] = wheels[k++ % wheels.size()];
    benchmark::DoNotOptimize(filter.add_wheels(t += 0.02, left, right));
  }
  state.counters["beams"] = 1;
}

}  // namespace

void register_benchmarks(const RunSettings& settings) {
  auto configure = [&](benchmark::internal::Benchmark* b) {
    b->Unit(benchmark::kNanosecond)
        ->UseRealTime()
        ->Repetitions(settings.repetitions)
        ->MinTime(settings.min_time_s)
        ->ReportAggregatesOnly(true);
  };
  // 1617 beams is the thesis's scanner; 11 000 the largest size the thesis timed.
  configure(benchmark::RegisterBenchmark("segmentation", segmentation)
                ->Arg(1617)
                ->Arg(11000)
                ->Arg(100000)
                ->Arg(1000000));
  configure(benchmark::RegisterBenchmark("filter_pipeline", filter_pipeline<false>)
                ->Arg(1617)
                ->Arg(11000)
                ->Arg(100000));
  configure(benchmark::RegisterBenchmark("filter_pipeline_default", filter_pipeline<true>)
                ->Arg(1617)
                ->Arg(11000));
  configure(
      benchmark::RegisterBenchmark("filter_pipeline_sparse", filter_pipeline_sparse)->Arg(1617));
  configure(benchmark::RegisterBenchmark("free_space_add_scan", free_space_add_scan)
                ->Arg(768)
                ->Arg(1617));
  configure(benchmark::RegisterBenchmark("reference_dbscan", dbscan<NeighbourSearch::kBruteForce>)
                ->Arg(1617)
                ->Arg(11000));
  configure(benchmark::RegisterBenchmark("reference_dbscan_grid", dbscan<NeighbourSearch::kGrid>)
                ->Arg(1617)
                ->Arg(11000)
                ->Arg(100000));
  // Odometry fusion: one UKF step (predict + wheel update), CT model and the omni baseline.
  configure(benchmark::RegisterBenchmark("odometry_ct_step", odometry_step<OdometryModel::kCt>));
  configure(
      benchmark::RegisterBenchmark("odometry_omni_step", odometry_step<OdometryModel::kOmni>));
}

}  // namespace dispel::bench
