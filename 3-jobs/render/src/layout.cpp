#include "layout.hpp"

#include <cairo.h>

#include <algorithm>
#include <cmath>

#include "dispel/jobs/job.hpp"

namespace dispel::render {

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

namespace detail {

std::string seconds_text(double s) { return format_number(s, 1) + " s"; }

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
  if (l.plot_w < 10 || l.plot_h < 10) throw jobs::JobError("the picture is too small to draw in");
  return l;
}

Picture::Picture(const RenderOptions& o, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi,
                 RenderResult& result)
    : canvas(o.output, o.width_px, o.height_px),
      layout(make_layout(canvas)),
      transform(fit(layout, lo, hi)) {
  result.transform = transform;
  result.width_px = canvas.width();
  result.height_px = canvas.height();
}

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

}  // namespace detail
}  // namespace dispel::render
