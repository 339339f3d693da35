#include "dispel/io/render.hpp"

#include <cairo.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/LaserScan.h>
#include <sys/stat.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>

#include "dispel/core/dynamic_filter.hpp"
#include "dispel/core/pose_buffer.hpp"
#include "dispel/core/segmentation.hpp"
#include "dispel/io/bag_topics.hpp"
#include "dispel/io/config_yaml.hpp"
#include "dispel/io/filter_job.hpp"
#include "dispel/io/frame_tree.hpp"
#include "dispel/io/render_canvas.hpp"
#include "dispel/io/ros_convert.hpp"

namespace dispel::io {

Rgb object_colour(std::size_t object_index) {
  static constexpr Rgb kPalette[] = {{31, 119, 180}, {44, 160, 44},   {148, 103, 189},
                                     {140, 86, 75},  {227, 119, 194}, {150, 150, 20},
                                     {23, 190, 207}, {40, 50, 140}};
  return kPalette[object_index % (sizeof kPalette / sizeof kPalette[0])];
}

Rgb track_colour(ObjectClass object_class) {
  switch (object_class) {
    case ObjectClass::kDynamic:
      return colours::kDynamic;
    case ObjectClass::kUnknown:
      return colours::kUnknown;
    case ObjectClass::kStatic:
      break;
  }
  return colours::kStaticTrack;
}

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

void check_input_file(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) throw JobError(path + ": " + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) throw JobError(path + ": not a regular file");
}

void check_not_cancelled(const std::atomic<bool>* cancel) {
  if (cancel != nullptr && cancel->load()) throw JobCancelled();
}

std::string seconds_text(double s) { return format_number(s, 1) + " s"; }

// ------------------------------------------------------------------------------------------
// The bag: its topics, and the sensor's pose at a scan's stamp.

struct BagInfo {
  explicit BagInfo(const rosbag::Bag& bag) : topics(bag) {}
  BagTopics topics;
  double begin_s = 0.0, end_s = 0.0;

  bool has(const std::string& topic, const std::string& type) const {
    return topics.has(topic, type);
  }
  std::string topics_of_type(const std::string& type) const { return topics.list(type); }
};

BagInfo inspect(rosbag::Bag& bag) {
  BagInfo info(bag);
  rosbag::View all(bag);
  if (all.size() > 0) {
    info.begin_s = all.getBeginTime().toSec();
    info.end_s = all.getEndTime().toSec();
  }
  return info;
}

// The laser's pose in the drawn frame at a stamp: identity (static sensor), or the base's pose
// from an Odometry topic (odometry or ground truth) times the laser's mount.
struct SensorPoses {
  bool identity = true;
  PoseBuffer base{0.05, 0.5};
  Pose2 mount;
  std::string pose_topic;
  std::string description;  // For the picture's subtitle.

  std::optional<Pose2> at(double stamp_s) const {
    if (identity) return Pose2{};
    Pose2 p;
    if (base.lookup(stamp_s, p) != PoseLookup::kOk) return std::nullopt;
    return p * mount;
  }
};

// What the first pass learns: poses, the mount, and a look at the scanner.
struct FirstPass {
  SensorPoses poses;
  LaserScan first_scan;
  std::vector<double> first_stamps;  // Up to 200 scan stamps (for --scale-to-scanner).
};

FirstPass read_poses(rosbag::Bag& bag, const BagInfo& info, const RenderOptions& o,
                     const std::atomic<bool>* cancel) {
  FirstPass f;
  f.poses.base = PoseBuffer(o.pose_tolerance_s, 0.5);
  f.poses.identity = o.static_sensor;
  if (o.static_sensor) {
    f.poses.description = "static sensor (identity pose)";
  } else if (o.frame == "truth") {
    f.poses.pose_topic = o.truth_topic;
    if (!info.has(o.truth_topic, "nav_msgs/Odometry")) {
      throw JobError(
          o.input + ": no nav_msgs/Odometry topic " + o.truth_topic +
          " for --frame truth (Odometry topics: " + info.topics_of_type("nav_msgs/Odometry") +
          "); ground truth comes from dispel sim");
    }
  } else {
    f.poses.pose_topic = o.odom_topic;
    if (!info.has(o.odom_topic, "nav_msgs/Odometry")) {
      throw JobError(o.input + ": no nav_msgs/Odometry topic " + o.odom_topic +
                     " (Odometry topics: " + info.topics_of_type("nav_msgs/Odometry") +
                     "); choose one with --odom-topic, or use --static-sensor for a sensor that "
                     "does not move");
    }
  }

  FrameTree mounts;
  std::string base_frame = "base_link";
  std::string fixed_frame = o.frame == "truth" ? "map" : "odom";
  std::string laser_frame;
  bool have_pose_frames = false;
  std::vector<std::string> topics{o.scan_topic, "/tf", "/tf_static"};
  if (!o.static_sensor) topics.push_back(f.poses.pose_topic);
  rosbag::View view(bag, rosbag::TopicQuery(topics));
  for (const rosbag::MessageInstance& m : view) {
    check_not_cancelled(cancel);
    if (m.getTopic() == o.scan_topic) {
      if (f.first_stamps.size() >= 200) continue;
      const auto scan = m.instantiate<sensor_msgs::LaserScan>();
      if (!scan) continue;
      if (f.first_stamps.empty()) {
        f.first_scan = from_ros(*scan);
        laser_frame = FrameTree::normalise(scan->header.frame_id);
      }
      f.first_stamps.push_back(to_seconds(scan->header.stamp));
    } else if (!o.static_sensor && m.getTopic() == f.poses.pose_topic) {
      const auto odom = m.instantiate<nav_msgs::Odometry>();
      if (!odom) continue;
      if (!have_pose_frames) {
        if (!odom->child_frame_id.empty()) base_frame = FrameTree::normalise(odom->child_frame_id);
        if (!odom->header.frame_id.empty()) {
          fixed_frame = FrameTree::normalise(odom->header.frame_id);
        }
        have_pose_frames = true;
      }
      f.poses.base.add(to_seconds(odom->header.stamp), from_ros(odom->pose.pose));
    } else {
      const auto tf = m.instantiate<tf2_msgs::TFMessage>();
      if (!tf) continue;
      for (const auto& t : tf->transforms) {
        const std::string parent = FrameTree::normalise(t.header.frame_id);
        const std::string child = FrameTree::normalise(t.child_frame_id);
        // Only fixed mounts: not the robot's motion in odom or map.
        if (parent == fixed_frame || child == fixed_frame || parent == "odom" || child == "odom" ||
            parent == "map" || child == "map") {
          continue;
        }
        mounts.set(parent, child, from_ros(t.transform));
      }
    }
  }
  if (f.first_stamps.empty()) throw JobError(o.input + ": no scans on " + o.scan_topic);
  if (!o.static_sensor) {
    if (f.poses.base.empty()) {
      throw JobError(o.input + ": no usable poses on " + f.poses.pose_topic);
    }
    const auto found = mounts.lookup(base_frame, laser_frame.empty() ? base_frame : laser_frame);
    if (!found) {
      throw JobError(o.input + ": no transform from " + base_frame + " to " + laser_frame +
                     " in /tf_static or /tf; record the sensor mount, or use --static-sensor");
    }
    f.poses.mount = *found;
    f.poses.identity = false;
    f.poses.description = std::string(o.frame == "truth" ? "ground truth " : "odometry ") +
                          f.poses.pose_topic + " + mount " + base_frame + " \u2192 " +
                          (laser_frame.empty() ? base_frame : laser_frame);
  }
  return f;
}

// ------------------------------------------------------------------------------------------
// Layout shared by both views: a title band, the plot, a legend band.

struct Layout {
  int plot_x = 0, plot_y = 0, plot_w = 0, plot_h = 0;
  double title_y = 0.0, subtitle_y = 0.0, legend_y = 0.0;
};

Layout make_layout(const Canvas& canvas) {
  const double f = canvas.font_px();
  Layout l;
  l.title_y = 1.6 * f;
  l.subtitle_y = 2.8 * f;
  l.plot_x = static_cast<int>(std::round(f));
  l.plot_y = static_cast<int>(std::round(3.5 * f));
  l.plot_w = canvas.width() - 2 * l.plot_x;
  const int legend_h = static_cast<int>(std::round(2.4 * f));
  l.plot_h = canvas.height() - l.plot_y - legend_h;
  l.legend_y = canvas.height() - 0.85 * f;
  if (l.plot_w < 10 || l.plot_h < 10) throw JobError("the picture is too small to draw in");
  return l;
}

// Fits the box [lo, hi] (metres, padded by 4%) into the plot area with equal scales on x and y.
PixelTransform fit(const Layout& l, Eigen::Vector2d lo, Eigen::Vector2d hi) {
  Eigen::Vector2d size = (hi - lo).cwiseMax(Eigen::Vector2d(1.0, 1.0));
  const Eigen::Vector2d centre = 0.5 * (lo + hi);
  size *= 1.08;
  PixelTransform t;
  t.scale_px_per_m = std::min(l.plot_w / size.x(), l.plot_h / size.y());
  t.centre_x_m = centre.x();
  t.centre_y_m = centre.y();
  t.centre_u_px = l.plot_x + 0.5 * l.plot_w;
  t.centre_v_px = l.plot_y + 0.5 * l.plot_h;
  return t;
}

void draw_frame(cairo_t* cr, const Layout& l) {
  set_colour(cr, {180, 180, 180});
  cairo_set_line_width(cr, 1.0);
  cairo_rectangle(cr, l.plot_x - 0.5, l.plot_y - 0.5, l.plot_w + 1.0, l.plot_h + 1.0);
  cairo_stroke(cr);
}

// A bar of a round number of metres in the plot's bottom-left corner, on a white box.
void draw_scale_bar(cairo_t* cr, const Layout& l, const PixelTransform& t, double f) {
  const double metres = nice_step(l.plot_w / t.scale_px_per_m / 6.0);
  const double len = metres * t.scale_px_per_m;
  const double x0 = l.plot_x + 1.0 * f, y0 = l.plot_y + l.plot_h - 1.0 * f;
  set_colour(cr, colours::kBackground, 0.85);
  cairo_rectangle(cr, x0 - 0.5 * f, y0 - 2.0 * f, len + 1.0 * f, 2.5 * f);
  cairo_fill(cr);
  set_colour(cr, {0, 0, 0});
  cairo_set_line_width(cr, std::max(2.0, 0.2 * f));
  cairo_move_to(cr, x0, y0);
  cairo_line_to(cr, x0 + len, y0);
  cairo_move_to(cr, x0, y0 - 0.4 * f);
  cairo_line_to(cr, x0, y0 + 0.2 * f);
  cairo_move_to(cr, x0 + len, y0 - 0.4 * f);
  cairo_line_to(cr, x0 + len, y0 + 0.2 * f);
  cairo_stroke(cr);
  draw_text(cr, x0 + 0.5 * len, y0 - 0.6 * f, format_number(metres, 3) + " m", 0.9 * f,
            TextAlign::kCentre);
}

// Legend entries left to right along the bottom band; returns where the next one starts.
double legend_swatch(cairo_t* cr, double x, double y, double f, Rgb colour,
                     const std::string& text) {
  set_colour(cr, colour);
  cairo_rectangle(cr, x, y - 0.8 * f, 0.8 * f, 0.8 * f);
  cairo_fill(cr);
  const double w = draw_text(cr, x + 1.2 * f, y, text, f);
  return x + 1.2 * f + w + 1.5 * f;
}

double legend_line(cairo_t* cr, double x, double y, double f, Rgb colour, const std::string& text) {
  set_colour(cr, colour);
  cairo_set_line_width(cr, std::max(2.0, 0.15 * f));
  cairo_move_to(cr, x, y - 0.35 * f);
  cairo_line_to(cr, x + 1.6 * f, y - 0.35 * f);
  cairo_stroke(cr);
  const double w = draw_text(cr, x + 2.0 * f, y, text, f);
  return x + 2.0 * f + w + 1.5 * f;
}

void draw_sensor_marker(cairo_t* cr, const PixelTransform& t, const Pose2& pose, double f) {
  const Eigen::Vector2d c = t.to_pixel(pose.translation());
  const double a = -pose.yaw_rad;  // Image angles turn the other way.
  const double s = 0.6 * f;
  cairo_move_to(cr, c.x() + s * std::cos(a), c.y() + s * std::sin(a));
  cairo_line_to(cr, c.x() + 0.6 * s * std::cos(a + 2.4), c.y() + 0.6 * s * std::sin(a + 2.4));
  cairo_line_to(cr, c.x() + 0.6 * s * std::cos(a - 2.4), c.y() + 0.6 * s * std::sin(a - 2.4));
  cairo_close_path(cr);
  set_colour(cr, {0, 0, 0});
  cairo_fill(cr);
}

// ------------------------------------------------------------------------------------------
// Map view.

// Robust bounds of many points without keeping them: histograms of x and y in 0.25 m bins; the
// 0.1% and 99.9% quantiles drop the odd stray return far away.
class RobustBounds {
 public:
  void add(const Eigen::Vector2d& p) {
    ++hx_[bin(p.x())];
    ++hy_[bin(p.y())];
    ++n_;
  }
  std::int64_t count() const { return n_; }
  Eigen::Vector2d lo() const { return {quantile(hx_, 0.001), quantile(hy_, 0.001)}; }
  Eigen::Vector2d hi() const { return {quantile(hx_, 0.999) + kBin, quantile(hy_, 0.999) + kBin}; }

 private:
  static constexpr double kBin = 0.25;
  static std::int64_t bin(double v) {
    return static_cast<std::int64_t>(std::floor(std::clamp(v, -1e6, 1e6) / kBin));
  }
  double quantile(const std::map<std::int64_t, std::int64_t>& h, double q) const {
    const auto target = static_cast<std::int64_t>(q * static_cast<double>(n_));
    std::int64_t seen = 0;
    for (const auto& [b, c] : h) {
      seen += c;
      if (seen > target) return static_cast<double>(b) * kBin;
    }
    return h.empty() ? 0.0 : static_cast<double>(h.rbegin()->first) * kBin;
  }
  std::map<std::int64_t, std::int64_t> hx_, hy_;
  std::int64_t n_ = 0;
};

// Calls @p fn(scan message, sensor pose) for every scan of @p topic in the window that has a
// pose; counts the scans in the window with and without one.
template <typename Fn>
void for_each_scan_in_window(rosbag::Bag& bag, const std::string& topic, double begin_s,
                             double from_s, double to_s, const SensorPoses& poses,
                             const std::atomic<bool>* cancel, std::int64_t& in_window,
                             std::int64_t& without_pose, Fn&& fn) {
  in_window = 0;
  without_pose = 0;
  rosbag::View view(bag, rosbag::TopicQuery(topic));
  for (const rosbag::MessageInstance& m : view) {
    check_not_cancelled(cancel);
    const double t = m.getTime().toSec() - begin_s;
    if (t < from_s || t > to_s) continue;
    const auto msg = m.instantiate<sensor_msgs::LaserScan>();
    if (!msg) continue;
    ++in_window;
    const std::optional<Pose2> pose = poses.at(to_seconds(msg->header.stamp));
    if (!pose) {
      ++without_pose;
      continue;
    }
    fn(*msg, *pose);
  }
}

// The valid points of a scan message in the frame given by @p pose; @p fn(point, beam).
template <typename Fn>
void for_each_point(const sensor_msgs::LaserScan& msg, const Pose2& pose, Fn&& fn) {
  for (std::size_t i = 0; i < msg.ranges.size(); ++i) {
    const float r = msg.ranges[i];
    if (!(r >= msg.range_min && r <= msg.range_max) || !std::isfinite(r)) continue;
    const double b = msg.angle_min + static_cast<double>(i) * msg.angle_increment;
    fn(pose.apply({r * std::cos(b), r * std::sin(b)}), i);
  }
}

enum PointClass : int { kKeptClass = 0, kDynamicClass = 1, kUnknownClass = 2, kClassCount = 3 };

std::uint32_t pixel_value(Rgb c) {
  return 0xFF000000U | (static_cast<std::uint32_t>(c.r) << 16) |
         (static_cast<std::uint32_t>(c.g) << 8) | c.b;
}

Rgb kept_shade(std::uint32_t hits) {
  const double t = std::min(1.0, std::log1p(static_cast<double>(hits)) /
                                     std::log1p(static_cast<double>(colours::kKeptSaturation)));
  const auto mix = [t](std::uint8_t a, std::uint8_t b) {
    return static_cast<std::uint8_t>(std::lround(a + (b - a) * t));
  };
  return {mix(colours::kKeptFaint.r, colours::kKept.r),
          mix(colours::kKeptFaint.g, colours::kKept.g),
          mix(colours::kKeptFaint.b, colours::kKept.b)};
}

// Counts per pixel and class over the plot area, then one ARGB image of them: a pixel takes the
// colour of its most frequent class (removed classes win ties); removed pixels also spread to
// their empty neighbours (3 x 3) so that a person's trail shows at any scale.
class PointRaster {
 public:
  PointRaster(int w, int h)
      : w_(w), h_(h), counts_(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 3, 0) {}

  void add(int col, int row, PointClass c) {
    if (col < 0 || row < 0 || col >= w_ || row >= h_) return;
    std::uint32_t& n = counts_[index(col, row) * 3 + static_cast<std::size_t>(c)];
    if (n < std::numeric_limits<std::uint32_t>::max()) ++n;
  }

  // Paints the raster with its top-left corner at (x, y).
  void paint(cairo_t* cr, int x, int y) const {
    cairo_surface_t* img = cairo_image_surface_create(CAIRO_FORMAT_ARGB32, w_, h_);
    cairo_surface_flush(img);
    unsigned char* data = cairo_image_surface_get_data(img);
    const int stride = cairo_image_surface_get_stride(img);
    const auto px = [&](int col, int row) -> std::uint32_t& {
      return *reinterpret_cast<std::uint32_t*>(data + static_cast<std::ptrdiff_t>(row) * stride +
                                               static_cast<std::ptrdiff_t>(col) * 4);
    };
    for (int row = 0; row < h_; ++row) {
      for (int col = 0; col < w_; ++col) px(col, row) = 0;  // Transparent.
    }
    std::vector<std::pair<int, int>> removed;
    for (int row = 0; row < h_; ++row) {
      for (int col = 0; col < w_; ++col) {
        const std::uint32_t* n = &counts_[index(col, row) * 3];
        if (n[0] == 0 && n[1] == 0 && n[2] == 0) continue;
        if (n[1] + n[2] >= n[0]) {
          px(col, row) = pixel_value(n[1] >= n[2] ? colours::kDynamic : colours::kUnknown);
          removed.emplace_back(col, row);
        } else {
          px(col, row) = pixel_value(kept_shade(n[0]));
        }
      }
    }
    for (const auto& [col, row] : removed) {
      const std::uint32_t v = px(col, row);
      for (int dr = -1; dr <= 1; ++dr) {
        for (int dc = -1; dc <= 1; ++dc) {
          const int c = col + dc, r = row + dr;
          if (c < 0 || r < 0 || c >= w_ || r >= h_) continue;
          if (px(c, r) == 0) px(c, r) = v;
        }
      }
    }
    cairo_surface_mark_dirty(img);
    cairo_save(cr);
    cairo_rectangle(cr, x, y, w_, h_);
    cairo_clip(cr);
    cairo_set_source_surface(cr, img, x, y);
    cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_NEAREST);
    cairo_paint(cr);
    cairo_restore(cr);
    cairo_surface_destroy(img);
  }

 private:
  std::size_t index(int col, int row) const {
    return static_cast<std::size_t>(row) * static_cast<std::size_t>(w_) +
           static_cast<std::size_t>(col);
  }
  int w_, h_;
  std::vector<std::uint32_t> counts_;
};

RenderResult render_map(rosbag::Bag& bag, const BagInfo& info, const FirstPass& first,
                        const RenderOptions& o, const std::atomic<bool>* cancel) {
  RenderResult result;
  const std::string labels_topic = o.scan_topic + "_labels";
  result.labelled = info.has(labels_topic, "sensor_msgs/LaserScan");
  // A labels message holds the original ranges, the labels in its intensities.
  const std::string topic = result.labelled ? labels_topic : o.scan_topic;
  const double span = info.end_s - info.begin_s;
  const double from_s = o.from_s.value_or(-std::numeric_limits<double>::infinity());
  const double to_s = o.to_s.value_or(std::numeric_limits<double>::infinity());
  const std::string window = "between " + seconds_text(o.from_s.value_or(0.0)) + " and " +
                             (o.to_s ? seconds_text(*o.to_s) : "the end");

  // Second pass: the extent of the points and of the path.
  RobustBounds bounds;
  Eigen::Vector2d path_lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d path_hi = -path_lo;
  double first_stamp = std::numeric_limits<double>::infinity();
  double last_stamp = -first_stamp;
  double first_t = 0.0, last_t = 0.0;
  std::int64_t in_window = 0;
  for_each_scan_in_window(
      bag, topic, info.begin_s, from_s, to_s, first.poses, cancel, in_window,
      result.scans_without_pose, [&](const sensor_msgs::LaserScan& msg, const Pose2& pose) {
        const double stamp = to_seconds(msg.header.stamp);
        if (stamp < first_stamp) first_stamp = stamp;
        if (stamp > last_stamp) last_stamp = stamp;
        path_lo = path_lo.cwiseMin(pose.translation());
        path_hi = path_hi.cwiseMax(pose.translation());
        for_each_point(msg, pose, [&](const Eigen::Vector2d& p, std::size_t) { bounds.add(p); });
        ++result.scans_drawn;
      });
  if (in_window == 0) {
    throw JobError(o.input + ": no scans on " + topic + " " + window +
                   " from the start (the recording spans 0 to " + seconds_text(span) + ")");
  }
  if (result.scans_drawn == 0) {
    throw JobError(o.input + ": none of the " + std::to_string(in_window) + " scans " + window +
                   " has a pose from " + first.poses.pose_topic);
  }
  first_t = o.from_s ? std::max(*o.from_s, 0.0) : 0.0;
  last_t = o.to_s ? std::min(*o.to_s, span) : span;
  // The robot's path between the first and the last scan drawn.
  std::vector<Pose2> path;
  if (!first.poses.identity) {
    for (const TimedPose& p : first.poses.base.poses()) {
      if (p.stamp_s >= first_stamp - 0.05 && p.stamp_s <= last_stamp + 0.05) {
        path.push_back(p.pose);
        path_lo = path_lo.cwiseMin(p.pose.translation());
        path_hi = path_hi.cwiseMax(p.pose.translation());
      }
    }
  }
  Eigen::Vector2d lo = path_lo, hi = path_hi;
  if (bounds.count() > 0) {
    lo = lo.cwiseMin(bounds.lo());
    hi = hi.cwiseMax(bounds.hi());
  }

  Canvas canvas(o.output, o.width_px, o.height_px);
  cairo_t* cr = canvas.cr();
  const double f = canvas.font_px();
  const Layout l = make_layout(canvas);
  const PixelTransform t = fit(l, lo, hi);
  result.transform = t;
  result.width_px = canvas.width();
  result.height_px = canvas.height();
  result.from_s = first_t;
  result.to_s = last_t;

  // Third pass: the points into the raster.
  PointRaster raster(l.plot_w, l.plot_h);
  std::int64_t unused_in = 0, unused_without = 0;
  for_each_scan_in_window(
      bag, topic, info.begin_s, from_s, to_s, first.poses, cancel, unused_in, unused_without,
      [&](const sensor_msgs::LaserScan& msg, const Pose2& pose) {
        const bool has_labels = result.labelled && msg.intensities.size() == msg.ranges.size();
        for_each_point(msg, pose, [&](const Eigen::Vector2d& p, std::size_t i) {
          PointClass c = kKeptClass;
          if (has_labels) {
            const float label = msg.intensities[i];
            if (label == 1.0F) c = kDynamicClass;
            if (label == 2.0F) c = kUnknownClass;
          }
          (c == kKeptClass
               ? result.points_kept
               : (c == kDynamicClass ? result.points_dynamic : result.points_unknown))++;
          const Eigen::Vector2d px = t.to_pixel(p);
          raster.add(static_cast<int>(std::floor(px.x())) - l.plot_x,
                     static_cast<int>(std::floor(px.y())) - l.plot_y, c);
        });
      });
  raster.paint(cr, l.plot_x, l.plot_y);
  draw_frame(cr, l);

  // The robot's path, its start (circle) and end (triangle).
  if (path.size() >= 2) {
    set_colour(cr, colours::kTrajectory);
    cairo_set_line_width(cr, std::max(2.0, 0.12 * f));
    cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
    Eigen::Vector2d last(kNaN, kNaN);
    for (std::size_t k = 0; k < path.size(); ++k) {
      const Eigen::Vector2d p = t.to_pixel(path[k].translation());
      if (k == 0) {
        cairo_move_to(cr, p.x(), p.y());
      } else if (!((p - last).norm() < 1.0) || k + 1 == path.size()) {
        cairo_line_to(cr, p.x(), p.y());
      } else {
        continue;
      }
      last = p;
    }
    cairo_stroke(cr);
    const Eigen::Vector2d s = t.to_pixel(path.front().translation());
    cairo_arc(cr, s.x(), s.y(), 0.3 * f, 0.0, 2.0 * kPi);
    cairo_fill(cr);
  }
  if (first.poses.identity) {
    draw_sensor_marker(cr, t, Pose2{}, f);
  } else if (!path.empty()) {
    draw_sensor_marker(cr, t, path.back() * first.poses.mount, f);
  }
  draw_scale_bar(cr, l, t, f);

  // Title, subtitle, legend.
  draw_text(cr, l.plot_x, l.title_y,
            base_name(o.input) + " \u2014 " + seconds_text(first_t) + " to " +
                seconds_text(last_t) + " of " + seconds_text(span),
            1.4 * f, TextAlign::kLeft, true);
  std::string sub = "map, frame: " + first.poses.description + "; " +
                    std::to_string(result.scans_drawn) + " scans on " + topic;
  if (result.scans_without_pose > 0) {
    sub += " (" + std::to_string(result.scans_without_pose) + " without a pose left out)";
  }
  draw_text(cr, l.plot_x, l.subtitle_y, sub, 0.9 * f, TextAlign::kLeft, false, {80, 80, 80});
  double x = l.plot_x;
  if (result.labelled) {
    x = legend_swatch(cr, x, l.legend_y, f, colours::kKept, "kept");
    x = legend_swatch(cr, x, l.legend_y, f, colours::kDynamic, "removed: dynamic (label 1)");
    x = legend_swatch(cr, x, l.legend_y, f, colours::kUnknown, "removed: unknown (label 2)");
  } else {
    x = legend_swatch(cr, x, l.legend_y, f, colours::kKept,
                      "points (not filtered: no " + labels_topic + ")");
  }
  if (!path.empty()) x = legend_line(cr, x, l.legend_y, f, colours::kTrajectory, "robot path");
  const std::int64_t removed = result.points_dynamic + result.points_unknown;
  draw_text(cr, canvas.width() - l.plot_x, l.legend_y,
            "grey \u2192 black: hit more often; " + std::to_string(removed) + " of " +
                std::to_string(removed + result.points_kept) + " points removed",
            0.9 * f, TextAlign::kRight, false, {80, 80, 80});
  (void)x;
  canvas.commit();
  return result;
}

// ------------------------------------------------------------------------------------------
// Scan view.

double median_period(const std::vector<double>& stamps) {
  std::vector<double> d;
  for (std::size_t i = 1; i < stamps.size(); ++i) {
    if (stamps[i] > stamps[i - 1]) d.push_back(stamps[i] - stamps[i - 1]);
  }
  if (d.empty()) return 0.0;
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
  return d[d.size() / 2];
}

DynamicFilterConfig scan_view_config(const RenderOptions& o, const FirstPass& first) {
  DynamicFilterConfig config = default_config();
  if (o.config_path) {
    try {
      config = load_filter_config(*o.config_path);
    } catch (const ConfigError& e) {
      throw JobError(e.what());
    }
  }
  if (o.scale_to_scanner) {
    const double period = median_period(first.first_stamps);
    if (!(period > 0.0) || !(first.first_scan.angle_increment_rad > 0.0)) {
      throw JobError(o.input +
                     ": --scale-to-scanner needs scans with a positive angle increment and "
                     "increasing stamps");
    }
    config = scale_to_scanner(config, first.first_scan.angle_increment_rad, period);
  }
  return config;
}

void draw_arrow(cairo_t* cr, const Eigen::Vector2d& from, const Eigen::Vector2d& to, double head) {
  cairo_move_to(cr, from.x(), from.y());
  cairo_line_to(cr, to.x(), to.y());
  cairo_stroke(cr);
  const Eigen::Vector2d d = (to - from).normalized();
  const Eigen::Vector2d n(-d.y(), d.x());
  const Eigen::Vector2d a = to - head * d + 0.5 * head * n;
  const Eigen::Vector2d b = to - head * d - 0.5 * head * n;
  cairo_move_to(cr, to.x(), to.y());
  cairo_line_to(cr, a.x(), a.y());
  cairo_line_to(cr, b.x(), b.y());
  cairo_close_path(cr);
  cairo_fill(cr);
}

RenderResult render_scan(rosbag::Bag& bag, const BagInfo& info, const FirstPass& first,
                         const RenderOptions& o, const std::atomic<bool>* cancel) {
  RenderResult result;
  const DynamicFilterConfig config = scan_view_config(o, first);

  // Run the filter over the scans up to the one asked for.
  DynamicFilter filter(config);
  FilterResult filtered;
  LaserScan scan;
  Pose2 sensor_pose;
  bool have_pose = false;
  double scan_t = 0.0;
  std::int64_t k = 0;
  {
    rosbag::View view(bag, rosbag::TopicQuery(o.scan_topic));
    for (const rosbag::MessageInstance& m : view) {
      check_not_cancelled(cancel);
      const auto msg = m.instantiate<sensor_msgs::LaserScan>();
      if (!msg) continue;
      scan = from_ros(*msg);
      const std::optional<Pose2> pose = first.poses.at(scan.stamp_s);
      filter.process(scan, pose ? *pose : Pose2{kNaN, 0.0, 0.0}, filtered);
      if (k == o.scan_index) {
        have_pose = pose.has_value();
        if (pose) sensor_pose = *pose;
        scan_t = m.getTime().toSec() - info.begin_s;
        break;
      }
      ++k;
    }
  }
  if (k != o.scan_index) {
    throw JobError(o.input + ": scan index " + std::to_string(o.scan_index) +
                   " out of range: only " + std::to_string(k) + " scans on " + o.scan_topic);
  }
  if (const ScanIssue issue = check_scan(scan); issue != ScanIssue::kNone) {
    throw JobError(o.input + ": scan " + std::to_string(o.scan_index) + " cannot be segmented (" +
                   describe_scan_issue(scan, issue) + ")");
  }
  Segmenter segmenter(config.segmentation);
  const Segmentation seg = segmenter.segment(scan);
  result.objects = static_cast<std::int64_t>(seg.objects.size());

  // The scan's points in the sensor frame, and their extent.
  Eigen::Vector2d lo(-0.5, -0.5), hi(0.5, 0.5);
  std::vector<Eigen::Vector2d> points(scan.size(), Eigen::Vector2d(kNaN, kNaN));
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (!scan.is_valid(i) || !std::isfinite(scan.ranges_m[i])) continue;
    const double b = scan.bearing_rad(i);
    points[i] = {scan.ranges_m[i] * std::cos(b), scan.ranges_m[i] * std::sin(b)};
    lo = lo.cwiseMin(points[i]);
    hi = hi.cwiseMax(points[i]);
  }

  Canvas canvas(o.output, o.width_px, o.height_px);
  cairo_t* cr = canvas.cr();
  const double f = canvas.font_px();
  const Layout l = make_layout(canvas);
  const PixelTransform t = fit(l, lo, hi);
  result.transform = t;
  result.width_px = canvas.width();
  result.height_px = canvas.height();
  result.scans_drawn = 1;
  result.from_s = result.to_s = scan_t;

  cairo_save(cr);
  cairo_rectangle(cr, l.plot_x, l.plot_y, l.plot_w, l.plot_h);
  cairo_clip(cr);
  const Eigen::Vector2d origin = t.to_pixel(Eigen::Vector2d::Zero());
  const double far = std::hypot(l.plot_w, l.plot_h) + 2.0 * std::hypot(origin.x(), origin.y());
  // Masked sectors (image angles turn the other way).
  set_colour(cr, colours::kMaskedSector);
  for (const AngleSector& s : config.segmentation.masked_sectors) {
    cairo_move_to(cr, origin.x(), origin.y());
    cairo_arc_negative(cr, origin.x(), origin.y(), far, -s.begin_rad, -s.end_rad);
    cairo_close_path(cr);
    cairo_fill(cr);
  }
  // The field of view's ends.
  set_colour(cr, {200, 200, 200});
  cairo_set_line_width(cr, 1.0);
  for (const double b : {scan.angle_min_rad, scan.bearing_rad(scan.size() - 1)}) {
    cairo_move_to(cr, origin.x(), origin.y());
    cairo_line_to(cr, origin.x() + far * std::cos(-b), origin.y() + far * std::sin(-b));
  }
  cairo_stroke(cr);
  // Points: objects by colour, noise grey, masked beams faint.
  const double radius = std::max(2.0, 0.15 * f);
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (!std::isfinite(points[i].x())) continue;
    const std::int32_t label = seg.beam_labels.empty() ? kLabelNoise : seg.beam_labels[i];
    Rgb c = colours::kNoise;
    double a = 1.0;
    if (label >= 0) {
      c = object_colour(static_cast<std::size_t>(label));
    } else if (label == kLabelMasked) {
      a = 0.4;
    }
    set_colour(cr, c, a);
    const Eigen::Vector2d p = t.to_pixel(points[i]);
    cairo_arc(cr, p.x(), p.y(), radius, 0.0, 2.0 * kPi);
    cairo_fill(cr);
  }
  // Tracks, moved from the fixed frame into the sensor frame.
  result.track_ring_radius_px = 0.7 * f;
  const Pose2 to_sensor = sensor_pose.inverse();
  if (have_pose) {
    for (const TrackedObject& tr : filtered.tracks) {
      DrawnTrack d;
      d.id = tr.id;
      d.object_class = tr.object_class;
      d.position_m = to_sensor.apply(tr.position_m);
      const double c = std::cos(to_sensor.yaw_rad), s = std::sin(to_sensor.yaw_rad);
      d.velocity_mps = {c * tr.velocity_mps.x() - s * tr.velocity_mps.y(),
                        s * tr.velocity_mps.x() + c * tr.velocity_mps.y()};
      d.seen = tr.missed_scans == 0;
      result.tracks.push_back(d);
    }
  }
  cairo_set_line_width(cr, std::max(2.0, 0.15 * f));
  for (const DrawnTrack& d : result.tracks) {
    const Eigen::Vector2d p = t.to_pixel(d.position_m);
    const Rgb c = track_colour(d.object_class);
    set_colour(cr, c);
    if (!d.seen) {
      const double dash[] = {0.3 * f, 0.3 * f};
      cairo_set_dash(cr, dash, 2, 0.0);
    }
    cairo_arc(cr, p.x(), p.y(), result.track_ring_radius_px, 0.0, 2.0 * kPi);
    cairo_stroke(cr);
    cairo_set_dash(cr, nullptr, 0, 0.0);
    const Eigen::Vector2d tip = t.to_pixel(d.position_m + d.velocity_mps);  // 1 s ahead.
    if ((tip - p).norm() > result.track_ring_radius_px + 2.0) {
      draw_arrow(cr, p, tip, 0.6 * f);
    }
    std::string label = "#" + std::to_string(d.id);
    if (d.object_class != ObjectClass::kStatic) {
      label += " " + format_number(d.velocity_mps.norm(), 1) + " m/s";
    }
    draw_text(cr, p.x() + 0.8 * f, p.y() - 0.8 * f, label, 0.75 * f, TextAlign::kLeft, false, c);
  }
  cairo_restore(cr);
  draw_sensor_marker(cr, t, Pose2{}, f);
  draw_frame(cr, l);
  draw_scale_bar(cr, l, t, f);

  draw_text(cr, l.plot_x, l.title_y,
            base_name(o.input) + " \u2014 scan " + std::to_string(o.scan_index) + " at " +
                format_number(scan_t, 2) + " s",
            1.4 * f, TextAlign::kLeft, true);
  const std::string sub =
      "scan, sensor frame (x right, y up); " + std::to_string(seg.objects.size()) +
      " objects (eps " + format_number(config.segmentation.cluster_gap_m, 3) + " m, N_min " +
      std::to_string(config.segmentation.min_points) + "), " +
      std::to_string(result.tracks.size()) + " tracks (" + first.poses.description + ")" +
      (have_pose ? "" : "; no pose for this scan, so no tracks");
  draw_text(cr, l.plot_x, l.subtitle_y, sub, 0.9 * f, TextAlign::kLeft, false, {80, 80, 80});
  double x = l.plot_x;
  for (std::size_t i = 0; i < 3; ++i) {
    set_colour(cr, object_colour(i));
    cairo_rectangle(cr, x + static_cast<double>(i) * 0.9 * f, l.legend_y - 0.8 * f, 0.8 * f,
                    0.8 * f);
    cairo_fill(cr);
  }
  x += 2.7 * f;
  x += draw_text(cr, x + 0.4 * f, l.legend_y, "objects", f) + 1.9 * f;
  x = legend_swatch(cr, x, l.legend_y, f, colours::kNoise, "noise (< N_min)");
  if (!config.segmentation.masked_sectors.empty()) {
    x = legend_swatch(cr, x, l.legend_y, f, colours::kMaskedSector, "masked sector");
  }
  x = legend_line(cr, x, l.legend_y, f, colours::kStaticTrack, "static track");
  x = legend_line(cr, x, l.legend_y, f, colours::kDynamic, "dynamic");
  x = legend_line(cr, x, l.legend_y, f, colours::kUnknown, "unknown");
  draw_text(cr, x, l.legend_y, "arrow: velocity over 1 s; dashed: not seen now", 0.9 * f,
            TextAlign::kLeft, false, {80, 80, 80});
  canvas.commit();
  return result;
}

}  // namespace

RenderResult render_bag(const RenderOptions& o, const std::atomic<bool>* cancel) {
  if (o.view != "map" && o.view != "scan") {
    throw JobError("unknown view '" + o.view + "' (use --view map or --view scan)");
  }
  if (o.frame != "odom" && o.frame != "truth") {
    throw JobError("unknown frame '" + o.frame + "' (use --frame odom or --frame truth)");
  }
  if (o.width_px < 200 || o.height_px < 200 || o.width_px > 10000 || o.height_px > 10000) {
    throw JobError("picture size " + std::to_string(o.width_px) + "x" +
                   std::to_string(o.height_px) + " out of range (200 to 10000 pixels each way)");
  }
  if (o.scan_index < 0) {
    throw JobError("scan index " + std::to_string(o.scan_index) + " out of range (from 0)");
  }
  check_input_file(o.input);
  if (o.output.empty()) throw JobError("no output file given (-o OUT.png or OUT.svg)");
  { Canvas check(o.output, 200, 200); }  // Fails now on a bad extension, before any reading.
  if (o.config_path) {
    try {
      load_filter_config(*o.config_path);
    } catch (const ConfigError& e) {
      throw JobError(e.what());
    }
  }
  rosbag::Bag bag;
  open_bag_for_reading(bag, o.input);
  try {
    const BagInfo info = inspect(bag);
    if (!info.has(o.scan_topic, "sensor_msgs/LaserScan")) {
      throw JobError(o.input + ": no sensor_msgs/LaserScan topic " + o.scan_topic +
                     " (LaserScan topics: " + info.topics_of_type("sensor_msgs/LaserScan") +
                     "); choose one with --scan-topic");
    }
    if (o.view == "scan") {
      const auto count =
          static_cast<std::int64_t>(rosbag::View(bag, rosbag::TopicQuery(o.scan_topic)).size());
      if (o.scan_index >= count) {
        throw JobError(o.input + ": scan index " + std::to_string(o.scan_index) +
                       " out of range: " + std::to_string(count) + " scans on " + o.scan_topic +
                       " (0 to " + std::to_string(count - 1) + ")");
      }
    }
    const FirstPass first = read_poses(bag, info, o, cancel);
    return o.view == "map" ? render_map(bag, info, first, o, cancel)
                           : render_scan(bag, info, first, o, cancel);
  } catch (...) {
    rethrow_as_recording_error(o.input);
  }
}

}  // namespace dispel::io
