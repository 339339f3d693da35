// dispel render --view scan: one scan in the sensor frame, its points coloured by the object the
// segmentation puts them in, masked sectors shaded, and the filter's tracks (the filter run over
// the scans up to it, as dispel filter runs it) with their velocity arrows and ids.
#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "dispel/core/segmentation.hpp"
#include "dispel/io/config_yaml.hpp"
#include "dispel/jobs/job.hpp"
#include "dispel/pipeline/scan_filter_runner.hpp"
#include "layout.hpp"

namespace dispel::render::detail {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

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

}  // namespace

RenderResult render_scan(const Scene& scene, const RenderOptions& o,
                         const std::atomic<bool>* cancel) {
  RenderResult result;
  DynamicFilterConfig base;
  if (o.config_path) base = jobs::as_job([&] { return io::load_filter_config(*o.config_path); });

  // Run the filter over the scans up to the one asked for, as dispel filter runs it.
  pipeline::ScanFilterRunner runner({base, o.scale_to_scanner, 0.0, o.static_sensor});
  FilterResult filtered;
  LaserScan scan;
  Pose2 sensor_pose;
  bool have_pose = false;
  double scan_t = 0.0;
  std::int64_t k = 0;
  jobs::as_job([&] {
    scene.recording->read({o.scan_topic}, [&](const io::RecordedMessage& m) {
      jobs::check_cancelled(cancel);
      const std::optional<io::ScanMessage> msg = m.scan();
      if (!msg) return;
      scan = msg->scan;
      const std::optional<Pose2> pose = scene.motion.sensor_pose(scan.stamp_s);
      const FilterResult& r = runner.process(scan, msg->scan_time, pose);
      if (k == o.scan_index) {
        filtered = r;
        have_pose = pose.has_value();
        if (pose) sensor_pose = *pose;
        scan_t = m.time().seconds() - scene.begin_s;
        throw io::StopReading{};
      }
      ++k;
    });
  });
  const DynamicFilterConfig& config = runner.config();
  if (k != o.scan_index) {
    throw jobs::JobError(o.input + ": scan index " + std::to_string(o.scan_index) +
                         " out of range: only " + std::to_string(k) + " scans on " + o.scan_topic);
  }
  if (const ScanIssue issue = check_scan(scan); issue != ScanIssue::kNone) {
    throw jobs::JobError(o.input + ": scan " + std::to_string(o.scan_index) +
                         " cannot be segmented (" + describe_scan_issue(scan, issue) + ")");
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

  Picture picture(o, lo, hi, result);
  Canvas& canvas = picture.canvas;
  cairo_t* cr = canvas.cr();
  const double f = canvas.font_px();
  const Layout& l = picture.layout;
  const PixelTransform& t = picture.transform;
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
  const std::string sub = "scan, sensor frame (x right, y up); " +
                          std::to_string(seg.objects.size()) + " objects (eps " +
                          format_number(config.segmentation.cluster_gap_m, 3) + " m, N_min " +
                          std::to_string(config.segmentation.min_points) + "), " +
                          std::to_string(result.tracks.size()) + " tracks (" + scene.description +
                          ")" + (have_pose ? "" : "; no pose for this scan, so no tracks");
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

}  // namespace dispel::render::detail
