#pragma once
/// @file
/// A Cairo drawing target written atomically, and the few drawing helpers the pictures share
/// (dispel render, dispel eval --plot). Used by render*.cpp; Cairo's types are only declared here.

#include <memory>
#include <string>

#include "dispel/io/atomic_file.hpp"
#include "dispel/render/render.hpp"

typedef struct _cairo cairo_t;                  // NOLINT: Cairo's own declaration.
typedef struct _cairo_surface cairo_surface_t;  // NOLINT

namespace dispel::render {

/// A PNG or SVG picture (chosen by @p path's extension) of a given size, white, drawn with Cairo
/// and written to "<path>.partial"; commit() finishes it and moves it into place. Without
/// commit() nothing is left behind. @throws jobs::JobError for another extension or an unwritable
/// path.
class Canvas {
 public:
  Canvas(const std::string& path, int width_px, int height_px);
  ~Canvas();
  Canvas(const Canvas&) = delete;
  Canvas& operator=(const Canvas&) = delete;

  cairo_t* cr() const { return cr_; }
  int width() const { return width_; }
  int height() const { return height_; }
  /// The base text size, pixels: readable on a laptop at the picture's size (20 at 1200 rows).
  double font_px() const { return font_px_; }

  /// Writes the picture. @throws jobs::JobError
  void commit();

 private:
  std::string path_;
  io::AtomicFile file_;
  bool svg_ = false;
  int width_ = 0, height_ = 0;
  double font_px_ = 20.0;
  cairo_surface_t* surface_ = nullptr;
  cairo_t* cr_ = nullptr;
};

void set_colour(cairo_t* cr, Rgb c, double alpha = 1.0);

enum class TextAlign { kLeft, kCentre, kRight };

/// Draws @p text with its baseline at @p y (sans-serif, Cairo's toy text API); returns its width.
double draw_text(cairo_t* cr, double x, double y, const std::string& text, double size_px,
                 TextAlign align = TextAlign::kLeft, bool bold = false, Rgb colour = {20, 20, 20});

/// Width of @p text at @p size_px.
double text_width(cairo_t* cr, const std::string& text, double size_px, bool bold = false);

/// The "nice" step (1, 2 or 5 times a power of ten) nearest below @p rough (> 0).
double nice_step(double rough);

/// A number with at most @p decimals decimals, trailing zeros dropped ("2", "0.5").
std::string format_number(double v, int decimals = 2);

/// The file name of a path (after the last '/').
std::string base_name(const std::string& path);

}  // namespace dispel::render
