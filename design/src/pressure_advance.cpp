#include "tunekit/design/pressure_advance.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/interpolate.hpp"
#include "tunekit/design/flow_advance.hpp"

namespace tunekit::design {
namespace {

bool finite(double v) { return std::isfinite(v); }

nlohmann::json num(double v) { return finite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

}  // namespace

bool gain_is_dimensionless(const std::string& unit) {
  std::string u;
  for (char c : unit)
    if (c != ' ') u += c;
  if (u == "1") return true;
  // "A/(B)": the denominator is the last parenthesized group (A may hold slashes itself).
  if (u.size() > 3 && u.back() == ')') {
    const auto open = u.rfind("/(");
    if (open != std::string::npos && open > 0) return u.substr(0, open) == u.substr(open + 2, u.size() - open - 3);
  }
  const auto slash = u.find('/');
  return slash != std::string::npos && slash > 0 && u.substr(0, slash) == u.substr(slash + 1);
}

double kernel_peak_factor(SmoothingKernel kernel) { return kernel == SmoothingKernel::triangular ? 2.0 : 1.0; }

double min_smoothing_window_s(double k_s, double print_accel_mm_s2, double area_ratio,
                              double extruder_accel_limit_mm_s2, SmoothingKernel kernel) {
  if (!finite(k_s) || k_s < 0) throw InputError(fmt::format("advance K must be >= 0 s, not {}", k_s));
  if (!finite(print_accel_mm_s2) || print_accel_mm_s2 < 0)
    throw InputError(fmt::format("print acceleration must be >= 0 mm/s^2, not {}", print_accel_mm_s2));
  if (!finite(area_ratio) || area_ratio < 0)
    throw InputError(fmt::format("line/filament area ratio must be >= 0, not {}", area_ratio));
  if (!finite(extruder_accel_limit_mm_s2) || extruder_accel_limit_mm_s2 <= 0)
    throw InputError(fmt::format("extruder acceleration limit must be > 0 mm/s^2, not {}", extruder_accel_limit_mm_s2));
  return kernel_peak_factor(kernel) * k_s * print_accel_mm_s2 * area_ratio / extruder_accel_limit_mm_s2;
}

namespace {

/// The operating points with a feed and a tau, by feed; each positive, no two at one feed.
std::vector<LiquefierPoint> usable_points(const AdvanceInputs& in, AdvanceDesign& d) {
  std::vector<LiquefierPoint> pts;
  for (const auto& p : in.points)
    if (finite(p.feed_mm_s) && finite(p.tau_s)) pts.push_back(p);
  if (pts.size() != in.points.size())
    d.warnings.push_back(
        fmt::format("{} operating point(s) without feed rate or tau were left out", in.points.size() - pts.size()));
  std::sort(pts.begin(), pts.end(), [](const auto& a, const auto& b) { return a.feed_mm_s < b.feed_mm_s; });
  for (const auto& p : pts) {
    if (p.tau_s < 0 || p.feed_mm_s <= 0)
      throw InputError(
          fmt::format("operating point at {} mm/s has tau {} s: both must be positive", p.feed_mm_s, p.tau_s));
  }
  for (std::size_t i = 1; i < pts.size(); ++i)
    if (pts[i].feed_mm_s == pts[i - 1].feed_mm_s)
      throw InputError(fmt::format("two operating points at the same feed rate {} mm/s", pts[i].feed_mm_s));
  return pts;
}

/// Two or more operating points: the advance a flow needs is the stored volume over the flow,
/// V(Q)/Q with V the integral of tau over 0..Q (flow_advance.hpp derives it), not tau(Q) itself.
void design_from_points(const std::vector<LiquefierPoint>& pts, double af, AdvanceDesign& d) {
  FlowAdvanceInputs fin;
  fin.filament_area_mm2 = af;
  std::vector<double> q;
  for (const auto& p : pts) {
    q.push_back(p.feed_mm_s * af);
    fin.levels.push_back({p.feed_mm_s * af, p.tau_s});
  }
  for (const auto& p : pts)
    d.schedule.push_back({p.feed_mm_s * af, p.feed_mm_s, needed_advance_s(fin, p.feed_mm_s * af)});
  d.k_s = needed_advance_s(fin, d.design_flow_mm3_s);
  d.k_source = "operating points";
  d.notes.push_back(
      "K at each flow is the stored melt volume over the flow (the integral of tau over 0..Q, divided by "
      "Q; tau held at the lowest level below it), not tau at that flow");
  if (d.design_flow_mm3_s < q.front() || d.design_flow_mm3_s > q.back())
    d.outside_range_warning = fmt::format(
        "design flow {:.3g} mm^3/s lies outside the identified range {:.3g}-{:.3g} mm^3/s: tau is held at the "
        "nearest operating point there",
        d.design_flow_mm3_s, q.front(), q.back());
  if (!finite(d.theta_s)) {
    std::vector<double> th;
    for (const auto& p : pts) th.push_back(p.theta_s);
    if (std::all_of(th.begin(), th.end(), finite)) d.theta_s = fitting::interp_linear(q, th, d.design_flow_mm3_s);
  }
  if (!finite(d.gain)) {
    std::vector<double> g;
    for (const auto& p : pts) g.push_back(p.gain);
    if (std::all_of(g.begin(), g.end(), finite)) d.gain = fitting::interp_linear(q, g, d.design_flow_mm3_s);
  }
}

/// A rheology prediction of tau(Q)'s shape, scaled to the measured tau at its reference flow.
void design_from_rheology(const AdvanceInputs& in, double af, AdvanceDesign& d) {
  const auto& q = in.rheo_flow_mm3_s;
  const auto& rel = in.rheo_relative_tau;
  if (q.size() != rel.size() || q.size() < 2)
    throw InputError("rheology prediction needs at least two flows with one relative_tau each");
  for (std::size_t i = 0; i < q.size(); ++i) {
    if (!(q[i] > 0) || !(rel[i] > 0) || (i > 0 && !(q[i] > q[i - 1])))
      throw InputError("rheology prediction: flows must be positive and increasing, relative_tau positive");
  }
  // relative_tau is relative to the reference flow; the pooled tau is taken to be tau there.
  const double rel_ref =
      finite(in.rheo_reference_flow_mm3_s) ? fitting::interp_linear(q, rel, in.rheo_reference_flow_mm3_s) : 1.0;
  for (std::size_t i = 0; i < q.size(); ++i) d.schedule.push_back({q[i], q[i] / af, in.tau_s * rel[i] / rel_ref});
  d.k_s = in.tau_s * fitting::interp_linear(q, rel, d.design_flow_mm3_s) / rel_ref;
  d.k_source = "rheology";
  d.notes.push_back(
      fmt::format("flow dependence predicted from rheology, scaled so that K = tau = {:.4g} s at the "
                  "reference flow {:.3g} mm^3/s",
                  in.tau_s, finite(in.rheo_reference_flow_mm3_s) ? in.rheo_reference_flow_mm3_s : q.front()));
}

/// The schedule's straight-line trend K = k0 + k1 Q and how far the single K is from its worst entry.
void schedule_trend(AdvanceDesign& d) {
  if (d.schedule.size() < 2) return;
  double sq = 0, sk = 0, sqq = 0, sqk = 0;
  const double n = static_cast<double>(d.schedule.size());
  double worst = 0;
  for (const auto& s : d.schedule) {
    sq += s.flow_mm3_s;
    sk += s.k_s;
    sqq += s.flow_mm3_s * s.flow_mm3_s;
    sqk += s.flow_mm3_s * s.k_s;
    if (s.k_s > 0) worst = std::max(worst, std::abs(s.k_s - d.k_s) / s.k_s);
  }
  const double den = n * sqq - sq * sq;
  if (den > 0) {
    d.trend_k1_s_per_mm3_s = (n * sqk - sq * sk) / den;
    d.trend_k0_s = (sk - d.trend_k1_s_per_mm3_s * sq) / n;
  }
  d.single_k_max_rel_error = worst;
}

/// What the advance does not do: the dead time it cannot cancel, a gain that is a flow-rate matter.
void dead_time_and_gain_notes(const AdvanceInputs& in, AdvanceDesign& d) {
  if (finite(d.theta_s) && finite(in.print_speed_mm_s)) d.theta_track_mm = d.theta_s * in.print_speed_mm_s;
  if (finite(d.theta_s) && d.theta_s > 0)
    d.notes.push_back(
        fmt::format("dead time theta = {:.4g} s is not cancelled by advance: after every speed change "
                    "the flow is wrong for theta{}",
                    d.theta_s,
                    finite(d.theta_track_mm) ? fmt::format(", about {:.3g} mm of line at print speed", d.theta_track_mm)
                                             : std::string()));
  // Comparing the gain with 1 means something only when input and output share units (flow in,
  // flow out): a feed in mm/s against a force in N has no natural "1".
  if (finite(d.gain) && std::abs(d.gain - 1.0) > 0.05 && gain_is_dimensionless(in.gain_unit))
    d.warnings.push_back(
        fmt::format("steady-state gain {:.4g} differs from 1: the delivered flow is off by that "
                    "factor, a flow-rate (extrusion multiplier) matter, not part of K",
                    d.gain));
}

}  // namespace

AdvanceDesign design_advance(const AdvanceInputs& in) {
  AdvanceDesign d;
  const double af = in.filament_area_mm2, al = in.line_area_mm2;
  if (!(finite(af) && af > 0 && finite(al) && al > 0))
    throw InputError("the advance design needs positive filament and line cross-sections (mm^2)");
  d.area_ratio = al / af;
  d.gain = in.gain;
  d.theta_s = in.theta_s;
  if (finite(in.tau_s) && in.tau_s < 0)
    throw InputError(fmt::format("time constant tau must be >= 0 s, not {}", in.tau_s));

  d.design_flow_mm3_s = in.design_flow_mm3_s;
  if (!finite(d.design_flow_mm3_s)) {
    if (!(finite(in.print_speed_mm_s) && in.print_speed_mm_s > 0))
      throw InputError("the advance design needs a print speed (mm/s) or a design flow (mm^3/s)");
    d.design_flow_mm3_s = in.print_speed_mm_s * al;
  }
  if (!(d.design_flow_mm3_s > 0))
    throw InputError(fmt::format("design flow must be > 0 mm^3/s, not {}", d.design_flow_mm3_s));
  d.design_feed_mm_s = d.design_flow_mm3_s / af;

  // Flow-dependent advance, from measured operating points (preferred) or the rheology shape.
  const std::vector<LiquefierPoint> pts = usable_points(in, d);
  if (pts.size() >= 2) {
    design_from_points(pts, af, d);
  } else if (!in.rheo_flow_mm3_s.empty() && finite(in.tau_s)) {
    design_from_rheology(in, af, d);
  } else if (finite(in.tau_s)) {
    d.k_s = in.tau_s;
    d.k_stderr_s = in.tau_stderr_s;
    d.k_source = in.tau_source.empty() ? "pooled" : in.tau_source;
    if (pts.size() == 1) d.notes.push_back("only one operating point: no flow dependence can be derived");
  } else if (pts.size() == 1) {
    d.k_s = pts.front().tau_s;
    d.k_source = "operating point";
    d.schedule.push_back({pts.front().feed_mm_s * af, pts.front().feed_mm_s, pts.front().tau_s});
  } else {
    throw InputError("no liquefier time constant: give the results of 'tunekit step' or 'tunekit freq', or --pa-k");
  }
  if (!in.rheo_flow_mm3_s.empty() && pts.size() >= 2)
    d.notes.push_back("rheology prediction not used: the measured operating points take precedence");
  if (!in.rheo_flow_mm3_s.empty() && !finite(in.tau_s) && pts.size() < 2)
    d.warnings.push_back(
        "rheology prediction ignored: it gives only the shape of tau(Q) and needs a measured tau to scale it");

  schedule_trend(d);
  dead_time_and_gain_notes(in, d);

  const bool limits = finite(in.print_accel_mm_s2) && in.print_accel_mm_s2 > 0 &&
                      finite(in.extruder_accel_limit_mm_s2) && in.extruder_accel_limit_mm_s2 > 0;
  if (limits) {
    d.window_box_s = min_smoothing_window_s(d.k_s, in.print_accel_mm_s2, d.area_ratio, in.extruder_accel_limit_mm_s2,
                                            SmoothingKernel::box);
    d.window_triangular_s = min_smoothing_window_s(d.k_s, in.print_accel_mm_s2, d.area_ratio,
                                                   in.extruder_accel_limit_mm_s2, SmoothingKernel::triangular);
  } else {
    d.warnings.push_back("no print acceleration or extruder acceleration limit: smoothing time not designed");
  }
  return d;
}

nlohmann::json AdvanceDesign::to_json() const {
  nlohmann::json sched = nlohmann::json::array();
  for (const auto& s : schedule)
    sched.push_back({{"flow_mm3_s", num(s.flow_mm3_s)}, {"feed_mm_s", num(s.feed_mm_s)}, {"K_s", num(s.k_s)}});
  return {{"K_s", num(k_s)},
          {"K_stderr_s", num(k_stderr_s)},
          {"K_source", k_source},
          {"K_unit", "s (mm of filament per mm/s of filament speed = mm^3 per mm^3/s of flow)"},
          {"design_flow_mm3_s", num(design_flow_mm3_s)},
          {"design_feed_mm_s", num(design_feed_mm_s)},
          {"area_ratio", num(area_ratio)},
          {"smoothing_window_box_s", num(window_box_s)},
          {"smoothing_window_triangular_s", num(window_triangular_s)},
          {"theta_s", num(theta_s)},
          {"theta_track_mm", num(theta_track_mm)},
          {"gain", num(gain)},
          {"schedule", sched},
          {"trend", {{"k0_s", num(trend_k0_s)}, {"k1_s_per_mm3_s", num(trend_k1_s_per_mm3_s)}}},
          {"single_K_max_rel_error", num(single_k_max_rel_error)},
          {"notes", notes},
          {"warnings", warnings}};
}

}  // namespace tunekit::design
