// The report's flow-dependent advance figure: the advance each flow needs (with its 95 % band),
// every exported model's curve over it, the design flow marked; below it the measured tau(Q) and,
// when a viscosity model and nozzle geometry gave one, the rheology prediction with the gap.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "tunekit/calibration/presentation/plots.hpp"

namespace tunekit::calibration {
namespace {

bool fap_all_finite(const std::vector<double>& v) {
  return !v.empty() && std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
}

}  // namespace

FlowAdvancePlot flow_advance_plot(const design::FlowAdvanceDesign& design) {
  FlowAdvancePlot p;
  for (const auto& s : design.curve) {
    p.flow_mm3_s.push_back(s.flow_mm3_s);
    p.tau_s.push_back(s.tau_s);
    p.k_need_s.push_back(s.k_need_s);
    p.k_lo_s.push_back(s.k_lo_s);
    p.k_hi_s.push_back(s.k_hi_s);
    p.k_kalico_s.push_back(s.k_kalico_s);
  }
  p.kalico_model = design::to_string(design.kalico.model);
  p.k_single_s = design.k_design_s;
  p.design_flow_mm3_s = design.design_flow_mm3_s;
  for (const auto& o : design.orca) {
    p.orca_flow_mm3_s.push_back(o.flow_mm3_s);
    p.orca_k_s.push_back(o.k_s);
  }
  return p;
}

Figure flow_advance_figure(const FlowAdvancePlot& fa) {
  Figure f;
  f.title = "Pressure advance against flow";
  f.share_x = true;
  f.height_px = 760;
  const auto& q = fa.flow_mm3_s;
  Panel p{
      "Advance the liquefier needs, V(Q)/Q, and what each export gives", "", "advance K (s)", false, false, {}, 1.6};
  p.series.push_back({"needed K(Q)", q, fa.k_need_s, Series::Style::line, 1});
  const auto &lo = fa.k_lo_s, &hi = fa.k_hi_s;
  if (fap_all_finite(lo) && fap_all_finite(hi)) {
    p.series.push_back({"95 % band", q, lo, Series::Style::dashed, 1});
    p.series.push_back({"", q, hi, Series::Style::dashed, 1});
  }
  if (fap_all_finite(fa.k_kalico_s))
    p.series.push_back({fmt::format("Kalico {}", fa.kalico_model.empty() ? "?" : fa.kalico_model), q, fa.k_kalico_s,
                        Series::Style::line, 3});
  const double k_single = fa.k_single_s, qd = fa.design_flow_mm3_s;
  if (std::isfinite(k_single) && !q.empty())
    p.series.push_back(
        {"Klipper / Marlin / RRF single K", {q.front(), q.back()}, {k_single, k_single}, Series::Style::dashed, 4});
  if (!fa.orca_flow_mm3_s.empty())
    p.series.push_back({"OrcaSlicer table", fa.orca_flow_mm3_s, fa.orca_k_s, Series::Style::points, 5});
  if (std::isfinite(qd) && std::isfinite(k_single)) {
    double top = k_single;
    for (double v : hi.empty() || !fap_all_finite(hi) ? fa.k_need_s : hi) top = std::max(top, v);
    p.series.push_back(
        {fmt::format("design flow {:.3g} mm^3/s", qd), {qd, qd}, {0.0, top * 1.05}, Series::Style::dashed, 6});
  }
  Panel t{"Time constant against flow", "volumetric flow (mm^3/s)", "tau (s)", false, false, {}, 1.0};
  t.series.push_back({"identified tau(Q)", q, fa.tau_s, Series::Style::line, 1});
  if (const auto& r = fa.rheology; r && !r->flow_mm3_s.empty() && r->flow_mm3_s.size() == r->tau_pred_s.size()) {
    const double gap = r->max_gap_rel;
    t.series.push_back({std::isfinite(gap) ? fmt::format("rheology prediction (gap up to {:.0f} %)", 100 * gap)
                                           : std::string("rheology prediction"),
                        r->flow_mm3_s, r->tau_pred_s, Series::Style::dashed, 2});
  }
  f.panels = {p, t};
  return f;
}

}  // namespace tunekit::calibration
