#include "dispel/eval/beam_evaluation.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace dispel::eval {
namespace {

TEST(BeamEvaluator, CountsRatesPerClassAndF1) {
  BeamEvaluator e(1);
  // 4 static (1 wrongly removed), 4 moving of actor 1 (3 removed), 2 still (1 removed), 1 none.
  e.add_scan(1.0, {0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 3}, {0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 0},
             {false, true, false, false, true, true, true, false, true, false, true});
  const Rates r = e.result();
  EXPECT_DOUBLE_EQ(r.preservation_rate(), 0.75);
  EXPECT_DOUBLE_EQ(r.rejection_rate(), 0.75);
  EXPECT_DOUBLE_EQ(r.f1(), 0.75);
  EXPECT_DOUBLE_EQ(r.still_removed_rate(), 0.5);
  EXPECT_EQ(r.scans, 1);
  EXPECT_THROW(e.add_scan(2.0, {0}, {0, 0}, {false}), std::invalid_argument);
}

// Actor 1 stands (scans 1-2), walks (3), stands again to the end (4); actor 2 only stands. The
// still beams of the actor seen moving later are counted apart: those an offline filter should
// remove; the rest are of what arrived and stayed, or never moved in view.
TEST(BeamEvaluator, StillBeamsOfActorsSeenMovingLaterAreCountedApart) {
  BeamEvaluator e(1);
  const std::vector<std::int32_t> actors = {1, 1, 2};
  e.add_scan(1.0, {2, 2, 2}, actors, {true, false, false});
  e.add_scan(2.0, {2, 2, 2}, actors, {true, true, true});
  e.add_scan(3.0, {1, 1, 2}, actors, {true, true, false});
  e.add_scan(4.0, {2, 2, 2}, actors, {false, false, true});
  const Rates r = e.result();
  EXPECT_EQ(r.still_beams, 10);
  EXPECT_EQ(r.still_removed, 5);
  EXPECT_EQ(r.still_moves_later_beams, 4);  // Actor 1 in scans 1 and 2.
  EXPECT_EQ(r.still_moves_later_removed, 3);
  EXPECT_DOUBLE_EQ(r.still_moves_later_removed_rate(), 0.75);
  BeamEvaluator none(1);
  none.add_scan(1.0, {2}, {1}, {true});
  EXPECT_TRUE(std::isnan(none.result().still_moves_later_removed_rate()));
}

TEST(BeamEvaluator, LatencyRunsFromFirstSightToFirstScanWithHalfTheBeamsRemoved) {
  BeamEvaluator e(2);
  const std::vector<std::uint8_t> truth = {1, 1, 1, 1, 0};
  const std::vector<std::int32_t> two_actors = {1, 1, 2, 2, 0};
  e.add_scan(10.0, {1, 0, 0, 0, 0}, {1, 0, 0, 0, 0},
             {false, false, false, false, false});                           // 1 beam: unseen.
  e.add_scan(10.5, truth, two_actors, {false, false, false, false, false});  // Both seen.
  e.add_scan(11.0, truth, two_actors, {true, false, false, false, false});   // Actor 1: half.
  e.add_scan(12.5, truth, two_actors, {true, true, true, true, false});      // Actor 2 too.
  const Rates r = e.result();
  EXPECT_EQ(r.actors_seen, 2);
  EXPECT_EQ(r.actors_removed, 2);
  EXPECT_DOUBLE_EQ(r.latency_median_s(), 1.25);  // 0.5 and 2.0.
  EXPECT_DOUBLE_EQ(r.latency_p90_s(), 0.5 + 0.9 * 1.5);
  BeamEvaluator never(1);
  never.add_scan(1.0, {1}, {1}, {false});
  EXPECT_EQ(never.result().actors_removed, 0);
  EXPECT_TRUE(std::isnan(never.result().latency_median_s()));
}

}  // namespace
}  // namespace dispel::eval
