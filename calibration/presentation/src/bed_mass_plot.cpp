#include "tunekit/calibration/presentation/bed_mass_plot.hpp"

#include <algorithm>

namespace tunekit::calibration {
namespace {
constexpr double kGramsPerKg = 1000;
constexpr int kCurvePoints = 200;
}  // namespace

Figure bed_mass_figure(const ident::BedMassFit& fit, const std::vector<ident::BedHeldOutCheck>& held_out,
                       const std::vector<double>& layer_mass_g) {
  double top_g = 0;
  for (const auto& p : fit.points) top_g = std::max(top_g, p.added_mass_kg * kGramsPerKg);
  for (const auto& h : held_out) top_g = std::max(top_g, h.point.added_mass_kg * kGramsPerKg);
  for (double m : layer_mass_g) top_g = std::max(top_g, m);
  Panel f{
      "Bed axis frequency against the mass on the bed", "mass on the bed (g)", "frequency (Hz)", false, false, {}, 1.4};
  Series mid{"f(m) = sqrt(k / (m0 + m)) / 2 pi", {}, {}, Series::Style::line, 1};
  Series lo{"95 % band", {}, {}, Series::Style::dashed, 1}, hi{"", {}, {}, Series::Style::dashed, 1};
  for (int i = 0; i <= kCurvePoints; ++i) {
    const double g = top_g * i / kCurvePoints;
    const auto p = fit.model.predict(g / kGramsPerKg);
    for (auto* s : {&mid, &lo, &hi}) s->x.push_back(g);
    mid.y.push_back(p.freq_hz), lo.y.push_back(p.ci95_lo_hz), hi.y.push_back(p.ci95_hi_hz);
  }
  Series fitted{"sweeps fitted", {}, {}, Series::Style::points, 2};
  for (const auto& p : fit.points) fitted.x.push_back(p.added_mass_kg * kGramsPerKg), fitted.y.push_back(p.freq_hz);
  f.series = {mid, lo, hi, fitted};
  if (!held_out.empty()) {
    Series held{"sweeps held out", {}, {}, Series::Style::points, 3};
    for (const auto& h : held_out)
      held.x.push_back(h.point.added_mass_kg * kGramsPerKg), held.y.push_back(h.point.freq_hz);
    f.series.push_back(held);
  }
  Figure fig;
  fig.title = "Bed slinger: the Y axis' resonance with the print's mass";
  fig.panels = {f};
  if (!layer_mass_g.empty()) {
    Panel m{"The print's mass over its layers", "layer", "mass on the bed (g)", false, false, {}, 1.0};
    Series mass{"mass when the layer starts", {}, layer_mass_g, Series::Style::line, 4};
    for (std::size_t i = 0; i < layer_mass_g.size(); ++i) mass.x.push_back(static_cast<double>(i));
    m.series = {mass};
    fig.panels.push_back(m);
    fig.height_px = 820;
  }
  return fig;
}

}  // namespace tunekit::calibration
