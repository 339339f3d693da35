#pragma once
// Test support: reads the scan CSV written by tools/export_scans_csv.py.

#include <string>
#include <vector>

#include "dispel/core/laser_scan.hpp"

namespace dispel::testing {

/// Reads every scan of @p path. Throws std::runtime_error naming the file and line on any error.
std::vector<LaserScan> read_scan_csv(const std::string& path);

/// Absolute path of a file in the source tree's data/ folder.
std::string data_path(const std::string& relative);

}  // namespace dispel::testing
