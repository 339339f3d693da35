#pragma once
// `dispel render`: a thin shell around dispel::render::render_bag.

#include <string>

#include "dispel/render/render.hpp"

namespace dispel::apps {

struct RenderCommandOptions {
  render::RenderOptions job;
  std::string size;  ///< WIDTHxHEIGHT; empty: the default 1600x1200.
};

/// Renders the picture and prints a summary on stdout. Returns the exit code: 0 done, 1 error,
/// 130 interrupted.
int run_render(RenderCommandOptions options);

}  // namespace dispel::apps
