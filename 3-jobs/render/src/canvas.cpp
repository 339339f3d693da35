#include "dispel/render/canvas.hpp"

#include <cairo-svg.h>
#include <cairo.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>

#include "dispel/jobs/job.hpp"

namespace dispel::render {
namespace {

bool ends_with(const std::string& s, const std::string& suffix) {
  if (s.size() < suffix.size()) return false;
  for (std::size_t i = 0; i < suffix.size(); ++i) {
    const char c = s[s.size() - suffix.size() + i];
    if (std::tolower(static_cast<unsigned char>(c)) != suffix[i]) return false;
  }
  return true;
}

}  // namespace

Canvas::Canvas(const std::string& path, int width_px, int height_px)
    : path_(path), file_(path), width_(width_px), height_(height_px) {
  if (path.empty()) throw jobs::JobError("no output file given (-o OUT.png or OUT.svg)");
  if (ends_with(path, ".svg")) {
    svg_ = true;
  } else if (!ends_with(path, ".png")) {
    throw jobs::JobError(path + ": unknown picture format (the output must end in .png or .svg)");
  }
  if (svg_) {
    surface_ = cairo_svg_surface_create(file_.temp_path().c_str(), width_px, height_px);
  } else {
    surface_ = cairo_image_surface_create(CAIRO_FORMAT_RGB24, width_px, height_px);
  }
  if (cairo_surface_status(surface_) != CAIRO_STATUS_SUCCESS) {
    const std::string why = cairo_status_to_string(cairo_surface_status(surface_));
    cairo_surface_destroy(surface_);
    surface_ = nullptr;
    throw jobs::JobError(path + ": cannot write (" + why + ")");
  }
  cr_ = cairo_create(surface_);
  font_px_ = std::max(11.0, std::round(std::min(height_px, width_px * 3 / 4) / 60.0));
  set_colour(cr_, colours::kBackground);
  cairo_paint(cr_);
}

Canvas::~Canvas() {
  if (cr_ != nullptr) cairo_destroy(cr_);
  if (surface_ != nullptr) cairo_surface_destroy(surface_);
}

void Canvas::commit() {
  cairo_status_t status = cairo_status(cr_);
  if (status == CAIRO_STATUS_SUCCESS) {
    if (svg_) {
      cairo_surface_finish(surface_);
      status = cairo_surface_status(surface_);
    } else {
      cairo_surface_flush(surface_);
      status = cairo_surface_write_to_png(surface_, file_.temp_path().c_str());
    }
  }
  if (status != CAIRO_STATUS_SUCCESS) {
    throw jobs::JobError(path_ + ": cannot write (" + cairo_status_to_string(status) + ")");
  }
  try {
    file_.commit();
  } catch (const std::exception& e) {
    throw jobs::JobError(path_ + ": cannot write (" + e.what() + ")");
  }
}

void set_colour(cairo_t* cr, Rgb c, double alpha) {
  cairo_set_source_rgba(cr, c.r / 255.0, c.g / 255.0, c.b / 255.0, alpha);
}

namespace {
void select_font(cairo_t* cr, double size_px, bool bold) {
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                         bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size_px);
}
}  // namespace

double text_width(cairo_t* cr, const std::string& text, double size_px, bool bold) {
  select_font(cr, size_px, bold);
  cairo_text_extents_t e;
  cairo_text_extents(cr, text.c_str(), &e);
  return e.x_advance;
}

double draw_text(cairo_t* cr, double x, double y, const std::string& text, double size_px,
                 TextAlign align, bool bold, Rgb colour) {
  const double w = text_width(cr, text, size_px, bold);
  if (align == TextAlign::kCentre) x -= w / 2.0;
  if (align == TextAlign::kRight) x -= w;
  set_colour(cr, colour);
  cairo_move_to(cr, x, y);
  cairo_show_text(cr, text.c_str());
  cairo_new_path(cr);
  return w;
}

double nice_step(double rough) {
  if (!(rough > 0.0) || !std::isfinite(rough)) return 1.0;
  const double p = std::pow(10.0, std::floor(std::log10(rough)));
  for (const double m : {5.0, 2.0, 1.0}) {
    if (m * p <= rough) return m * p;
  }
  return p;
}

std::string format_number(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  std::string s = buf;
  if (s.find('.') != std::string::npos) {
    while (!s.empty() && s.back() == '0') s.pop_back();
    if (!s.empty() && s.back() == '.') s.pop_back();
  }
  if (s == "-0") s = "0";
  return s;
}

std::string base_name(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

}  // namespace dispel::render
