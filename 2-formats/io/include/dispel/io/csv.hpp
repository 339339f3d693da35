#pragma once
/// @file
/// CSV files with a header row: numeric columns by name (wheel speeds, yaw rates, trajectories),
/// and trajectories (t,x,y,yaw) written and read back.

#include <memory>
#include <string>
#include <vector>

#include "dispel/eval/trajectory_error.hpp"

namespace dispel::io {

/// The values of the requested columns, row by row, with the file's line numbers.
struct CsvColumns {
  std::vector<std::vector<double>> rows;  ///< In the order of the requested columns.
  std::vector<int> lines;
};

/// Reads the columns @p wanted (by header name, any order; other columns are ignored) of a CSV
/// file. @throws InputError naming the file and the line: no such file, a header without a
/// wanted column, a row with the wrong number of values, a value that is not a number.
CsvColumns read_csv(const std::string& path, const std::vector<std::string>& wanted);

/// Reads a trajectory CSV: a header naming at least the columns t, x, y and yaw, then one row per
/// pose. @throws InputError naming the file and line
std::vector<eval::TrajectoryPoint> read_trajectory_csv(const std::string& path);

/// Writes @p trajectory as a CSV with the header t,x,y,yaw (what read_trajectory_csv() reads);
/// the file appears only when complete. @throws OutputError when it cannot be written
void write_trajectory_csv(const std::string& path,
                          const std::vector<eval::TrajectoryPoint>& trajectory);

/// A text file written by rows, that appears under its name only when commit() succeeds.
class CsvWriter {
 public:
  /// @throws OutputError when the file cannot be created.
  explicit CsvWriter(const std::string& path);
  ~CsvWriter();
  CsvWriter(const CsvWriter&) = delete;
  CsvWriter& operator=(const CsvWriter&) = delete;

  /// Appends a line (without the newline: it is added). Errors show at commit().
  void line(const std::string& text);
  /// Appends formatted text as std::fprintf does.
  void printf(const char* format, ...) __attribute__((format(printf, 2, 3)));
  /// Flushes and closes the file, not yet under its name (for several files that appear
  /// together: close() them all, then commit()). @throws OutputError when writing failed.
  void close();
  /// close() if not done, and moves the file into place. @throws OutputError when writing failed.
  void commit();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Writes the header t,x,y,yaw and one row per point of @p trajectory (as write_trajectory_csv).
void write_trajectory(CsvWriter& out, const std::vector<eval::TrajectoryPoint>& trajectory);

}  // namespace dispel::io
