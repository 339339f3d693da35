// dispel render --view map: every scan's points accumulated in the fixed frame, streamed into a
// fixed-size raster of counts per pixel and class, with the robot's path.
#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>

#include "dispel/core/offline_cleaner.hpp"
#include "dispel/jobs/job.hpp"
#include "layout.hpp"

namespace dispel::render::detail {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

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

// Calls @p fn(scan, sensor pose) for every scan of @p topic in the window that has a pose;
// counts the scans in the window with and without one.
template <typename Fn>
void for_each_scan_in_window(const Scene& scene, const std::string& topic, double from_s,
                             double to_s, const std::atomic<bool>* cancel, std::int64_t& in_window,
                             std::int64_t& without_pose, Fn&& fn) {
  in_window = 0;
  without_pose = 0;
  jobs::as_job([&] {
    scene.recording->read({topic}, [&](const io::RecordedMessage& m) {
      jobs::check_cancelled(cancel);
      const double t = m.time().seconds() - scene.begin_s;
      if (t < from_s || t > to_s) return;
      const std::optional<io::ScanMessage> msg = m.scan();
      if (!msg) return;
      ++in_window;
      const std::optional<Pose2> pose = scene.motion.sensor_pose(msg->scan.stamp_s);
      if (!pose) {
        ++without_pose;
        return;
      }
      fn(msg->scan, *pose);
    });
  });
}

// The valid points of a scan in the frame given by @p pose; @p fn(point, beam).
template <typename Fn>
void for_each_point(const LaserScan& scan, const Pose2& pose, Fn&& fn) {
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const float r = scan.ranges_m[i];
    if (!scan.is_valid(i) || !std::isfinite(r)) continue;
    const double b = scan.bearing_rad(i);
    fn(pose.apply({r * std::cos(b), r * std::sin(b)}), i);
  }
}

// A point's class by its label: dispel filter's (1 dynamic, 2 unknown) or dispel clean's, which
// adds three removed ones (5 moved at another time, 6 place seen through, 8 walked leg in no
// object); every other label is kept.
enum PointClass : int {
  kKeptClass = 0,
  kDynamicClass = 1,
  kUnknownClass = 2,
  kMovedLaterClass = 3,
  kVacatedClass = 4,
  kWalkedLegClass = 5,
  kClassCount = 6
};

PointClass point_class(float value) {
  const std::optional<CleanLabel> label = clean_label(value);
  if (!label) return kKeptClass;
  switch (*label) {  // Every label named, so that a new one is a compiler warning here.
    case CleanLabel::kDynamic:
      return kDynamicClass;
    case CleanLabel::kUnknown:
      return kUnknownClass;
    case CleanLabel::kMovedLater:
      return kMovedLaterClass;
    case CleanLabel::kVacated:
      return kVacatedClass;
    case CleanLabel::kWalkedLeg:
      return kWalkedLegClass;
    case CleanLabel::kStatic:
    case CleanLabel::kNoObject:
    case CleanLabel::kInvalid:
    case CleanLabel::kRestored:
      return kKeptClass;
  }
  return kKeptClass;
}

constexpr Rgb kRemovedColours[kClassCount] = {colours::kKept,    colours::kDynamic,
                                              colours::kUnknown, colours::kMovedLater,
                                              colours::kVacated, colours::kWalkedLeg};

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
      : w_(w),
        h_(h),
        counts_(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * kClassCount, 0) {}

  void add(int col, int row, PointClass c) {
    if (col < 0 || row < 0 || col >= w_ || row >= h_) return;
    std::uint32_t& n = counts_[index(col, row) * kClassCount + static_cast<std::size_t>(c)];
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
        const std::uint32_t* n = &counts_[index(col, row) * kClassCount];
        std::uint64_t removed_here = 0;
        int most = kDynamicClass;
        for (int c = kDynamicClass; c < kClassCount; ++c) {
          removed_here += n[c];
          if (n[c] > n[most]) most = c;
        }
        if (n[kKeptClass] == 0 && removed_here == 0) continue;
        if (removed_here >= n[kKeptClass]) {
          px(col, row) = pixel_value(kRemovedColours[most]);
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

}  // namespace

RenderResult render_map(const Scene& scene, const RenderOptions& o,
                        const std::atomic<bool>* cancel) {
  RenderResult result;
  const std::string labels_topic = o.scan_topic + "_labels";
  result.labelled = scene.recording->topics().has(labels_topic, io::MessageKind::kLaserScan);
  // A labels message holds the original ranges, the labels in its intensities.
  const std::string topic = result.labelled ? labels_topic : o.scan_topic;
  const double span = scene.end_s - scene.begin_s;
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
      scene, topic, from_s, to_s, cancel, in_window, result.scans_without_pose,
      [&](const LaserScan& scan, const Pose2& pose) {
        const double stamp = scan.stamp_s;
        if (stamp < first_stamp) first_stamp = stamp;
        if (stamp > last_stamp) last_stamp = stamp;
        path_lo = path_lo.cwiseMin(pose.translation());
        path_hi = path_hi.cwiseMax(pose.translation());
        for_each_point(scan, pose, [&](const Eigen::Vector2d& p, std::size_t) { bounds.add(p); });
        ++result.scans_drawn;
      });
  if (in_window == 0) {
    throw jobs::JobError(o.input + ": no scans on " + topic + " " + window +
                         " from the start (the recording spans 0 to " + seconds_text(span) + ")");
  }
  if (result.scans_drawn == 0) {
    throw jobs::JobError(o.input + ": none of the " + std::to_string(in_window) + " scans " +
                         window + " has a pose from " + scene.pose_topic);
  }
  first_t = o.from_s ? std::max(*o.from_s, 0.0) : 0.0;
  last_t = o.to_s ? std::min(*o.to_s, span) : span;
  // The robot's path between the first and the last scan drawn.
  std::vector<Pose2> path;
  if (!scene.motion.static_sensor) {
    for (const TimedPose& p : scene.motion.base_poses.poses()) {
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

  Picture picture(o, lo, hi, result);
  Canvas& canvas = picture.canvas;
  cairo_t* cr = canvas.cr();
  const double f = canvas.font_px();
  const Layout& l = picture.layout;
  const PixelTransform& t = picture.transform;
  result.from_s = first_t;
  result.to_s = last_t;

  // Third pass: the points into the raster.
  PointRaster raster(l.plot_w, l.plot_h);
  std::int64_t unused_in = 0, unused_without = 0;
  for_each_scan_in_window(
      scene, topic, from_s, to_s, cancel, unused_in, unused_without,
      [&](const LaserScan& scan, const Pose2& pose) {
        const bool has_labels = result.labelled && scan.intensities.size() == scan.size();
        for_each_point(scan, pose, [&](const Eigen::Vector2d& p, std::size_t i) {
          const PointClass c = has_labels ? point_class(scan.intensities[i]) : kKeptClass;
          std::int64_t* counts[kClassCount] = {&result.points_kept,    &result.points_dynamic,
                                               &result.points_unknown, &result.points_moved_later,
                                               &result.points_vacated, &result.points_walked_legs};
          ++*counts[c];
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
  if (scene.motion.static_sensor) {
    draw_sensor_marker(cr, t, Pose2{}, f);
  } else if (!path.empty()) {
    draw_sensor_marker(cr, t, path.back() * scene.motion.mount, f);
  }
  draw_scale_bar(cr, l, t, f);

  // Title, subtitle, legend.
  draw_text(cr, l.plot_x, l.title_y,
            base_name(o.input) + " \u2014 " + seconds_text(first_t) + " to " +
                seconds_text(last_t) + " of " + seconds_text(span),
            1.4 * f, TextAlign::kLeft, true);
  std::string sub = "map, frame: " + scene.description + "; " + std::to_string(result.scans_drawn) +
                    " scans on " + topic;
  if (result.scans_without_pose > 0) {
    sub += " (" + std::to_string(result.scans_without_pose) + " without a pose left out)";
  }
  draw_text(cr, l.plot_x, l.subtitle_y, sub, 0.9 * f, TextAlign::kLeft, false, {80, 80, 80});
  double x = l.plot_x;
  // dispel clean's labels take three more swatches: the legend's texts are shorter then.
  const bool cleaned = result.points_removed_offline() > 0;
  if (result.labelled && !cleaned) {
    x = legend_swatch(cr, x, l.legend_y, f, colours::kKept, "kept");
    x = legend_swatch(cr, x, l.legend_y, f, colours::kDynamic, "removed: dynamic (label 1)");
    x = legend_swatch(cr, x, l.legend_y, f, colours::kUnknown, "removed: unknown (label 2)");
  } else if (cleaned) {
    x = legend_swatch(cr, x, l.legend_y, f, colours::kKept, "kept");
    x = legend_swatch(cr, x, l.legend_y, f, colours::kDynamic, "removed: dynamic (1)");
    x = legend_swatch(cr, x, l.legend_y, f, colours::kUnknown, "unknown (2)");
    x = legend_swatch(cr, x, l.legend_y, f, colours::kMovedLater, "moved elsewhen (5)");
    x = legend_swatch(cr, x, l.legend_y, f, colours::kVacated, "seen through (6)");
    x = legend_swatch(cr, x, l.legend_y, f, colours::kWalkedLeg, "walked leg (8)");
  } else {
    x = legend_swatch(cr, x, l.legend_y, f, colours::kKept,
                      "points (not filtered: no " + labels_topic + ")");
  }
  if (!path.empty()) x = legend_line(cr, x, l.legend_y, f, colours::kTrajectory, "robot path");
  const std::int64_t removed =
      result.points_dynamic + result.points_unknown + result.points_removed_offline();
  draw_text(cr, canvas.width() - l.plot_x, l.legend_y,
            std::string(cleaned ? "" : "grey \u2192 black: hit more often; ") +
                std::to_string(removed) + " of " + std::to_string(removed + result.points_kept) +
                " points removed",
            0.9 * f, TextAlign::kRight, false, {80, 80, 80});
  (void)x;
  canvas.commit();
  return result;
}

}  // namespace dispel::render::detail
