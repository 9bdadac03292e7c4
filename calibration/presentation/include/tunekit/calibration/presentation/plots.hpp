#pragma once
// Figures for reports, drawn with PLplot's cairo drivers (SVG for the report, PNG on
// request). A Figure is a stack of panels sharing its width; each panel has lines or markers,
// optional logarithmic axes and a legend. The plot builders of the report (step, Bode, PSD, viscosity, line width) are
// thin functions that fill a Figure from results.

#include <string>
#include <vector>

#include "tunekit/calibration/results/plot_data.hpp"
#include "tunekit/design/flow_advance.hpp"

namespace tunekit::calibration {

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
  bool share_x = false;  ///< all panels use one x range (the union of their data), e.g. a time axis
  std::vector<Panel> panels;
};

/// Renders the figure to PATH: an SVG (PLplot's cairo SVG driver, text as outlines, so it
/// looks the same in every browser and stays sharp when zoomed) for ".svg", a PNG of exactly
/// width_px x height_px pixels for ".png". An SVG measures width_px x height_px points.
/// Logarithmic axes are labelled at every decade and, over at most three decades, at 2x and
/// 5x each decade. Throws InputError when the figure has no data, the extension is neither,
/// or the file cannot be written. Every plot of the reports uses this one style.
void render_figure(const Figure& figure, const std::string& path);
/// Where a logarithmic axis spanning 10^lo_exp .. 10^hi_exp is labelled (values, ascending):
/// every decade and, when the span is at most three decades, 2x and 5x each decade.
std::vector<double> log_axis_ticks(double lo_exp, double hi_exp);

/// The flow-dependent advance figure (flow_advance_plot.cpp): the need with its band, each
/// exported model, the design flow and (when given) the rheology prediction.
Figure flow_advance_figure(const FlowAdvancePlot& flow_advance);
/// The flow-dependent advance plot of a design (without a rheology prediction).
FlowAdvancePlot flow_advance_plot(const design::FlowAdvanceDesign& design);

/// render_figure for a ".png" path (InputError otherwise).
void render_png(const Figure& figure, const std::string& path);
/// render_figure for a ".svg" path (InputError otherwise).
void render_svg(const Figure& figure, const std::string& path);

}  // namespace tunekit::calibration
