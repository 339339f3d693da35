#include "dispel/io/csv.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "dispel/io/atomic_file.hpp"
#include "dispel/io/errors.hpp"
#include "dispel/io/text.hpp"

namespace dispel::io {
namespace {

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) {
    const auto b = cell.find_first_not_of(" \t\r");
    const auto e = cell.find_last_not_of(" \t\r");
    out.push_back(b == std::string::npos ? "" : cell.substr(b, e - b + 1));
  }
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

bool blank(const std::string& line) { return line.find_first_not_of(" \t\r") == std::string::npos; }

}  // namespace

CsvColumns read_csv(const std::string& path, const std::vector<std::string>& wanted) {
  std::ifstream in(path);
  if (!in) throw InputError(one_line(path + ": cannot open the file"));
  std::string line;
  int number = 0;
  std::vector<std::string> header;
  while (header.empty() && std::getline(in, line)) {
    ++number;
    if (!blank(line)) header = split(line);
  }
  std::string expected;
  for (const auto& w : wanted) expected += (expected.empty() ? "" : ",") + w;
  std::vector<std::size_t> index;
  for (const auto& w : wanted) {
    const auto it = std::find(header.begin(), header.end(), w);
    if (it == header.end()) {
      throw InputError(one_line(path + ": the header must name the columns " + expected +
                                " (line " + std::to_string(number) + ": " + quote(line) + ")"));
    }
    index.push_back(static_cast<std::size_t>(it - header.begin()));
  }
  CsvColumns out;
  while (std::getline(in, line)) {
    ++number;
    if (blank(line)) continue;
    const auto cells = split(line);
    if (cells.size() != header.size()) {
      throw InputError(one_line(path + ":" + std::to_string(number) + ": " +
                                std::to_string(header.size()) + " values expected, got " +
                                std::to_string(cells.size())));
    }
    std::vector<double> row;
    for (std::size_t i : index) {
      const std::string& c = cells[i];
      std::size_t used = 0;
      double v = 0.0;
      try {
        v = std::stod(c, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (c.empty() || used != c.size()) {
        throw InputError(one_line(path + ":" + std::to_string(number) + ": " + header[i] + " " +
                                  quote(c) + " is not a number"));
      }
      row.push_back(v);
    }
    out.rows.push_back(std::move(row));
    out.lines.push_back(number);
  }
  return out;
}

std::vector<eval::TrajectoryPoint> read_trajectory_csv(const std::string& path) {
  const CsvColumns c = read_csv(path, {"t", "x", "y", "yaw"});
  std::vector<eval::TrajectoryPoint> out;
  out.reserve(c.rows.size());
  for (const auto& r : c.rows) out.push_back({r[0], r[1], r[2], r[3]});
  return out;
}

void write_trajectory(CsvWriter& out, const std::vector<eval::TrajectoryPoint>& trajectory) {
  out.line("t,x,y,yaw");
  for (const auto& p : trajectory)
    out.printf("%.9f,%.9g,%.9g,%.9g\n", p.t_s, p.x_m, p.y_m, p.yaw_rad);
}

void write_trajectory_csv(const std::string& path,
                          const std::vector<eval::TrajectoryPoint>& trajectory) {
  CsvWriter out(path);
  write_trajectory(out, trajectory);
  out.commit();
}

struct CsvWriter::Impl {
  explicit Impl(const std::string& p) : path(p), file(p) {}
  std::string path;
  AtomicFile file;
  std::FILE* f = nullptr;
  int first_error = 0;  ///< errno of the first write that failed (ENOSPC, EFBIG), 0 if none.
  void check(int result) {
    if (result < 0 && first_error == 0) first_error = errno != 0 ? errno : EIO;
  }
};

CsvWriter::CsvWriter(const std::string& path) : impl_(std::make_unique<Impl>(path)) {
  impl_->f = std::fopen(impl_->file.temp_path().c_str(), "w");
  if (impl_->f == nullptr) {
    throw OutputError(path + ": cannot write the file (" + std::strerror(errno) + ")");
  }
}

CsvWriter::~CsvWriter() {
  if (impl_->f != nullptr) std::fclose(impl_->f);
}

void CsvWriter::line(const std::string& text) {
  impl_->check(std::fputs(text.c_str(), impl_->f));
  impl_->check(std::fputc('\n', impl_->f));
}

void CsvWriter::printf(const char* format, ...) {
  va_list args;
  va_start(args, format);
  impl_->check(std::vfprintf(impl_->f, format, args));
  va_end(args);
}

void CsvWriter::close() {
  if (impl_->f == nullptr) return;
  errno = 0;
  const bool ok = std::fflush(impl_->f) == 0 && std::ferror(impl_->f) == 0;
  const int error = errno;
  const bool closed = std::fclose(impl_->f) == 0;
  impl_->f = nullptr;
  if (!ok || !closed || impl_->first_error != 0) {
    const int reason = impl_->first_error != 0 ? impl_->first_error : error != 0 ? error : errno;
    throw OutputError(impl_->path + ": cannot write (" +
                      (reason != 0 ? std::strerror(reason) : "writing failed") + ")");
  }
}

void CsvWriter::commit() {
  close();
  try {
    impl_->file.commit();
  } catch (const std::exception& e) {
    throw OutputError(impl_->path + ": " + e.what());
  }
}

}  // namespace dispel::io
