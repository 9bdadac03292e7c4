#include "tunekit/design/flow_advance.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/interpolate.hpp"
#include "tunekit/fitting/stats.hpp"

namespace tunekit::design {
namespace {

bool fa_finite(double v) { return std::isfinite(v); }

nlohmann::json fa_num(double v) { return fa_finite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

/// A power-law trend tau = a Q^b stores a finite volume a Q^(b+1)/(b+1) from zero flow only for
/// a > 0 and b > -1; otherwise the levels' own table is designed from.
bool fa_trend_usable(const FlowAdvanceInputs& in) {
  return in.trend && fa_finite(in.trend->a) && in.trend->a > 0 && fa_finite(in.trend->b) && in.trend->b > -1;
}

/// The levels sorted by flow, with the bound `which` selected (-1 lower, 0 estimate, +1 upper).
struct FaKnots {
  std::vector<double> q, t;
};

FaKnots fa_knots(const FlowAdvanceInputs& in, int which) {
  std::vector<FlowTau> lv = in.levels;
  std::sort(lv.begin(), lv.end(), [](const FlowTau& a, const FlowTau& b) { return a.flow_mm3_s < b.flow_mm3_s; });
  FaKnots k;
  for (const auto& l : lv) {
    double t = l.tau_s;
    if (which < 0 && fa_finite(l.tau_lo_s)) t = l.tau_lo_s;
    if (which > 0 && fa_finite(l.tau_hi_s)) t = l.tau_hi_s;
    k.q.push_back(l.flow_mm3_s);
    k.t.push_back(std::max(0.0, t));
  }
  return k;
}

/// tau of the piecewise-linear table (held outside the levels).
double fa_table_tau(const FaKnots& k, double q) { return fitting::interp_linear(k.q, k.t, q); }

/// Exact integral of the piecewise-linear table from 0 to Q.
double fa_table_volume(const FaKnots& k, double Q) {
  if (Q <= 0) return 0;
  double v = k.t.front() * std::min(Q, k.q.front());
  for (std::size_t i = 1; i < k.q.size() && Q > k.q[i - 1]; ++i) {
    const double hi = std::min(Q, k.q[i]);
    v += 0.5 * (k.t[i - 1] + fa_table_tau(k, hi)) * (hi - k.q[i - 1]);
  }
  if (Q > k.q.back()) v += k.t.back() * (Q - k.q.back());
  return v;
}

/// The volume a power-law trend stores from zero flow up to q. No level measured tau below the
/// lowest identified flow q0, so that part is bounded: tau held at its value at q0 (the melt turns
/// Newtonian right below the data) and the power law followed down to zero flow (the melt keeps
/// thinning). A shear-thinning melt whose viscosity lies below its power-law asymptote, as the
/// Cross and Carreau models' do (Bird, Armstrong and Hassager, Dynamics of polymeric liquids,
/// 1987), stores a volume between the two, and where between is not measured: ABS's Cross
/// transition at 230 degC, tau* / eta0 = 23 1/s (Holtrup, Tuning liquefier dynamics, 2019, Table
/// 2.4), lies within a factor 4 of a 0.4 mm nozzle's wall shear rate at the lowest flows a
/// liquefier test holds (4 Q / (pi R^3) = 80 1/s at 0.5 mm^3/s). The estimate is the middle of the
/// two, the value whose largest error over that range is smallest (the power law's end read the
/// simulated desktop printer's advance 16 % high on the median camera run, 135 % at worst).
/// `which` -1 takes the smaller bound, +1 the larger, 0 their middle.
double fa_trend_volume(const TauPowerLaw& t, double q0, double q, int which) {
  const double below = std::min(q, q0);
  const double held = t.a * std::pow(q0, t.b) * below;
  const double power = t.a * std::pow(below, t.b + 1) / (t.b + 1);
  const double low = which < 0 ? std::min(held, power) : which > 0 ? std::max(held, power) : 0.5 * (held + power);
  const double above = q > q0 ? t.a * (std::pow(q, t.b + 1) - std::pow(q0, t.b + 1)) / (t.b + 1) : 0.0;
  return low + above;
}

/// The volume below the data is known: measured at one flow (low_volume) or read by the sensor at
/// every level (volume_measured).
bool fa_volume_known(const FlowAdvanceInputs& in) {
  return fa_trend_usable(in) && (in.low_volume || in.volume_measured);
}

/// The 95 % half-width of the trend's volume between flows q0 and q1 (q0 = 0: from zero flow).
/// Delta method with the trend's covariance: V(q) = tau_ref q_ref^-b q^(b+1) / (b+1) has
/// dV/d ln tau_ref = V and dV/db = V (ln(q / q_ref) - 1 / (b+1)). Without a covariance, the given
/// widest relative half-width of the trend (of tau, or of V from zero flow) times the volume.
double fa_trend_volume_half_width(const FlowAdvanceInputs& in, double q0, double q1, double rel_fallback) {
  const TauPowerLaw& t = *in.trend;
  const double e = t.b + 1;
  auto volume = [&](double q) { return q > 0 ? t.a * std::pow(q, e) / e : 0.0; };
  const double dv = volume(q1) - volume(q0);
  const auto& c = in.trend_covariance;
  if (!c || !(c->reference_flow_mm3_s > 0) || !fa_finite(c->var_ln_tau_ref)) return rel_fallback * dv;
  auto dvdb = [&](double q) { return q > 0 ? volume(q) * (std::log(q / c->reference_flow_mm3_s) - 1 / e) : 0.0; };
  const double gb = dvdb(q1) - dvdb(q0);
  const double cov = fa_finite(c->cov_ln_tau_ref_b) ? c->cov_ln_tau_ref_b : 0.0;
  const double vb = fa_finite(c->var_b) ? c->var_b : 0.0;
  return fitting::kZ95 * std::sqrt(std::max(dv * dv * c->var_ln_tau_ref + 2 * dv * gb * cov + gb * gb * vb, 0.0));
}

/// V(q) of a trend whose volume below the data is known; `which` -1 / +1 its 95 % bounds. With a
/// measured low volume: that volume plus the trend's integral from its flow (below its flow, the
/// trend's shape scaled through it); the bounds add the two half-widths in quadrature.
double fa_known_volume(const FlowAdvanceInputs& in, double q, int which) {
  const TauPowerLaw& t = *in.trend;
  const double e = t.b + 1;
  if (!in.low_volume) {
    const double hw = which == 0 ? 0.0 : fa_trend_volume_half_width(in, 0.0, q, in.volume_rel_half_width);
    return t.a * std::pow(q, e) / e + which * hw;
  }
  const MeasuredVolume& lv = *in.low_volume;
  if (q < lv.flow_mm3_s) {
    const double scale = std::pow(q / lv.flow_mm3_s, e);
    return scale * (lv.volume_mm3 + which * lv.half_width_mm3);
  }
  const double above = t.a * (std::pow(q, e) - std::pow(lv.flow_mm3_s, e)) / e;
  const double hw = which == 0 ? 0.0
                               : std::hypot(lv.half_width_mm3,
                                            fa_trend_volume_half_width(in, lv.flow_mm3_s, q, in.trend_rel_half_width));
  return lv.volume_mm3 + above + which * hw;
}

double fa_kalico_shape(KalicoModel m, double x) {
  return m == KalicoModel::tanh ? std::tanh(x) : 1.0 - 1.0 / (1.0 + x);
}

/// Relative-error fit of offset = la v + off f(v/lv) for a fixed lv; returns {la, off, max rel, rms rel}.
struct FaTrial {
  double la = 0, off = 0, max_rel = std::numeric_limits<double>::infinity(), rms_rel = 0;
};

FaTrial fa_fit_fixed(KalicoModel m, double lv, const std::vector<double>& v, const std::vector<double>& y) {
  // Minimize sum ((la v + off g - y) / y)^2: weighted least squares in (la, off).
  double s11 = 0, s12 = 0, s22 = 0, r1 = 0, r2 = 0;
  for (std::size_t i = 0; i < v.size(); ++i) {
    const double w = 1.0 / (y[i] * y[i]);
    const double g1 = v[i], g2 = fa_kalico_shape(m, v[i] / lv);
    s11 += w * g1 * g1;
    s12 += w * g1 * g2;
    s22 += w * g2 * g2;
    r1 += w * g1 * y[i];
    r2 += w * g2 * y[i];
  }
  FaTrial t;
  const double det = s11 * s22 - s12 * s12;
  if (det > 1e-12 * s11 * s22) {
    t.la = (r1 * s22 - r2 * s12) / det;
    t.off = (s11 * r2 - s12 * r1) / det;
  }
  // Kalico refuses negative values (extruder.py: minval=0.): fit the one-term models instead.
  if (!(det > 1e-12 * s11 * s22) || t.la < 0 || t.off < 0) {
    const FaTrial a{r1 / s11, 0.0};
    const FaTrial b{0.0, r2 / s22};
    auto cost = [&](const FaTrial& c) {
      double e = 0;
      for (std::size_t i = 0; i < v.size(); ++i) {
        const double r = (c.la * v[i] + c.off * fa_kalico_shape(m, v[i] / lv) - y[i]) / y[i];
        e += r * r;
      }
      return e;
    };
    t = cost(a) <= cost(b) ? a : b;
  }
  double mx = 0, ss = 0;
  for (std::size_t i = 0; i < v.size(); ++i) {
    const double r = std::abs(t.la * v[i] + t.off * fa_kalico_shape(m, v[i] / lv) - y[i]) / y[i];
    mx = std::max(mx, r);
    ss += r * r;
  }
  t.max_rel = mx;
  t.rms_rel = std::sqrt(ss / static_cast<double>(v.size()));
  return t;
}

void fa_validate(const FlowAdvanceInputs& in) {
  if (!(fa_finite(in.filament_area_mm2) && in.filament_area_mm2 > 0))
    throw InputError("the flow-dependent advance needs a positive filament cross-section (mm^2)");
  if (in.levels.size() < 2)
    throw InputError(
        fmt::format("the flow-dependent advance needs at least two flow levels, not {}", in.levels.size()));
  std::vector<double> qs;
  for (const auto& l : in.levels) {
    if (!(fa_finite(l.flow_mm3_s) && l.flow_mm3_s > 0))
      throw InputError(fmt::format("flow level {} mm^3/s: flows must be positive", l.flow_mm3_s));
    if (!(fa_finite(l.tau_s) && l.tau_s > 0))
      throw InputError(fmt::format("flow level {} mm^3/s has tau {} s: it must be positive", l.flow_mm3_s, l.tau_s));
    if ((fa_finite(l.tau_lo_s) && !(l.tau_lo_s <= l.tau_s)) || (fa_finite(l.tau_hi_s) && !(l.tau_hi_s >= l.tau_s)))
      throw InputError(fmt::format("flow level {} mm^3/s: its 95 % interval [{}, {}] s does not hold tau {} s",
                                   l.flow_mm3_s, l.tau_lo_s, l.tau_hi_s, l.tau_s));
    qs.push_back(l.flow_mm3_s);
  }
  if (const auto& lv = in.low_volume; lv && !(lv->flow_mm3_s > 0 && lv->volume_mm3 > 0 && lv->half_width_mm3 >= 0 &&
                                              fa_finite(lv->flow_mm3_s) && fa_finite(lv->volume_mm3)))
    throw InputError(fmt::format("the measured stored volume {} mm^3 at {} mm^3/s must be positive", lv->volume_mm3,
                                 lv->flow_mm3_s));
  std::sort(qs.begin(), qs.end());
  for (std::size_t i = 1; i < qs.size(); ++i)
    if (qs[i] == qs[i - 1]) throw InputError(fmt::format("two flow levels at the same flow {} mm^3/s", qs[i]));
}

}  // namespace

std::string to_string(KalicoModel m) { return m == KalicoModel::tanh ? "tanh" : "recipr"; }

double kalico_offset_mm(KalicoModel m, double linear_advance_s, double nonlinear_offset_mm,
                        double linearization_velocity_mm_s, double v_mm_s) {
  double pos = linear_advance_s * v_mm_s;
  if (nonlinear_offset_mm != 0.0) {
    const double rel = v_mm_s / linearization_velocity_mm_s;
    pos += nonlinear_offset_mm * (m == KalicoModel::tanh ? std::tanh(rel) : (1. - 1. / (1. + rel)));
  }
  return pos;
}

double flow_tau_s(const FlowAdvanceInputs& in, double q, int which) {
  const FaKnots k = fa_knots(in, which);
  if (fa_trend_usable(in)) {
    const double est = in.trend->a * std::pow(std::max(q, 0.0), in.trend->b);
    if (which == 0) return est;
    const FaKnots k0 = fa_knots(in, 0);
    return est * fa_table_tau(k, q) / fa_table_tau(k0, q);
  }
  return fa_table_tau(k, q);
}

double stored_volume_mm3(const FlowAdvanceInputs& in, double q, int which) {
  if (q <= 0) return 0;
  const FaKnots k = fa_knots(in, which);
  if (fa_volume_known(in)) return fa_known_volume(in, q, which);
  if (fa_trend_usable(in)) {
    const double est = fa_trend_volume(*in.trend, k.q.front(), q, which);
    if (which == 0) return est;
    // The band of a trend: its bound below the data scaled by the levels' bound over their estimate.
    const FaKnots k0 = fa_knots(in, 0);
    return est * fa_table_volume(k, q) / fa_table_volume(k0, q);
  }
  return fa_table_volume(k, q);
}

double needed_advance_s(const FlowAdvanceInputs& in, double q, int which) {
  if (!(q > 0)) throw InputError(fmt::format("the needed advance is defined for flows above 0, not {} mm^3/s", q));
  return stored_volume_mm3(in, q, which) / q;
}

KalicoFit fit_kalico(const FlowAdvanceInputs& in, KalicoModel model, const std::vector<double>& flows) {
  std::vector<double> v, y;
  for (double q : flows) {
    v.push_back(q / in.filament_area_mm2);
    y.push_back(stored_volume_mm3(in, q) / in.filament_area_mm2);
  }
  const double vmin = *std::min_element(v.begin(), v.end());
  const double vmax = *std::max_element(v.begin(), v.end());
  // linearization_velocity: log grid from a twentieth of the slowest to twenty times the fastest
  // filament speed, then a golden-section refinement around the best grid point.
  const int n = 240;
  const double lo = std::log(vmin / 20), hi = std::log(vmax * 20);
  FaTrial best;
  double best_lv = std::exp(lo);
  int best_i = 0;
  for (int i = 0; i <= n; ++i) {
    const double lv = std::exp(lo + (hi - lo) * i / n);
    const FaTrial t = fa_fit_fixed(model, lv, v, y);
    if (t.max_rel < best.max_rel) {
      best = t;
      best_lv = lv;
      best_i = i;
    }
  }
  double a = lo + (hi - lo) * std::max(0, best_i - 1) / n, b = lo + (hi - lo) * std::min(n, best_i + 1) / n;
  const double gr = (std::sqrt(5.0) - 1) / 2;
  for (int it = 0; it < 40; ++it) {
    const double c = b - gr * (b - a), d = a + gr * (b - a);
    if (fa_fit_fixed(model, std::exp(c), v, y).max_rel < fa_fit_fixed(model, std::exp(d), v, y).max_rel) b = d;
    else a = c;
  }
  const FaTrial refined = fa_fit_fixed(model, std::exp(0.5 * (a + b)), v, y);
  if (refined.max_rel < best.max_rel) {
    best = refined;
    best_lv = std::exp(0.5 * (a + b));
  }
  KalicoFit f;
  f.model = model;
  f.linear_advance_s = best.la;
  f.nonlinear_offset_mm = best.off;
  f.linearization_velocity_mm_s = best_lv;
  f.max_rel_error = best.max_rel;
  f.rms_rel_error = best.rms_rel;
  return f;
}

namespace {

// Below this share of the design flow's stored volume the part below the data is not worth a note.
constexpr double kLowFlowShareNote = 0.1;

/// How much of the design flow's stored volume lies below the lowest identified flow, where a
/// power-law trend is bounded rather than followed (fa_trend_volume); said when it matters.
void fa_note_low_flow(const FlowAdvanceInputs& in, FlowAdvanceDesign& d) {
  if (!fa_trend_usable(in)) return;
  const double q0 = d.flow_min_mm3_s, qd = d.design_flow_mm3_s;
  if (in.volume_measured && !in.low_volume) {
    d.notes.push_back(
        "the sensor reads the stored melt volume at every level (a pressure sensor): V(Q) at the design flow is "
        "measured, not extrapolated below the data; its band is the model's 95 % interval of V");
    return;
  }
  if (const auto& lv = in.low_volume) {
    d.low_flow_share = stored_volume_mm3(in, std::min(qd, lv->flow_mm3_s)) / stored_volume_mm3(in, qd);
    d.notes.push_back(fmt::format(
        "{:.0f} % of the melt stored at the design flow is the volume held at the first level {:.3g} mm^3/s, "
        "measured from the record's start-up transient ({:.4g} mm^3 [{:.4g}, {:.4g}]): the flows below the data are "
        "not extrapolated",
        100 * d.low_flow_share, lv->flow_mm3_s, lv->volume_mm3, lv->volume_mm3 - lv->half_width_mm3,
        lv->volume_mm3 + lv->half_width_mm3));
    return;
  }
  d.low_flow_share = fa_trend_volume(*in.trend, q0, std::min(qd, q0), 0) / fa_trend_volume(*in.trend, q0, qd, 0);
  if (d.low_flow_share < kLowFlowShareNote) return;
  d.notes.push_back(fmt::format(
      "{:.0f} % of the melt stored at the design flow lies below the lowest identified flow {:.3g} mm^3/s, "
      "where no level measured tau: its bounds are tau held at that flow and the power law followed to zero "
      "flow ({:.4g}-{:.4g} s), and the advance takes the middle of the two",
      100 * d.low_flow_share, q0, d.k_design_lo_s, d.k_design_hi_s));
}

/// A design flow outside the identified flows. Above them a power-law trend (the whole-record
/// model's tau ~ Q^b) carries tau on, and its band is the law's own: said as a note. Without a
/// trend tau is held at the nearest level, which a liquefier whose tau falls with the flow does
/// not do: a warning.
void fa_note_design_flow_range(const FlowAdvanceInputs& in, FlowAdvanceDesign& d) {
  const double qd = d.design_flow_mm3_s;
  if (qd >= d.flow_min_mm3_s && qd <= d.flow_max_mm3_s) return;
  const std::string where =
      fmt::format("design flow {:.3g} mm^3/s lies {} the identified flows {:.3g}-{:.3g} mm^3/s", qd,
                  qd > d.flow_max_mm3_s ? "above" : "below", d.flow_min_mm3_s, d.flow_max_mm3_s);
  if (fa_trend_usable(in) && qd > d.flow_max_mm3_s)
    d.notes.push_back(fmt::format(
        "{}: tau there follows the power law tau ~ Q^{:.3g} fitted to the record beyond it (its band assumes the "
        "law holds there); a test at the design flow would measure it",
        where, in.trend->b));
  else if (!fa_trend_usable(in)) d.warnings.push_back(where + ": tau is held at the nearest level there");
}

/// Whether the advance has a band and what it is: from the levels' intervals, from the power
/// law, or the interval of a known volume. True when every level has an interval.
bool fa_band_kind(const FlowAdvanceInputs& in, FlowAdvanceDesign& d) {
  const bool level_band = std::all_of(in.levels.begin(), in.levels.end(),
                                      [](const FlowTau& l) { return fa_finite(l.tau_lo_s) && fa_finite(l.tau_hi_s); });
  d.has_band = level_band || fa_trend_usable(in);
  d.band_from_levels = level_band && !fa_volume_known(in);
  d.band_is_interval = fa_volume_known(in) &&
                       fa_finite(in.low_volume ? std::hypot(in.low_volume->half_width_mm3, in.trend_rel_half_width)
                                               : in.volume_rel_half_width);
  return level_band;
}

/// The identified flows' range and the design flow (given, else their geometric middle) with
/// the single advance needed there and its band.
void fa_design_point(const FlowAdvanceInputs& in, const FaKnots& k, FlowAdvanceDesign& d) {
  d.flow_min_mm3_s = k.q.front();
  d.flow_max_mm3_s = k.q.back();
  d.design_flow_mm3_s = fa_finite(in.design_flow_mm3_s) ? in.design_flow_mm3_s : std::sqrt(k.q.front() * k.q.back());
  if (!(d.design_flow_mm3_s > 0))
    throw InputError(fmt::format("design flow must be above 0 mm^3/s, not {}", d.design_flow_mm3_s));
  if (!fa_finite(in.design_flow_mm3_s))
    d.notes.push_back(fmt::format("no design flow given: the geometric middle of the identified range, {:.3g} mm^3/s",
                                  d.design_flow_mm3_s));
  fa_note_design_flow_range(in, d);
  d.k_design_s = needed_advance_s(in, d.design_flow_mm3_s);
  d.k_design_lo_s = needed_advance_s(in, d.design_flow_mm3_s, -1);
  d.k_design_hi_s = needed_advance_s(in, d.design_flow_mm3_s, +1);
}

/// Kalico: both models over `flows`, the better one (smaller worst relative error) is written;
/// the dead time as its pressure_advance_time_offset.
void fa_kalico(const FlowAdvanceInputs& in, const std::vector<double>& flows, FlowAdvanceDesign& d) {
  const KalicoFit ft = fit_kalico(in, KalicoModel::tanh, flows);
  const KalicoFit fr = fit_kalico(in, KalicoModel::recipr, flows);
  d.kalico = ft.max_rel_error <= fr.max_rel_error ? ft : fr;
  d.kalico_other = ft.max_rel_error <= fr.max_rel_error ? fr : ft;
  if (d.kalico.max_rel_error > 0.05)
    d.warnings.push_back(
        fmt::format("Kalico's {} model reproduces the needed advance only within {:.1f} % over the "
                    "identified flows",
                    to_string(d.kalico.model), 100 * d.kalico.max_rel_error));
  // pressure_advance_time_offset shifts the whole extruder motion earlier by that time
  // (kin_extruder.c extruder_calc_position: move_time += es->time_offset): the dead time.
  // Kalico accepts -0.2..0.2 s (extruder.py, minval=-0.2, maxval=0.2).
  if (fa_finite(in.theta_s) && in.theta_s >= 0) {
    d.kalico_time_offset_s = std::min(in.theta_s, 0.2);
    if (in.theta_s > 0.2)
      d.warnings.push_back(
          fmt::format("dead time {:.3g} s exceeds Kalico's pressure_advance_time_offset maximum of "
                      "0.2 s: written as 0.2 s",
                      in.theta_s));
  }
}

/// The curve at `flows`: tau, the advance needed (with its band) and the volume, and Kalico's.
void fa_curve(const FlowAdvanceInputs& in, const std::vector<double>& flows, FlowAdvanceDesign& d) {
  for (double q : flows) {
    FlowAdvanceSample s;
    s.flow_mm3_s = q;
    s.tau_s = flow_tau_s(in, q);
    s.k_need_s = needed_advance_s(in, q);
    s.offset_need_mm = stored_volume_mm3(in, q) / in.filament_area_mm2;
    if (d.has_band) {
      s.k_lo_s = needed_advance_s(in, q, -1);
      s.k_hi_s = needed_advance_s(in, q, +1);
    }
    const double v = q / in.filament_area_mm2;
    s.k_kalico_s = kalico_offset_mm(d.kalico.model, d.kalico.linear_advance_s, d.kalico.nonlinear_offset_mm,
                                    d.kalico.linearization_velocity_mm_s, v) /
                   v;
    d.curve.push_back(s);
  }
}

/// The range around the design flow where the single K stays within the tolerance of the need
/// (a fine scan of the identified range; the contiguous interval holding the design flow).
void fa_range_within_tolerance(const FlowAdvanceInputs& in, FlowAdvanceDesign& d) {
  const int nf = 2000;
  auto ok = [&](double q) {
    const double need = needed_advance_s(in, q);
    return std::abs(d.k_design_s - need) <= in.tolerance * need;
  };
  const double qd = std::clamp(d.design_flow_mm3_s, d.flow_min_mm3_s, d.flow_max_mm3_s);
  if (!ok(qd)) return;
  const double step = (d.flow_max_mm3_s - d.flow_min_mm3_s) / nf;
  double lo = qd, hi = qd;
  while (lo > d.flow_min_mm3_s && ok(std::max(lo - step, d.flow_min_mm3_s))) lo = std::max(lo - step, d.flow_min_mm3_s);
  while (hi < d.flow_max_mm3_s && ok(std::min(hi + step, d.flow_max_mm3_s))) hi = std::min(hi + step, d.flow_max_mm3_s);
  d.k_within_lo_mm3_s = lo;
  d.k_within_hi_mm3_s = hi;
}

/// OrcaSlicer table: the need at each identified level, for each acceleration.
void fa_orca_table(const FlowAdvanceInputs& in, const FaKnots& k, FlowAdvanceDesign& d) {
  std::vector<double> accels = in.orca_accels_mm_s2;
  if (accels.empty()) accels.push_back(0.0);
  std::sort(accels.begin(), accels.end());
  accels.erase(std::unique(accels.begin(), accels.end()), accels.end());
  for (double q : k.q)
    for (double acc : accels) d.orca.push_back({needed_advance_s(in, q), q, acc});
}

/// How the advance was designed, and what its band is when the levels have no intervals.
void fa_note_method(const FlowAdvanceInputs& in, bool level_band, FlowAdvanceDesign& d) {
  const char* below = fa_volume_known(in)
                          ? (in.low_volume ? "the volume at the first level measured" : "the volume read by the sensor")
                      : fa_trend_usable(in) ? "below the lowest level the middle of tau held there and the power law"
                                            : "tau held at the lowest level below it";
  d.notes.push_back(fmt::format(
      "advance designed as the stored melt volume V(Q) = integral of tau over 0..Q (one first-order store, {}); the "
      "single K at flow Q is V(Q)/Q",
      below));
  if (!level_band && !d.band_is_interval)
    d.notes.push_back(d.has_band ? "no 95 % intervals per level: the advance's band is that of the flows below the data"
                                 : "no 95 % intervals per level: the advance is drawn without a band");
}

}  // namespace

FlowAdvanceDesign design_flow_advance(const FlowAdvanceInputs& in) {
  fa_validate(in);
  FlowAdvanceDesign d;
  if (in.trend && !fa_trend_usable(in))
    d.warnings.push_back(fmt::format(
        "the levels' time constants fall with the flow as steeply as tau ~ Q^{:.3g}: followed down to zero flow that "
        "trend would store an unbounded melt volume, so it is not used; the advance is designed from the measured "
        "levels, assuming tau holds the lowest level's value below it",
        in.trend->b));
  const bool level_band = fa_band_kind(in, d);
  const FaKnots k = fa_knots(in, 0);
  fa_design_point(in, k, d);
  fa_note_low_flow(in, d);

  // Curve over the identified range (linear in flow).
  const int ns = std::max(8, in.samples);
  std::vector<double> flows;
  for (int i = 0; i < ns; ++i) flows.push_back(d.flow_min_mm3_s + (d.flow_max_mm3_s - d.flow_min_mm3_s) * i / (ns - 1));
  fa_kalico(in, flows, d);
  fa_curve(in, flows, d);
  fa_range_within_tolerance(in, d);
  fa_orca_table(in, k, d);
  fa_note_method(in, level_band, d);
  return d;
}

nlohmann::json FlowAdvanceDesign::to_json() const {
  auto kal = [](const KalicoFit& f) {
    return nlohmann::json{{"pressure_advance_model", to_string(f.model)},
                          {"linear_advance_s", fa_num(f.linear_advance_s)},
                          {"nonlinear_offset_mm", fa_num(f.nonlinear_offset_mm)},
                          {"linearization_velocity_mm_s", fa_num(f.linearization_velocity_mm_s)},
                          {"max_rel_error", fa_num(f.max_rel_error)},
                          {"rms_rel_error", fa_num(f.rms_rel_error)}};
  };
  nlohmann::json curve_j = nlohmann::json::array();
  for (const auto& s : curve)
    curve_j.push_back({{"flow_mm3_s", fa_num(s.flow_mm3_s)},
                       {"tau_s", fa_num(s.tau_s)},
                       {"K_need_s", fa_num(s.k_need_s)},
                       {"K_lo_s", fa_num(s.k_lo_s)},
                       {"K_hi_s", fa_num(s.k_hi_s)},
                       {"offset_need_mm", fa_num(s.offset_need_mm)},
                       {"K_kalico_s", fa_num(s.k_kalico_s)}});
  nlohmann::json orca_j = nlohmann::json::array();
  for (const auto& o : orca)
    orca_j.push_back(
        {{"K_s", fa_num(o.k_s)}, {"flow_mm3_s", fa_num(o.flow_mm3_s)}, {"accel_mm_s2", fa_num(o.accel_mm_s2)}});
  nlohmann::json kj = kal(kalico);
  kj["pressure_advance_time_offset_s"] = fa_num(kalico_time_offset_s);
  return {{"flow_range_mm3_s", {fa_num(flow_min_mm3_s), fa_num(flow_max_mm3_s)}},
          {"design_flow_mm3_s", fa_num(design_flow_mm3_s)},
          {"single",
           {{"K_s", fa_num(k_design_s)},
            {"K_bounds_s", {fa_num(k_design_lo_s), fa_num(k_design_hi_s)}},
            {"low_flow_share", fa_num(low_flow_share)},
            {"within_10pct_flow_mm3_s", {fa_num(k_within_lo_mm3_s), fa_num(k_within_hi_mm3_s)}}}},
          {"kalico", kj},
          {"kalico_other_model", kal(kalico_other)},
          {"orca", orca_j},
          {"curve", curve_j},
          {"has_band", has_band},
          {"band_is_interval", band_is_interval},
          {"notes", notes},
          {"warnings", warnings}};
}

}  // namespace tunekit::design
