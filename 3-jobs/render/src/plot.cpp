// `dispel eval --plot`: the detection-latency histogram and the per-class rates as bars.
#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "dispel/io/text.hpp"
#include "dispel/jobs/job.hpp"
#include "dispel/render/canvas.hpp"
#include "dispel/render/render.hpp"

namespace dispel::render {
namespace {

struct Panel {
  double x, y, w, h;  // The axes' box, pixels.
};

void draw_axes(cairo_t* cr, const Panel& p) {
  set_colour(cr, {0, 0, 0});
  cairo_set_line_width(cr, 1.5);
  cairo_move_to(cr, p.x, p.y);
  cairo_line_to(cr, p.x, p.y + p.h);
  cairo_line_to(cr, p.x + p.w, p.y + p.h);
  cairo_stroke(cr);
}

void dashed_vertical(cairo_t* cr, double x, const Panel& p, Rgb c, double f) {
  set_colour(cr, c);
  cairo_set_line_width(cr, std::max(2.0, 0.12 * f));
  const double dash[] = {0.5 * f, 0.3 * f};
  cairo_set_dash(cr, dash, 2, 0.0);
  cairo_move_to(cr, x, p.y);
  cairo_line_to(cr, x, p.y + p.h);
  cairo_stroke(cr);
  cairo_set_dash(cr, nullptr, 0, 0.0);
}

void latency_histogram(cairo_t* cr, const Panel& p, const eval::Rates& r, double f) {
  draw_text(cr, p.x, p.y - 1.0 * f, "Detection latency (first seen moving \u2192 removed)", f,
            TextAlign::kLeft, true);
  draw_axes(cr, p);
  draw_text(cr, p.x + p.w / 2.0, p.y + p.h + 2.6 * f, "latency (s)", f, TextAlign::kCentre);
  cairo_save(cr);
  cairo_translate(cr, p.x - 2.6 * f, p.y + p.h / 2.0);
  cairo_rotate(cr, -kPi / 2.0);
  draw_text(cr, 0.0, 0.0, "actors", f, TextAlign::kCentre);
  cairo_restore(cr);
  const std::vector<double>& v = r.latencies_s;
  if (v.empty()) {
    draw_text(cr, p.x + p.w / 2.0, p.y + p.h / 2.0, "no moving actor was removed", f,
              TextAlign::kCentre, false, {120, 120, 120});
    return;
  }
  const double max_v = std::max(0.1, *std::max_element(v.begin(), v.end()));
  const double bin = std::max(0.05, nice_step(max_v / 20.0));
  const auto bins = static_cast<std::size_t>(std::floor(max_v / bin)) + 1;
  std::vector<std::int64_t> counts(bins, 0);
  for (const double x : v) {
    const auto b = static_cast<std::size_t>(std::floor(std::max(0.0, x) / bin));
    ++counts[std::min(b, bins - 1)];
  }
  const std::int64_t max_c = *std::max_element(counts.begin(), counts.end());
  const double x_max = static_cast<double>(bins) * bin;
  const double sx = p.w / x_max;
  const double y_top = static_cast<double>(max_c) * 1.1;
  const double sy = p.h / y_top;
  set_colour(cr, kPlotHistogram);
  for (std::size_t b = 0; b < bins; ++b) {
    const double h = static_cast<double>(counts[b]) * sy;
    cairo_rectangle(cr, p.x + static_cast<double>(b) * bin * sx + 1.0, p.y + p.h - h,
                    bin * sx - 2.0, h);
  }
  cairo_fill(cr);
  // Ticks.
  set_colour(cr, {0, 0, 0});
  cairo_set_line_width(cr, 1.0);
  const double xs = nice_step(x_max / 6.0);
  for (double x = 0.0; x <= x_max + 1e-9; x += xs) {
    cairo_move_to(cr, p.x + x * sx, p.y + p.h);
    cairo_line_to(cr, p.x + x * sx, p.y + p.h + 0.4 * f);
    draw_text(cr, p.x + x * sx, p.y + p.h + 1.4 * f, format_number(x, 2), 0.85 * f,
              TextAlign::kCentre);
  }
  const double ys = std::max(1.0, nice_step(y_top / 5.0));
  for (double y = 0.0; y <= y_top + 1e-9; y += ys) {
    cairo_move_to(cr, p.x - 0.4 * f, p.y + p.h - y * sy);
    cairo_line_to(cr, p.x, p.y + p.h - y * sy);
    draw_text(cr, p.x - 0.6 * f, p.y + p.h - y * sy + 0.3 * f, format_number(y, 0), 0.85 * f,
              TextAlign::kRight);
  }
  cairo_stroke(cr);
  const double median = r.latency_median_s(), p90 = r.latency_p90_s();
  dashed_vertical(cr, p.x + median * sx, p, {215, 38, 38}, f);
  dashed_vertical(cr, p.x + p90 * sx, p, {245, 145, 0}, f);
  draw_text(cr, p.x + p.w, p.y + 0.8 * f,
            "median " + format_number(median, 2) + " s (red), p90 " + format_number(p90, 2) +
                " s (orange)",
            0.85 * f, TextAlign::kRight);
  draw_text(cr, p.x + p.w, p.y + 2.0 * f,
            std::to_string(r.actors_removed) + " of " + std::to_string(r.actors_seen) +
                " moving actors removed",
            0.85 * f, TextAlign::kRight);
}

PlotLayout rate_bars(cairo_t* cr, Panel p, const eval::Rates& r, double f) {
  PlotLayout layout;
  layout.zero_v_px = p.y + p.h;
  const Panel axes = p;
  p.y += 0.08 * p.h;  // Rate 1 a little below the panel's top.
  p.h -= 0.08 * axes.h;
  layout.one_v_px = p.y;
  draw_text(cr, axes.x, axes.y - 1.0 * f, "Beam rates per ground-truth class", f, TextAlign::kLeft,
            true);
  draw_axes(cr, axes);
  set_colour(cr, {0, 0, 0});
  cairo_set_line_width(cr, 1.0);
  for (int k = 0; k <= 5; ++k) {
    const double y = p.y + p.h - p.h * k / 5.0;
    cairo_move_to(cr, p.x - 0.4 * f, y);
    cairo_line_to(cr, p.x, y);
    draw_text(cr, p.x - 0.6 * f, y + 0.3 * f, format_number(k / 5.0, 1), 0.85 * f,
              TextAlign::kRight);
  }
  cairo_stroke(cr);
  struct Item {
    const char* name;
    double rate;
    std::string detail;
    double target;  // NaN: none.
  };
  const double none = std::numeric_limits<double>::quiet_NaN();
  const Item items[] = {
      {"preservation", r.preservation_rate(),
       std::to_string(r.static_kept) + " of " + std::to_string(r.static_beams) + " static kept",
       0.99},
      {"rejection", r.rejection_rate(),
       std::to_string(r.moving_removed) + " of " + std::to_string(r.moving_beams) +
           " moving removed",
       0.90},
      {"still actors removed", r.still_removed_rate(),
       std::to_string(r.still_removed) + " of " + std::to_string(r.still_beams) + " still", none}};
  const double slot = p.w / 3.0;
  for (std::size_t i = 0; i < 3; ++i) {
    const Item& it = items[i];
    const double cx = p.x + (static_cast<double>(i) + 0.5) * slot;
    const double bw = 0.5 * slot;
    PlotLayout::Bar bar;
    bar.x = cx - bw / 2.0;
    bar.width = bw;
    bar.y = p.y + p.h;
    if (std::isfinite(it.rate)) {
      bar.height = std::clamp(it.rate, 0.0, 1.0) * p.h;
      bar.y -= bar.height;
      set_colour(cr, kPlotBar);
      cairo_rectangle(cr, bar.x, bar.y, bar.width, bar.height);
      cairo_fill(cr);
      // The value inside the bar's top (above it when the bar is too short for it).
      if (bar.height > 2.0 * f) {
        draw_text(cr, cx, bar.y + 1.4 * f, format_number(it.rate, 4), f, TextAlign::kCentre, true,
                  colours::kBackground);
      } else {
        draw_text(cr, cx, bar.y - 0.4 * f, format_number(it.rate, 4), f, TextAlign::kCentre, true);
      }
    } else {
      bar.width = 0.0;
      draw_text(cr, cx, p.y + p.h - 0.5 * f, "n/a", f, TextAlign::kCentre);
    }
    if (std::isfinite(it.target)) {
      const double y = p.y + p.h - it.target * p.h;
      set_colour(cr, {215, 38, 38});
      cairo_set_line_width(cr, 2.0);
      const double dash[] = {0.4 * f, 0.25 * f};
      cairo_set_dash(cr, dash, 2, 0.0);
      cairo_move_to(cr, cx - 0.6 * slot / 2.0 - 0.3 * f, y);
      cairo_line_to(cr, cx + 0.6 * slot / 2.0 + 0.3 * f, y);
      cairo_stroke(cr);
      cairo_set_dash(cr, nullptr, 0, 0.0);
    }
    draw_text(cr, cx, p.y + p.h + 1.4 * f, it.name, 0.9 * f, TextAlign::kCentre);
    draw_text(cr, cx, p.y + p.h + 2.6 * f, it.detail, 0.75 * f, TextAlign::kCentre, false,
              {80, 80, 80});
    layout.bars.push_back(bar);
  }
  draw_text(cr, p.x + p.w, p.y + p.h + 3.9 * f, "red dashes: targets (0.99, 0.90)", 0.75 * f,
            TextAlign::kRight, false, {80, 80, 80});
  return layout;
}

}  // namespace

PlotLayout plot_evaluation(const eval::Rates& rates, const std::string& title,
                           const std::string& output, int width_px, int height_px) {
  if (width_px < 200 || height_px < 200 || width_px > 10000 || height_px > 10000) {
    throw jobs::JobError("picture size " + std::to_string(width_px) + "x" +
                         std::to_string(height_px) +
                         " out of range (200 to 10000 pixels each way)");
  }
  Canvas canvas(output, width_px, height_px);
  cairo_t* cr = canvas.cr();
  const double f = canvas.font_px();
  draw_text(cr, f, 1.6 * f, title, 1.4 * f, TextAlign::kLeft, true);
  draw_text(cr, f, 2.8 * f,
            std::to_string(rates.scans) + " scans; F1 " + format_number(rates.f1(), 4), 0.9 * f,
            TextAlign::kLeft, false, {80, 80, 80});
  const double top = 6.0 * f, bottom = canvas.height() - 5.0 * f;
  const double half = canvas.width() / 2.0;
  latency_histogram(cr, {4.5 * f, top, half - 6.5 * f, bottom - top}, rates, f);
  const PlotLayout layout =
      rate_bars(cr, {half + 3.5 * f, top, half - 5.0 * f, bottom - top}, rates, f);
  canvas.commit();
  return layout;
}

std::pair<int, int> parse_image_size(const std::string& text) {
  const auto x = text.find_first_of("xX");
  const auto bad = [&text]() {
    return jobs::JobError(
        "picture size " + io::quote(text) +
        " is not WIDTHxHEIGHT in pixels, each from 200 to 10000 (e.g. 1600x1200)");
  };
  if (x == std::string::npos) throw bad();
  const std::string w = text.substr(0, x), h = text.substr(x + 1);
  const auto parse = [&bad](const std::string& s) {
    if (s.empty() || s.size() > 6 || s.find_first_not_of("0123456789") != std::string::npos) {
      throw bad();
    }
    const long v = std::strtol(s.c_str(), nullptr, 10);
    if (v < 200 || v > 10000) throw bad();
    return static_cast<int>(v);
  };
  return {parse(w), parse(h)};
}

}  // namespace dispel::render
