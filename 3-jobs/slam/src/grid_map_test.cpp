#include "dispel/slam/grid_map.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "dispel/jobs/job.hpp"
#include "test_files.hpp"

namespace dispel::slam {
namespace {

using jobs::JobError;
using test::temp_path;

// A 5 x 3 map with every kind of cell, its origin turned by 0.3 rad.
GridMap small_map() {
  GridMap m;
  m.resolution_m = 0.1;
  m.origin = {-1.25, 2.5, 0.3};
  m.width = 5;
  m.height = 3;
  m.cells = {100, 0,  0, -1, 100,  //
             0,   0,  0, -1, 100,  //
             -1,  -1, 0, 0,  100};
  return m;
}

using test::write_text;

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(SlamGridMap, WriteThenReadGivesTheSameMap) {
  const GridMap m = small_map();
  const std::string yaml = temp_path("small_map.yaml");
  write_map_yaml(m, yaml);
  EXPECT_FALSE(test::exists(yaml + ".partial"));
  EXPECT_FALSE(test::exists(temp_path("small_map.pgm.partial")));
  const GridMap back = read_map_yaml(yaml);
  EXPECT_EQ(back, m);
  EXPECT_EQ(back.occupied_cells(), 4);
  EXPECT_EQ(back.free_cells(), 7);
  // map_saver's layout: the image's first row is the map's last (top) row.
  const std::string pgm = read_text(temp_path("small_map.pgm"));
  const std::string pixels = pgm.substr(pgm.size() - 15);
  EXPECT_EQ(static_cast<unsigned char>(pixels[0]), 205u);  // (0, 2) unknown
  EXPECT_EQ(static_cast<unsigned char>(pixels[2]), 254u);  // (2, 2) free
  EXPECT_EQ(static_cast<unsigned char>(pixels[10]), 0u);   // (0, 0) occupied
  std::remove(yaml.c_str());
  std::remove(temp_path("small_map.pgm").c_str());
}

// Cells between map_saver's thresholds are written as unknown; the rest stays.
TEST(SlamGridMap, IntermediateOccupancyIsSavedAsMapSaverDoes) {
  GridMap m = small_map();
  m.cells[1] = 20;  // free (<= 25)
  m.cells[2] = 50;  // unknown
  m.cells[3] = 70;  // occupied (>= 65)
  const std::string yaml = temp_path("intermediate.yaml");
  write_map_yaml(m, yaml);
  const GridMap back = read_map_yaml(yaml);
  EXPECT_EQ(back.at(1, 0), kFreeCell);
  EXPECT_EQ(back.at(2, 0), kUnknownCell);
  EXPECT_EQ(back.at(3, 0), kOccupiedCell);
}

// A map as a robotics engineer has it: P2 (text) image in a sub-folder, comments, negate, scale
// mode and a maximum value below 255.
TEST(SlamGridMap, ReadsMapServerVariants) {
  const std::string dir = temp_path("");
  write_text("ascii.pgm", "P2\n# made by hand\n3 2\n# max\n15\n15 0 8\n0 15 15\n");
  // negate: pixel 15 (-> 255) is occupied, 0 free, 8 (136 -> occupancy 0.53) unknown.
  const std::string yaml =
      write_text("ascii.yaml",
                 "image: ascii.pgm\nresolution: 0.5\norigin: [1.0, -2.0, 0.0]\nnegate: 1\n"
                 "occupied_thresh: 0.65\nfree_thresh: 0.196\n");
  const GridMap m = read_map_yaml(yaml);
  ASSERT_EQ(m.width, 3);
  ASSERT_EQ(m.height, 2);
  EXPECT_EQ(m.resolution_m, 0.5);
  EXPECT_EQ(m.origin.x_m, 1.0);
  EXPECT_EQ(m.origin.y_m, -2.0);
  // Bottom row (the image's last): 0 15 15 -> free occupied occupied.
  EXPECT_EQ(m.at(0, 0), kFreeCell);
  EXPECT_EQ(m.at(1, 0), kOccupiedCell);
  EXPECT_EQ(m.at(2, 1), kUnknownCell);
  EXPECT_EQ(m.at(0, 1), kOccupiedCell);

  const std::string scaled =
      write_text("scaled.yaml", "image: " + dir +
                                    "/ascii.pgm\nresolution: 0.5\norigin: [0, 0, 0]\nnegate: 1\n"
                                    "occupied_thresh: 0.65\nfree_thresh: 0.196\nmode: scale\n");
  const GridMap s = read_map_yaml(scaled);
  EXPECT_GT(s.at(2, 1), 0);  // 0.53 between the thresholds: scaled, not unknown.
  EXPECT_LT(s.at(2, 1), 100);
}

// --- Bad files ----------------------------------------------------------------------------------

void expect_error(const std::string& yaml, const std::string& expected) {
  try {
    read_map_yaml(yaml);
    ADD_FAILURE() << "accepted " << yaml;
  } catch (const JobError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(expected), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

std::string map_yaml(const std::string& name, const std::string& image,
                     const std::string& resolution = "0.05") {
  return write_text(name, "image: " + image + "\nresolution: " + resolution +
                              "\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\n"
                              "free_thresh: 0.196\n");
}

TEST(SlamGridMapBadInput, EachProblemNamedWithItsFile) {
  write_text("good.pgm", std::string("P5\n2 2\n255\n") + std::string("\x00\xfe\xcd\xfe", 4));
  EXPECT_NO_THROW(read_map_yaml(map_yaml("good.yaml", "good.pgm")));

  expect_error(temp_path("no_such_map.yaml"), "no_such_map.yaml: No such file or directory");
  expect_error(map_yaml("no_image.yaml", "missing.pgm"), "missing.pgm: No such file or directory");
  expect_error(map_yaml("zero.yaml", "good.pgm", "0"),
               "zero.yaml: resolution 0: must be a positive number");
  expect_error(map_yaml("negative.yaml", "good.pgm", "-0.05"), "negative.yaml: resolution -0.05");
  expect_error(map_yaml("word.yaml", "good.pgm", "fine"), "word.yaml: resolution is not a number");
  expect_error(write_text("no_origin.yaml",
                          "image: good.pgm\nresolution: 0.05\nnegate: 0\n"
                          "occupied_thresh: 0.65\nfree_thresh: 0.196\n"),
               "no_origin.yaml: no 'origin' key");
  expect_error(write_text("no_negate.yaml",
                          "image: good.pgm\nresolution: 0.05\n"
                          "origin: [0, 0, 0]\noccupied_thresh: 0.65\n"
                          "free_thresh: 0.196\n"),
               "no_negate.yaml: no 'negate' key");
  expect_error(write_text("short_origin.yaml",
                          "image: good.pgm\nresolution: 0.05\n"
                          "origin: [0, 0]\nnegate: 0\n"
                          "occupied_thresh: 0.65\nfree_thresh: 0.196\n"),
               "origin must be [x, y, yaw]");
  expect_error(write_text("not_yaml.yaml", "image: [unclosed\n"), "not_yaml.yaml: not a YAML file");
  expect_error(write_text("list.yaml", "- a\n- b\n"), "list.yaml: not a map_server map");

  write_text("png.pgm", "\x89PNG\r\n\x1a\n0000");
  expect_error(map_yaml("png.yaml", "png.pgm"), "png.pgm: not a PGM image");
  write_text("truncated.pgm", std::string("P5\n4 4\n255\n") + std::string(10, '\xfe'));
  expect_error(map_yaml("truncated.yaml", "truncated.pgm"),
               "truncated.pgm: image is 4 x 4 pixels but holds only 10");
  write_text("bad_header.pgm", "P5\n4 x\n255\n");
  expect_error(map_yaml("bad_header.yaml", "bad_header.pgm"),
               "bad_header.pgm: PGM height 'x' is not a positive integer");
  write_text("wide.pgm", "P5\n1 1\n65535\n\x00\x00");
  expect_error(map_yaml("wide.yaml", "wide.pgm"), "16-bit PGM");
  write_text("ascii_bad.pgm", "P2\n2 1\n255\n12 300\n");
  expect_error(map_yaml("ascii_bad.yaml", "ascii_bad.pgm"), "pixel 1 '300'");
}

// Issue 16, fuzzing: a PGM header stating 10^6 x 10^6 pixels had them allocated before they were
// read (4 TB); scale mode with equal thresholds divided 0 by 0 into a cell (undefined behaviour);
// an image name with a newline made an error of two lines.
TEST(SlamGridMapBadInput, FuzzingFindings) {
  write_text("huge.pgm", std::string("P5\n1000000 1000000\n255\n\x00", 24));
  expect_error(map_yaml("huge.yaml", "huge.pgm"),
               "huge.pgm: image is 1000000 x 1000000 pixels, more than the file's 24 bytes can "
               "hold");
  write_text("black.pgm", std::string("P5\n2 1\n255\n\x00\xff", 13));
  const GridMap m =
      read_map_yaml(write_text("equal.yaml",
                               "image: black.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\n"
                               "occupied_thresh: 1\nfree_thresh: 1\nmode: scale\n"));
  EXPECT_EQ(m.at(0, 0), kUnknownCell);  // Occupancy 1: neither above nor below the thresholds.
  EXPECT_EQ(m.at(1, 0), kFreeCell);
  expect_error(write_text("newline.yaml",
                          "image: \"bad\\nname.pgm\"\nresolution: 0.05\norigin: [0, 0, 0]\n"
                          "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"),
               "bad\\x0aname.pgm: No such file or directory");
}

TEST(SlamGridMapBadInput, InvalidMapsAreNotWritten) {
  const std::string yaml = temp_path("invalid.yaml");
  const auto expect_refused = [&](const GridMap& m, const std::string& expected) {
    try {
      write_map_yaml(m, yaml);
      ADD_FAILURE() << "wrote an invalid map";
    } catch (const JobError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
    EXPECT_FALSE(test::exists(yaml));
    EXPECT_FALSE(test::exists(temp_path("invalid.pgm")));
  };
  GridMap m = small_map();
  m.resolution_m = 0.0;
  expect_refused(m, "resolution 0 m: must be a positive number");
  m = small_map();
  m.cells.pop_back();
  expect_refused(m, "map of 5 x 3 cells holds 14 values");
  m = small_map();
  m.cells[0] = 101;
  expect_refused(m, "map cell value 101");
  expect_refused(GridMap{}, "it has none");
  EXPECT_THROW(write_map_yaml(small_map(), temp_path("no_such_folder/map.yaml")), JobError);
}

}  // namespace
}  // namespace dispel::slam

namespace dispel::slam {
namespace {

// An empty (free) map of @p width x @p height cells of @p resolution_m at @p origin, with the
// cells whose centres lie within 0.01 m of the segment from @p a to @p b occupied.
GridMap map_with_line(double resolution_m, const Pose2& origin, int width, int height,
                      const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  GridMap m;
  m.resolution_m = resolution_m;
  m.origin = origin;
  m.width = width;
  m.height = height;
  m.cells.assign(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), 0);
  const Pose2 to_grid = origin.inverse();
  for (int k = 0; k <= 1000; ++k) {
    const Eigen::Vector2d p = to_grid.apply(a + (b - a) * (k / 1000.0));
    const int col = static_cast<int>(std::floor(p.x() / resolution_m));
    const int row = static_cast<int>(std::floor(p.y() / resolution_m));
    if (col >= 0 && row >= 0 && col < width && row < height) {
      m.cells[static_cast<std::size_t>(row) * static_cast<std::size_t>(width) +
              static_cast<std::size_t>(col)] = 100;
    }
  }
  return m;
}

// Two SLAM runs' maps of one wall: their grids have their own origins; a person kept in one of
// them is wrongly occupied, a stretch of wall missing is lost.
TEST(CompareGridMaps, MatchesCellsWithinTheToleranceAcrossDifferentGrids) {
  const GridMap oracle = map_with_line(0.05, {-1.0, -1.0, 0.0}, 80, 80, {0.0, 1.012}, {2.0, 1.012});
  // The same wall in a grid whose origin is off by a fraction of a cell, with a person's cells.
  GridMap raw = map_with_line(0.05, {-1.02, -0.99, 0.0}, 80, 80, {0.0, 1.012}, {2.0, 1.012});
  const auto mark = [&](double x, double y) {
    const int col = static_cast<int>(std::floor((x + 1.02) / 0.05));
    const int row = static_cast<int>(std::floor((y + 0.99) / 0.05));
    raw.cells[static_cast<std::size_t>(row) * 80 + static_cast<std::size_t>(col)] = 100;
  };
  mark(1.0, 0.0);
  mark(1.05, 0.0);
  mark(1.0, 0.05);
  const eval::MapComparison same = compare_grid_maps(oracle, oracle, 0.0);
  EXPECT_EQ(same.reference_occupied, oracle.occupied_cells());
  EXPECT_EQ(same.wrongly_occupied, 0);
  EXPECT_EQ(same.lost, 0);
  const eval::MapComparison person = compare_grid_maps(oracle, raw, 0.1);
  EXPECT_EQ(person.wrongly_occupied, 3);
  EXPECT_EQ(person.lost, 0);
  EXPECT_EQ(person.evaluated_occupied, raw.occupied_cells());
  // Without a tolerance the shifted grid's wall matches nothing.
  EXPECT_EQ(compare_grid_maps(oracle, raw, 0.0).lost, oracle.occupied_cells());
  // Half the wall, in a coarser grid turned by 90 degrees: the other half is lost.
  const GridMap half =
      map_with_line(0.1, {3.0, -1.0, 1.5707963267948966}, 40, 40, {0.0, 1.012}, {1.0, 1.012});
  const eval::MapComparison lost = compare_grid_maps(oracle, half, 0.1);
  EXPECT_EQ(lost.wrongly_occupied, 0);
  EXPECT_NEAR(lost.lost_share(), 0.5, 0.05);
  EXPECT_THROW(compare_grid_maps(oracle, raw, -0.1), JobError);
  EXPECT_THROW(compare_grid_maps(oracle, raw, std::nan("")), JobError);
  GridMap broken = raw;
  broken.cells.pop_back();
  EXPECT_THROW(compare_grid_maps(oracle, broken, 0.1), JobError);
}

}  // namespace
}  // namespace dispel::slam
