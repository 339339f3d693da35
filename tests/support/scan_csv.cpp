#include "scan_csv.hpp"

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace dispel::testing {
namespace {

double parse_number(const std::string& field, const std::string& where) {
  if (field == "inf") return std::numeric_limits<double>::infinity();
  if (field == "-inf") return -std::numeric_limits<double>::infinity();
  if (field == "nan") return std::numeric_limits<double>::quiet_NaN();
  std::size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(field, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != field.size()) {
    throw std::runtime_error(where + ": not a number: '" + field + "'");
  }
  return value;
}

}  // namespace

std::vector<LaserScan> read_scan_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  std::vector<LaserScan> scans;
  std::string line;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    if (line.empty() || line[0] == '#') continue;
    const std::string where = path + ":" + std::to_string(line_no);
    std::vector<double> values;
    std::stringstream fields(line);
    for (std::string field; std::getline(fields, field, ',');) {
      values.push_back(parse_number(field, where));
    }
    if (values.size() < 6 || values[5] != static_cast<double>(values.size() - 6)) {
      throw std::runtime_error(where + ": beam count does not match the number of ranges");
    }
    LaserScan scan;
    scan.stamp_s = values[0];
    scan.angle_min_rad = values[1];
    scan.angle_increment_rad = values[2];
    scan.range_min_m = static_cast<float>(values[3]);
    scan.range_max_m = static_cast<float>(values[4]);
    for (std::size_t i = 6; i < values.size(); ++i) {
      scan.ranges_m.push_back(static_cast<float>(values[i]));
    }
    scans.push_back(std::move(scan));
  }
  if (scans.empty()) throw std::runtime_error(path + ": no scans");
  return scans;
}

std::string data_path(const std::string& relative) {
  return std::string(DISPEL_SOURCE_DIR) + "/data/" + relative;
}

}  // namespace dispel::testing
