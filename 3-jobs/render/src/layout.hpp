#pragma once
// Internal to dispel::render: what both views of a recording share: the frame they are drawn in
// (the laser's poses from the recording's first pass), the layout of the picture (a title band,
// the plot, a legend band), and the markers, bars and legends drawn on it.

#include <Eigen/Core>
#include <string>

#include "dispel/io/recording.hpp"
#include "dispel/io/recording_motion.hpp"
#include "dispel/render/canvas.hpp"
#include "dispel/render/render.hpp"

namespace dispel::render::detail {

/// The recording as both views see it: where its messages are, and the laser's poses.
struct Scene {
  io::RecordingReader* recording = nullptr;
  io::RecordingMotion motion;
  std::string pose_topic;   ///< Empty for a static sensor.
  std::string description;  ///< For the picture's subtitle.
  double begin_s = 0.0;     ///< The recording's first and last receive time.
  double end_s = 0.0;
};

std::string seconds_text(double s);

struct Layout {
  int plot_x = 0, plot_y = 0, plot_w = 0, plot_h = 0;
  double title_y = 0.0, subtitle_y = 0.0, legend_y = 0.0;
};

/// @throws jobs::JobError when the picture is too small to draw in.
Layout make_layout(const Canvas& canvas);

/// A picture begun: the canvas of @p o's output and size, its layout, and the transform that fits
/// the box [lo, hi] (metres) into the plot; @p result gets the size and the transform.
struct Picture {
  Picture(const RenderOptions& o, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi,
          RenderResult& result);
  Canvas canvas;
  Layout layout;
  PixelTransform transform;
};
/// Fits the box [lo, hi] (metres, padded by 4%) into the plot area with equal scales on x and y.
PixelTransform fit(const Layout& l, Eigen::Vector2d lo, Eigen::Vector2d hi);
void draw_frame(cairo_t* cr, const Layout& l);
/// A bar of a round number of metres in the plot's bottom-left corner, on a white box.
void draw_scale_bar(cairo_t* cr, const Layout& l, const PixelTransform& t, double f);
/// Legend entries left to right along the bottom band; each returns where the next one starts.
double legend_swatch(cairo_t* cr, double x, double y, double f, Rgb colour,
                     const std::string& text);
double legend_line(cairo_t* cr, double x, double y, double f, Rgb colour, const std::string& text);
void draw_sensor_marker(cairo_t* cr, const PixelTransform& t, const Pose2& pose, double f);

RenderResult render_map(const Scene& scene, const RenderOptions& o,
                        const std::atomic<bool>* cancel);
RenderResult render_scan(const Scene& scene, const RenderOptions& o,
                         const std::atomic<bool>* cancel);

}  // namespace dispel::render::detail
