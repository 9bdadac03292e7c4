#pragma once
// Figures for reports, drawn with PLplot's cairo PNG driver. A Figure is a stack of panels
// sharing its width; each panel has lines or markers, optional logarithmic axes and a
// legend. The plot builders of the report (step, Bode, PSD, viscosity, line width) are
// thin functions that fill a Figure from results.

#include <string>
#include <vector>

namespace tunekit::cli {

struct Series {
  enum class Style { line, dashed, points };
  std::string label;  ///< empty: not in the legend
  std::vector<double> x, y;
  Style style = Style::line;
  int color = 1;  ///< index into the report palette (1..8)
};

struct Panel {
  std::string title, xlabel, ylabel;
  bool log_x = false, log_y = false;
  std::vector<Series> series;
  double height_weight = 1.0;  ///< relative height among the figure's panels
};

struct Figure {
  std::string title;
  int width_px = 960;
  int height_px = 640;
  std::vector<Panel> panels;
};

/// Renders the figure to a PNG file of exactly width_px x height_px pixels. Throws
/// InputError when the figure has no data or the file cannot be written.
void render_png(const Figure& figure, const std::string& path);

}  // namespace tunekit::cli
