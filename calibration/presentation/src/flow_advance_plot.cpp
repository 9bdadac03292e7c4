// The report's flow-dependent advance figure: the advance each flow needs (with its 95 % band),
// every exported model's curve over it, the design flow marked; below it the measured tau(Q) and,
// when a viscosity model and nozzle geometry gave one, the rheology prediction with the gap.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "tunekit/calibration/presentation/plots.hpp"

namespace tunekit::calibration {
namespace {

std::vector<double> fap_column(const nlohmann::json& rows, const char* key) {
  std::vector<double> v;
  for (const auto& r : rows) v.push_back(r.contains(key) && r[key].is_number() ? r[key].get<double>() : std::nan(""));
  return v;
}

bool fap_all_finite(const std::vector<double>& v) {
  return !v.empty() && std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
}

}  // namespace

Figure flow_advance_figure(const nlohmann::json& fa) {
  Figure f;
  f.title = "Pressure advance against flow";
  f.share_x = true;
  f.height_px = 760;
  const auto& curve = fa.at("curve");
  const auto q = fap_column(curve, "flow_mm3_s");
  Panel p{
      "Advance the liquefier needs, V(Q)/Q, and what each export gives", "", "advance K (s)", false, false, {}, 1.6};
  p.series.push_back({"needed K(Q)", q, fap_column(curve, "K_need_s"), Series::Style::line, 1});
  const auto lo = fap_column(curve, "K_lo_s"), hi = fap_column(curve, "K_hi_s");
  if (fap_all_finite(lo) && fap_all_finite(hi)) {
    p.series.push_back({"95 % band", q, lo, Series::Style::dashed, 1});
    p.series.push_back({"", q, hi, Series::Style::dashed, 1});
  }
  const auto kk = fap_column(curve, "K_kalico_s");
  if (fap_all_finite(kk)) {
    const std::string model =
        fa.contains("kalico") ? fa["kalico"].value("pressure_advance_model", std::string("?")) : "?";
    p.series.push_back({fmt::format("Kalico {}", model), q, kk, Series::Style::line, 3});
  }
  double k_single = std::nan(""), qd = std::nan("");
  if (fa.contains("single") && fa["single"].contains("K_s") && fa["single"]["K_s"].is_number())
    k_single = fa["single"]["K_s"].get<double>();
  if (fa.contains("design_flow_mm3_s") && fa["design_flow_mm3_s"].is_number())
    qd = fa["design_flow_mm3_s"].get<double>();
  if (std::isfinite(k_single) && !q.empty())
    p.series.push_back(
        {"Klipper / Marlin / RRF single K", {q.front(), q.back()}, {k_single, k_single}, Series::Style::dashed, 4});
  if (fa.contains("orca") && fa["orca"].is_array() && !fa["orca"].empty())
    p.series.push_back({"OrcaSlicer table", fap_column(fa["orca"], "flow_mm3_s"), fap_column(fa["orca"], "K_s"),
                        Series::Style::points, 5});
  if (std::isfinite(qd) && std::isfinite(k_single)) {
    double top = k_single;
    for (double v : hi.empty() || !fap_all_finite(hi) ? fap_column(curve, "K_need_s") : hi) top = std::max(top, v);
    p.series.push_back(
        {fmt::format("design flow {:.3g} mm^3/s", qd), {qd, qd}, {0.0, top * 1.05}, Series::Style::dashed, 6});
  }
  Panel t{"Time constant against flow", "volumetric flow (mm^3/s)", "tau (s)", false, false, {}, 1.0};
  t.series.push_back({"identified tau(Q)", q, fap_column(curve, "tau_s"), Series::Style::line, 1});
  if (fa.contains("rheology") && fa["rheology"].is_object()) {
    const auto& r = fa["rheology"];
    std::vector<double> rq, rt;
    if (r.contains("flow_mm3_s") && r.contains("tau_pred_s")) {
      rq = r["flow_mm3_s"].get<std::vector<double>>();
      rt = r["tau_pred_s"].get<std::vector<double>>();
    }
    if (!rq.empty() && rq.size() == rt.size()) {
      const double gap =
          r.contains("max_gap_rel") && r["max_gap_rel"].is_number() ? r["max_gap_rel"].get<double>() : std::nan("");
      t.series.push_back({std::isfinite(gap) ? fmt::format("rheology prediction (gap up to {:.0f} %)", 100 * gap)
                                             : std::string("rheology prediction"),
                          rq, rt, Series::Style::dashed, 2});
    }
  }
  f.panels = {p, t};
  return f;
}

}  // namespace tunekit::calibration
