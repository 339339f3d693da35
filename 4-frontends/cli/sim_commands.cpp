#include "sim_commands.hpp"

#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>

#include "cli_common.hpp"
#include "dispel/io/scenario_yaml.hpp"
#include "dispel/jobs/eval_job.hpp"
#include "dispel/jobs/sim_job.hpp"
#include "dispel/render/render.hpp"

namespace dispel::apps {
namespace {

// JSON has no NaN: a rate over no beams is null.
nlohmann::ordered_json number_or_null(double v) {
  return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
}

}  // namespace

int run_sim(const SimOptions& o) {
  const Interrupts interrupts;  // Ctrl-C: stop and remove OUT.bag.partial.
  try {
    const sim::Scenario scenario = io::load_scenario(o.scenario);
    // Streamed: each scan and sample is written as it is made, so memory does not grow with
    // the duration; a run whose bag would not fit on the disk is refused before any work.
    const jobs::SimulationSummary run =
        jobs::simulate_to_recording(scenario, o.seed, o.duration_s, o.output, interrupts.flag());
    std::printf(
        "dispel sim: %s, seed %llu: %lld scans, %d actors; beams: %lld static, %lld moving, %lld "
        "still actors, %lld no return\nwrote %s\n",
        scenario.name.c_str(), static_cast<unsigned long long>(o.seed),
        static_cast<long long>(run.scans), run.actor_count, static_cast<long long>(run.beams[0]),
        static_cast<long long>(run.beams[1]), static_cast<long long>(run.beams[2]),
        static_cast<long long>(run.beams[3]), o.output.c_str());
    return 0;
  } catch (const jobs::JobCancelled&) {
    std::cerr << "dispel sim: interrupted; " << error_line(o.output) << " was not written\n";
    return 130;
  } catch (const std::exception& e) {
    std::cerr << "dispel sim: " << error_line(e.what()) << "\n";
    return 1;
  }
}

int run_eval(const EvalOptions& o) {
  jobs::Evaluation evaluation;
  try {
    std::optional<eval::OccupancyGridConfig> grid;
    if (o.map) {
      grid.emplace();
      grid->resolution_m = o.map_resolution_m;
    }
    evaluation = jobs::evaluate_recordings(o.truth, o.result, o.scan_topic, grid);
  } catch (const std::exception& e) {
    std::cerr << "dispel eval: " << error_line(e.what()) << "\n";
    return 1;
  }
  const eval::Rates& r = evaluation.rates;
  const std::optional<jobs::MapQuality>& map = evaluation.map;
  if (!o.plot.empty()) {
    try {
      const auto name = [](const std::string& p) { return p.substr(p.find_last_of('/') + 1); };
      render::plot_evaluation(r, "dispel eval: " + name(o.result) + " against " + name(o.truth),
                              o.plot);
    } catch (const std::exception& e) {
      std::cerr << "dispel eval: " << error_line(e.what()) << "\n";
      return 1;
    }
  }
  if (o.json) {
    nlohmann::ordered_json j;
    j["preservation_rate"] = number_or_null(r.preservation_rate());
    j["rejection_rate"] = number_or_null(r.rejection_rate());
    j["f1"] = number_or_null(r.f1());
    j["detection_latency_s"] = {{"median", number_or_null(r.latency_median_s())},
                                {"p90", number_or_null(r.latency_p90_s())},
                                {"actors_seen", r.actors_seen},
                                {"actors_removed", r.actors_removed}};
    j["per_class"] = {{"static", {{"beams", r.static_beams}, {"kept", r.static_kept}}},
                      {"moving", {{"beams", r.moving_beams}, {"removed", r.moving_removed}}},
                      {"still",
                       {{"beams", r.still_beams},
                        {"removed", r.still_removed},
                        {"removed_rate", number_or_null(r.still_removed_rate())}}},
                      {"still_moves_later",
                       {{"beams", r.still_moves_later_beams},
                        {"removed", r.still_moves_later_removed},
                        {"removed_rate", number_or_null(r.still_moves_later_removed_rate())}}}};
    j["scans"] = r.scans;
    if (map) {
      const auto comparison = [](const eval::MapComparison& c) {
        return nlohmann::ordered_json{
            {"occupied_cells", c.evaluated_occupied},
            {"wrongly_occupied_cells", c.wrongly_occupied},
            {"wrongly_occupied_share", number_or_null(c.wrongly_occupied_share())},
            {"lost_cells", c.lost},
            {"lost_share", number_or_null(c.lost_share())}};
      };
      j["map"] = {{"resolution_m", map->resolution_m},
                  {"scans", map->scans},
                  {"oracle_occupied_cells", map->result.reference_occupied},
                  {"result", comparison(map->result)},
                  {"raw", comparison(map->raw)}};
    }
    std::cout << j.dump(2) << std::endl;
    return 0;
  }
  std::printf("%-34s %10s\n", "measure", "value");
  std::printf("%-34s %10.4f  (%lld of %lld static beams kept)\n", "preservation rate",
              r.preservation_rate(), static_cast<long long>(r.static_kept),
              static_cast<long long>(r.static_beams));
  std::printf("%-34s %10.4f  (%lld of %lld moving beams removed)\n", "rejection rate",
              r.rejection_rate(), static_cast<long long>(r.moving_removed),
              static_cast<long long>(r.moving_beams));
  std::printf("%-34s %10.4f\n", "F1", r.f1());
  std::printf("%-34s %10.2f s (p90 %.2f s; %lld of %lld actors removed)\n",
              "detection latency, median", r.latency_median_s(), r.latency_p90_s(),
              static_cast<long long>(r.actors_removed), static_cast<long long>(r.actors_seen));
  std::printf("%-34s %10.4f  (%lld beams; reported, not a target)\n", "still actors removed",
              r.still_removed_rate(), static_cast<long long>(r.still_beams));
  std::printf("%-34s %10.4f  (%lld beams of actors seen moving later)\n",
              "  of them, moving later, removed", r.still_moves_later_removed_rate(),
              static_cast<long long>(r.still_moves_later_beams));
  if (map) {
    std::printf(
        "map (%.2f m cells, %lld scans from the true poses): the oracle's scans occupy "
        "%lld cells\n",
        map->resolution_m, static_cast<long long>(map->scans),
        static_cast<long long>(map->result.reference_occupied));
    const auto line = [](const char* name, const eval::MapComparison& c) {
      std::printf("%-34s %10.4f  (%lld cells; %lld lost, %.4f)\n", name, c.wrongly_occupied_share(),
                  static_cast<long long>(c.wrongly_occupied), static_cast<long long>(c.lost),
                  c.lost_share());
    };
    line("map cells wrongly occupied", map->result);
    line("... unfiltered scans", map->raw);
  }
  return 0;
}

}  // namespace dispel::apps
