// dispel::slam: map_server maps (YAML + PGM) read and written. No MRPT here.

#include "dispel/slam/grid_map.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <unordered_map>
#include <vector>

#include "dispel/io/atomic_file.hpp"
#include "dispel/io/text.hpp"
#include "dispel/jobs/job.hpp"

namespace dispel::slam {
namespace {

using jobs::JobError;

// map_saver's thresholds (percent) and pixel values.
constexpr int kSaverOccupiedPercent = 65;
constexpr int kSaverFreePercent = 25;
constexpr int kOccupiedPixel = 0;
constexpr int kFreePixel = 254;
constexpr int kUnknownPixel = 205;

std::string folder_of(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? std::string() : path.substr(0, slash + 1);
}

std::string file_name_of(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

// The shortest decimal text that reads back as exactly @p v.
std::string exact(double v) {
  char text[64];
  for (int digits = 6; digits <= 17; ++digits) {
    std::snprintf(text, sizeof text, "%.*g", digits, v);
    if (std::strtod(text, nullptr) == v) break;
  }
  return text;
}

YAML::Node required(const YAML::Node& root, const std::string& key, const std::string& path) {
  const YAML::Node node = root[key];
  if (!node) throw JobError(path + ": no " + io::quote(key) + " key (map_server needs it)");
  return node;
}

double number(const YAML::Node& root, const std::string& key, const std::string& path) {
  const YAML::Node node = required(root, key, path);
  try {
    const double v = node.as<double>();
    if (!std::isfinite(v)) throw JobError(path + ": " + key + " is not finite");
    return v;
  } catch (const YAML::Exception&) {
    throw JobError(path + ": " + key + " is not a number");
  }
}

// A PGM image: pixels in file order (top row first), scaled to 0-255.
struct Pgm {
  int width = 0;
  int height = 0;
  std::vector<int> pixels;
};

// The next header token of a PGM, skipping white space and '#' comments.
bool pgm_token(std::istream& in, std::string& token) {
  token.clear();
  int c;
  while ((c = in.get()) != EOF) {
    if (c == '#') {
      while ((c = in.get()) != EOF && c != '\n') {
      }
      continue;
    }
    if (std::isspace(c) != 0) {
      if (!token.empty()) return true;
      continue;
    }
    token.push_back(static_cast<char>(c));
  }
  return !token.empty();
}

int pgm_header_number(std::istream& in, const std::string& path, const char* what) {
  std::string token;
  if (!pgm_token(in, token)) throw JobError(path + ": PGM header ends before its " + what);
  char* end = nullptr;
  const long v = std::strtol(token.c_str(), &end, 10);
  if (*end != '\0' || v <= 0 || v > 1000000) {
    throw JobError(path + ": PGM " + what + " " + io::quote(token) + " is not a positive integer");
  }
  return static_cast<int>(v);
}

Pgm read_pgm(const std::string& path) {
  jobs::check_input_file(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw JobError(path + ": cannot read");
  in.seekg(0, std::ios::end);
  const auto file_size = static_cast<std::uint64_t>(std::max<std::streamoff>(in.tellg(), 0));
  in.seekg(0);
  char magic[2] = {0, 0};
  in.read(magic, 2);
  if (in.gcount() != 2 || magic[0] != 'P' || (magic[1] != '5' && magic[1] != '2')) {
    throw JobError(path + ": not a PGM image (P5 or P2); map_server's other formats are not read");
  }
  const bool binary = magic[1] == '5';
  Pgm pgm;
  pgm.width = pgm_header_number(in, path, "width");
  pgm.height = pgm_header_number(in, path, "height");
  const int maxval = pgm_header_number(in, path, "maximum value");
  if (maxval > 255) {
    throw JobError(path + ": 16-bit PGM (maximum value " + std::to_string(maxval) +
                   ") is not supported; save the map with 8 bits");
  }
  const std::size_t n = static_cast<std::size_t>(pgm.width) * static_cast<std::size_t>(pgm.height);
  // Every pixel takes at least a byte of the file (P2: a digit and a space): a header that states
  // more is refused before anything is allocated for them (it asked for up to 10^12 pixels).
  if (n > file_size) {
    throw JobError(path + ": image is " + std::to_string(pgm.width) + " x " +
                   std::to_string(pgm.height) + " pixels, more than the file's " +
                   std::to_string(file_size) + " bytes can hold (truncated?)");
  }
  pgm.pixels.resize(n);
  std::size_t got = 0;
  if (binary) {  // The header ended with one white-space character, already read.
    std::vector<char> bytes(n);
    in.read(bytes.data(), static_cast<std::streamsize>(n));
    got = static_cast<std::size_t>(in.gcount());
    for (std::size_t i = 0; i < got; ++i) pgm.pixels[i] = static_cast<unsigned char>(bytes[i]);
  } else {
    std::string token;
    while (got < n && pgm_token(in, token)) {
      char* end = nullptr;
      const long v = std::strtol(token.c_str(), &end, 10);
      if (*end != '\0' || v < 0 || v > maxval) {
        throw JobError(path + ": pixel " + std::to_string(got) + " " + io::quote(token) +
                       " is not a value in 0.." + std::to_string(maxval));
      }
      pgm.pixels[got++] = static_cast<int>(v);
    }
  }
  if (got != n) {
    throw JobError(path + ": image is " + std::to_string(pgm.width) + " x " +
                   std::to_string(pgm.height) + " pixels but holds only " + std::to_string(got) +
                   " of them (truncated?)");
  }
  for (int& p : pgm.pixels) {
    if (p > maxval) throw JobError(path + ": a pixel exceeds the maximum value");
    if (maxval != 255) p = static_cast<int>(std::lround(255.0 * p / maxval));
  }
  return pgm;
}

void write_or_throw(std::ofstream& out, const std::string& path) {
  out.flush();
  if (!out) throw JobError(path + ": cannot write (" + std::strerror(errno) + ")");
}

// A YAML double-quoted string.
std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') out.push_back('\\');
    out.push_back(c);
  }
  return out + "\"";
}

}  // namespace

namespace {

// The centres of @p map's occupied cells in its frame.
std::vector<Eigen::Vector2d> occupied_centres(const GridMap& map) {
  std::vector<Eigen::Vector2d> out;
  for (int row = 0; row < map.height; ++row) {
    for (int col = 0; col < map.width; ++col) {
      if (map.at(col, row) < kSaverOccupiedPercent) continue;
      out.push_back(
          map.origin.apply({(col + 0.5) * map.resolution_m, (row + 0.5) * map.resolution_m}));
    }
  }
  return out;
}

// Points in square buckets of the tolerance's size: a point within the tolerance of a query lies
// in the query's bucket or one of its eight neighbours.
class PointBuckets {
 public:
  PointBuckets(const std::vector<Eigen::Vector2d>& points, double tolerance_m)
      : bucket_m_(std::max(tolerance_m, 1e-6)), tolerance_m_(tolerance_m) {
    for (const Eigen::Vector2d& p : points) {
      buckets_[eval::OccupancyGrid::cell_key(bucket(p.x()), bucket(p.y()))].push_back(p);
    }
  }
  bool has_near(const Eigen::Vector2d& q) const {
    const std::int64_t bx = bucket(q.x()), by = bucket(q.y());
    for (std::int64_t dx = -1; dx <= 1; ++dx) {
      for (std::int64_t dy = -1; dy <= 1; ++dy) {
        const auto it = buckets_.find(eval::OccupancyGrid::cell_key(bx + dx, by + dy));
        if (it == buckets_.end()) continue;
        for (const Eigen::Vector2d& p : it->second) {
          if ((p - q).norm() <= tolerance_m_) return true;
        }
      }
    }
    return false;
  }

 private:
  std::int64_t bucket(double v) const {
    return static_cast<std::int64_t>(std::floor(v / bucket_m_));
  }
  double bucket_m_, tolerance_m_;
  std::unordered_map<std::uint64_t, std::vector<Eigen::Vector2d>> buckets_;
};

}  // namespace

eval::MapComparison compare_grid_maps(const GridMap& reference, const GridMap& evaluated,
                                      double tolerance_m) {
  reference.validate();
  evaluated.validate();
  if (!std::isfinite(tolerance_m) || tolerance_m < 0.0) {
    throw jobs::JobError("map comparison: the tolerance " + std::to_string(tolerance_m) +
                         " m must be finite and not negative");
  }
  const std::vector<Eigen::Vector2d> ref = occupied_centres(reference);
  const std::vector<Eigen::Vector2d> got = occupied_centres(evaluated);
  const PointBuckets ref_buckets(ref, tolerance_m), got_buckets(got, tolerance_m);
  eval::MapComparison out;
  out.reference_occupied = static_cast<std::int64_t>(ref.size());
  out.evaluated_occupied = static_cast<std::int64_t>(got.size());
  for (const Eigen::Vector2d& p : got) out.wrongly_occupied += ref_buckets.has_near(p) ? 0 : 1;
  for (const Eigen::Vector2d& p : ref) out.lost += got_buckets.has_near(p) ? 0 : 1;
  return out;
}

std::int64_t GridMap::occupied_cells() const {
  std::int64_t n = 0;
  for (const std::int8_t c : cells) n += c >= kSaverOccupiedPercent;
  return n;
}

std::int64_t GridMap::free_cells() const {
  std::int64_t n = 0;
  for (const std::int8_t c : cells) n += c >= 0 && c <= kSaverFreePercent;
  return n;
}

void GridMap::validate() const {
  if (!(resolution_m > 0.0) || !std::isfinite(resolution_m)) {
    throw JobError("map resolution " + exact(resolution_m) +
                   " m: must be a positive number of metres per cell");
  }
  if (!std::isfinite(origin.x_m) || !std::isfinite(origin.y_m) || !std::isfinite(origin.yaw_rad)) {
    throw JobError("map origin is not finite");
  }
  if (width <= 0 || height <= 0) {
    throw JobError("map of " + std::to_string(width) + " x " + std::to_string(height) +
                   " cells: it has none");
  }
  if (cells.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height)) {
    throw JobError("map of " + std::to_string(width) + " x " + std::to_string(height) +
                   " cells holds " + std::to_string(cells.size()) + " values");
  }
  for (const std::int8_t c : cells) {
    if (c < kUnknownCell || c > kOccupiedCell) {
      throw JobError("map cell value " + std::to_string(c) + ": must be -1 (unknown) or 0..100");
    }
  }
}

namespace {

GridMap read_map(const std::string& path) {
  jobs::check_input_file(path);
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw JobError(path + ": not a YAML file (" + io::one_line(e.what(), 200) + ")");
  }
  if (!root.IsMap()) throw JobError(path + ": not a map_server map (no key: value pairs)");

  GridMap map;
  map.resolution_m = number(root, "resolution", path);
  if (!(map.resolution_m > 0.0)) {
    throw JobError(path + ": resolution " + exact(map.resolution_m) +
                   ": must be a positive number of metres per cell");
  }
  const YAML::Node origin = required(root, "origin", path);
  if (!origin.IsSequence() || origin.size() != 3) {
    throw JobError(path + ": origin must be [x, y, yaw]");
  }
  double o[3];
  for (std::size_t i = 0; i < 3; ++i) {
    try {
      o[i] = origin[i].as<double>();
    } catch (const YAML::Exception&) {
      throw JobError(path + ": origin must be [x, y, yaw] numbers");
    }
    if (!std::isfinite(o[i])) throw JobError(path + ": origin is not finite");
  }
  map.origin = {o[0], o[1], o[2]};
  const double occupied_thresh = number(root, "occupied_thresh", path);
  const double free_thresh = number(root, "free_thresh", path);
  if (!(0.0 <= free_thresh && free_thresh <= occupied_thresh && occupied_thresh <= 1.0)) {
    throw JobError(path + ": thresholds must hold 0 <= free_thresh <= occupied_thresh <= 1 (" +
                   exact(free_thresh) + ", " + exact(occupied_thresh) + ")");
  }
  bool negate = false;
  try {
    const YAML::Node n = required(root, "negate", path);
    negate = n.as<int>() != 0;
  } catch (const YAML::Exception&) {
    throw JobError(path + ": negate must be 0 or 1");
  }
  std::string mode = "trinary";
  if (const YAML::Node m = root["mode"]) mode = m.as<std::string>("");
  if (mode != "trinary" && mode != "scale" && mode != "raw") {
    throw JobError(path + ": mode " + io::quote(mode) + ": expected trinary, scale or raw");
  }
  std::string image;
  try {
    image = required(root, "image", path).as<std::string>();
  } catch (const YAML::Exception&) {
    throw JobError(path + ": image must be a file name");
  }
  if (image.empty()) throw JobError(path + ": image is empty");
  if (image.front() != '/') image = folder_of(path) + image;

  const Pgm pgm = read_pgm(image);
  map.width = pgm.width;
  map.height = pgm.height;
  map.cells.resize(pgm.pixels.size());
  for (int row = 0; row < map.height; ++row) {
    for (int col = 0; col < map.width; ++col) {
      int pixel = pgm.pixels[static_cast<std::size_t>(map.height - 1 - row) * map.width + col];
      std::int8_t value;
      if (mode == "raw") {
        value = pixel <= kOccupiedCell ? static_cast<std::int8_t>(pixel) : kUnknownCell;
      } else {
        if (negate) pixel = 255 - pixel;
        const double occupancy = (255.0 - pixel) / 255.0;
        if (occupancy > occupied_thresh) {
          value = kOccupiedCell;
        } else if (occupancy < free_thresh) {
          value = kFreeCell;
        } else if (mode == "trinary" || occupied_thresh == free_thresh) {
          // (scale with equal thresholds: an occupancy equal to both is neither; 0 / 0 before.)
          value = kUnknownCell;
        } else {
          value = static_cast<std::int8_t>(99.0 * (occupancy - free_thresh) /
                                           (occupied_thresh - free_thresh));
        }
      }
      map.cells[static_cast<std::size_t>(row) * map.width + col] = value;
    }
  }
  return map;
}

}  // namespace

GridMap read_map_yaml(const std::string& path) {
  // The messages name the files (the image's name is the YAML file's text) and quote their text:
  // one line, cut.
  try {
    return read_map(path);
  } catch (const JobError& e) {
    throw JobError(io::one_line(e.what()));
  }
}

void write_map_yaml(const GridMap& map, const std::string& yaml_path) {
  try {
    map.validate();
  } catch (const JobError& e) {
    throw JobError(yaml_path + ": " + e.what());
  }
  std::string stem = file_name_of(yaml_path);
  if (const auto dot = stem.find_last_of('.'); dot != std::string::npos && dot > 0) {
    stem = stem.substr(0, dot);
  }
  const std::string image_name = stem + ".pgm";
  const std::string image_path = folder_of(yaml_path) + image_name;

  try {
    io::AtomicFile image(image_path);
    {
      std::ofstream out(image.temp_path(), std::ios::binary);
      write_or_throw(out, image_path);
      out << "P5\n# dispel map, " << exact(map.resolution_m) << " m/cell\n"
          << map.width << " " << map.height << "\n255\n";
      std::vector<char> row(static_cast<std::size_t>(map.width));
      for (int r = map.height - 1; r >= 0; --r) {
        for (int col = 0; col < map.width; ++col) {
          const std::int8_t c = map.at(col, r);
          const int pixel = c >= kSaverOccupiedPercent           ? kOccupiedPixel
                            : (c >= 0 && c <= kSaverFreePercent) ? kFreePixel
                                                                 : kUnknownPixel;
          row[static_cast<std::size_t>(col)] = static_cast<char>(pixel);
        }
        out.write(row.data(), static_cast<std::streamsize>(row.size()));
      }
      write_or_throw(out, image_path);
    }
    image.commit();

    io::AtomicFile yaml(yaml_path);
    {
      std::ofstream out(yaml.temp_path());
      write_or_throw(out, yaml_path);
      out << "image: " << quoted(image_name) << "\nresolution: " << exact(map.resolution_m)
          << "\norigin: [" << exact(map.origin.x_m) << ", " << exact(map.origin.y_m) << ", "
          << exact(map.origin.yaw_rad) << "]\nnegate: 0\noccupied_thresh: 0.65\n"
          << "free_thresh: 0.196\n";
      write_or_throw(out, yaml_path);
    }
    yaml.commit();
  } catch (const JobError&) {
    throw;
  } catch (const std::exception& e) {
    throw JobError(io::one_line(e.what()));
  }
}

}  // namespace dispel::slam
