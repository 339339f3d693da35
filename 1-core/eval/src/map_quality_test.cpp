#include "dispel/eval/map_quality.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace dispel::eval {
namespace {

std::uint64_t key(std::int64_t col, std::int64_t row) { return OccupancyGrid::cell_key(col, row); }

TEST(OccupancyGrid, ARayMissesTheCellsItCrossesAndHitsItsEnd) {
  OccupancyGrid grid;  // 0.05 m
  grid.add_return({0.025, 0.025}, {1.025, 0.025});
  EXPECT_EQ(grid.occupied_cells(), std::vector<std::uint64_t>{key(20, 0)});
  EXPECT_EQ(grid.known_cells(), 21);

  // Negative coordinates: floor, not truncation. A diagonal crosses one cell per step.
  OccupancyGrid negative;
  negative.add_return({-0.01, -0.01}, {-0.26, -0.51});
  EXPECT_EQ(negative.occupied_cells(), std::vector<std::uint64_t>{key(-6, -11)});
  EXPECT_EQ(negative.known_cells(), 1 + 5 + 10);

  // A return in its own start cell is a hit there; non-finite points change nothing.
  OccupancyGrid same;
  same.add_return({0.01, 0.01}, {0.02, 0.03});
  same.add_return({0.0, 0.0}, {std::nan(""), 1.0});
  EXPECT_EQ(same.occupied_cells(), std::vector<std::uint64_t>{key(0, 0)});
  EXPECT_EQ(same.known_cells(), 1);
}

TEST(OccupancyGrid, AThingThatStoodLongIsGoneAfterEightRaysThroughItsPlace) {
  // OctoMap's clamp: a cell hit any number of times is at most 0.97, and each miss (0.4) takes
  // it down by 0.405 in log odds; below 0.65 after ceil((3.476 - 0.619) / 0.405) = 8 misses.
  OccupancyGrid grid;
  for (int i = 0; i < 1000; ++i) grid.add_return({0.025, 0.025}, {1.025, 0.025});
  for (int i = 0; i < 7; ++i) grid.add_return({0.025, 0.025}, {2.025, 0.025});
  EXPECT_EQ(grid.occupied_cells(), (std::vector<std::uint64_t>{key(20, 0), key(40, 0)}));
  grid.add_return({0.025, 0.025}, {2.025, 0.025});
  EXPECT_EQ(grid.occupied_cells(), std::vector<std::uint64_t>{key(40, 0)});

  // A beam without a return clears its whole length, its last cell too.
  for (int i = 0; i < 7; ++i) grid.add_no_return({0.025, 0.025}, {2.025, 0.025});
  EXPECT_EQ(grid.occupied_cells(), std::vector<std::uint64_t>{key(40, 0)});
  grid.add_no_return({0.025, 0.025}, {2.025, 0.025});
  EXPECT_TRUE(grid.occupied_cells().empty());
  EXPECT_EQ(grid.known_cells(), 41);
}

// A wall at x = 3 seen from the origin, beam by beam.
void see_wall(OccupancyGrid& grid, int scans) {
  for (int s = 0; s < scans; ++s) {
    for (int i = -20; i <= 20; ++i) grid.add_return({0.0, 0.0}, {3.0, 0.1 * i});
  }
}

TEST(CompareMaps, CountsCellsWronglyOccupiedAndCellsLost) {
  OccupancyGrid oracle, kept_person, lost_wall;
  see_wall(oracle, 10);
  see_wall(kept_person, 10);
  see_wall(lost_wall, 10);
  // A person at (1.5, 0) the whole time: three beams end on it (0.05 m cells).
  for (int s = 0; s < 10; ++s) {
    for (const double y : {-0.1, 0.0, 0.1}) kept_person.add_return({0.0, 0.0}, {1.5, y});
  }
  const MapComparison same = compare_maps(oracle, oracle);
  EXPECT_GT(same.reference_occupied, 30);
  EXPECT_EQ(same.wrongly_occupied, 0);
  EXPECT_EQ(same.lost, 0);
  const MapComparison person = compare_maps(oracle, kept_person);
  EXPECT_EQ(person.wrongly_occupied, 3);
  EXPECT_EQ(person.lost, 0);
  EXPECT_NEAR(person.wrongly_occupied_share(), 3.0 / static_cast<double>(same.reference_occupied),
              1e-12);
  // A wall the filter took away part of is lost; the rays that were removed clear nothing.
  OccupancyGrid partial;
  for (int s = 0; s < 10; ++s) {
    for (int i = -20; i <= 0; ++i) partial.add_return({0.0, 0.0}, {3.0, 0.1 * i});
  }
  const MapComparison lost = compare_maps(oracle, partial);
  EXPECT_EQ(lost.wrongly_occupied, 0);
  EXPECT_EQ(lost.lost, same.reference_occupied - lost.evaluated_occupied);
  EXPECT_GT(lost.lost, 15);
  EXPECT_TRUE(std::isnan(compare_maps(OccupancyGrid{}, oracle).lost_share()));
  EXPECT_THROW(compare_maps(oracle, OccupancyGrid(OccupancyGridConfig{0.1})),
               std::invalid_argument);
}

TEST(OccupancyGridConfig, InvalidValuesAreNamed) {
  const auto message = [](OccupancyGridConfig c) -> std::string {
    try {
      c.validate();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  OccupancyGridConfig c;
  EXPECT_EQ(message(c), "");
  c.resolution_m = 0.0;
  EXPECT_NE(message(c).find("map resolution"), std::string::npos);
  c = {};
  c.resolution_m = std::nan("");
  EXPECT_NE(message(c).find("map resolution"), std::string::npos);
  c = {};
  c.hit_probability = 0.4;
  EXPECT_NE(message(c).find("hit probability"), std::string::npos);
  c = {};
  c.miss_probability = 1.0;
  EXPECT_NE(message(c).find("miss probability"), std::string::npos);
  c = {};
  c.occupied_probability = 0.99;
  EXPECT_NE(message(c).find("occupied probability"), std::string::npos);
  EXPECT_THROW(OccupancyGrid{c}, std::invalid_argument);
}

}  // namespace
}  // namespace dispel::eval
