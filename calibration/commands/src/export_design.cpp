// The design stages of `tunekit export` (export_design.hpp).
#include "export_design.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "tunekit/fitting/stats.hpp"
#include "tunekit/calibration/results/agreement.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/firmware/firmware_export.hpp"
#include "tunekit/firmware/firmware_limits.hpp"
#include "tunekit/fitting/interpolate.hpp"
#include "tunekit/machine/machine_profile.hpp"

namespace tunekit::calibration::export_design {
namespace {

/// An estimate for the agreement rule: false when the value or its interval is not finite.
bool estimate_of(const EstimatedValue& v, const std::string& method, Estimate& out) {
  out = {method, v.value, v.ci95_lo, v.ci95_hi};
  return std::isfinite(v.value) && std::isfinite(v.ci95_lo) && std::isfinite(v.ci95_hi);
}

void take_step(const StepDesignInput& s, LiquefierInputs& li) {
  design::AdvanceInputs& in = li.in;
  in.tau_s = s.tau_s.value;
  in.tau_stderr_s = s.tau_s.std_error;
  li.tau_ci95_lo = s.tau_s.ci95_lo;
  li.tau_ci95_hi = s.tau_s.ci95_hi;
  // The dead time the summary lists: the whole-record model's when it was fitted.
  in.theta_s = s.model && std::isfinite(s.model->theta_s.value) ? s.model->theta_s.value : s.theta_s.value;
  in.gain = s.K.value;
  in.gain_unit = s.K_unit;
  in.tau_source = "step";
  li.trend_u = s.trend;
  li.model = s.model;
  if (!std::isfinite(in.tau_s) && s.model && std::isfinite(s.model->a.value)) in.tau_s = s.model->a.value;
  li.levels_in_flow = s.levels_in_flow;
  li.levels = s.levels;
  for (const auto& l : s.levels) in.points.push_back({l.u, l.K, l.tau_s, l.theta_s});
}

/// Both measured: the step value is designed with; the two are compared by the one rule.
void compare_step_and_freq(const StepDesignInput& s, const FreqDesignInput& f, LiquefierInputs& li, Envelope& env) {
  Estimate by_step, by_freq;
  if (step_tau_for_freq(s, f, by_step) && estimate_of(f.tau_s, "frequency response", by_freq)) {
    Agreement a =
        compare_estimates("liquefier time constant tau", "s", by_step, by_freq, fitting::equivalence_margin("tau_s"));
    a.id = "tau";
    if (!a.agree) env.warn(a.statement + "; the step value is used");
    li.agreement.push_back(to_json(a));
    return;
  }
  env.warn(
      fmt::format("the step response gives tau = {:.4g} s, the frequency response {:.4g} s; without a 95 % interval "
                  "for each they are not compared; the step value is used",
                  s.tau_s.value, f.tau_s.value));
}

}  // namespace

LiquefierInputs liquefier_inputs(const ExportOptions& a, const DesignInputs& d, Envelope& env) {
  LiquefierInputs li;
  design::AdvanceInputs& in = li.in;
  if (d.step) take_step(*d.step, li);
  const bool freq_tau = d.freq && std::isfinite(d.freq->tau_s.value);
  if (!std::isfinite(in.tau_s) && freq_tau) {
    in.tau_s = d.freq->tau_s.value;
    in.tau_stderr_s = d.freq->tau_s.std_error;
    li.tau_ci95_lo = d.freq->tau_s.ci95_lo;
    li.tau_ci95_hi = d.freq->tau_s.ci95_hi;
    in.tau_source = "freq";
  } else if (std::isfinite(in.tau_s) && freq_tau) {
    compare_step_and_freq(*d.step, *d.freq, li, env);
  }
  if (d.rheo) {
    in.rheo_flow_mm3_s = d.rheo->flow_mm3_s;
    in.rheo_relative_tau = d.rheo->relative_tau;
    in.rheo_reference_flow_mm3_s = d.rheo->reference_flow_mm3_s;
  }
  if (std::isfinite(a.pa_k)) {
    li.model.reset();
    in.tau_s = a.pa_k;
    in.tau_stderr_s = fitting::kNaN;
    li.tau_ci95_lo = li.tau_ci95_hi = fitting::kNaN;
    in.tau_source = "command line";
    in.points.clear();
    in.rheo_flow_mm3_s.clear();
    in.rheo_relative_tau.clear();
  }
  return li;
}

void apply_machine_profile(const ExportOptions& a, LiquefierInputs& li, Envelope& env) {
  machine::MachineProfile profile;
  if (a.loaded_profile && a.loaded_profile_digest) {
    profile = *a.loaded_profile;
    add_input(env, *a.loaded_profile_digest);
  } else if (!a.profile.empty()) {
    std::string bytes;
    profile = machine::load_machine_profile(a.profile, &bytes);
    env.add_input(a.profile, bytes);
  }
  design::AdvanceInputs& in = li.in;
  in.filament_area_mm2 = profile.filament_area_mm2();
  if (li.levels_in_flow)
    for (auto& p : in.points) p.feed_mm_s /= in.filament_area_mm2;  // mm^3/s -> mm/s of filament
  in.line_area_mm2 = profile.line_area_mm2();
  in.print_speed_mm_s = profile.print.speed_mm_s;
  in.print_accel_mm_s2 = profile.print.max_accel_mm_s2;
  in.extruder_accel_limit_mm_s2 = profile.extruder.max_accel_mm_s2;
  in.design_flow_mm3_s = a.design_flow;
}

std::map<std::string, firmware::ShaperSetting> firmware_shapers(const DesignInputs& d, firmware::ExportFirmware fw,
                                                                bool ft_motion, Envelope& env) {
  // The firmware must have the shaper and accept its damping (firmware_limits.hpp).
  auto usable = [&](const firmware::ShaperSetting& s) {
    const auto f = firmware::limits::find_shaper(fw, firmware::canonical_shaper_type(s.type), ft_motion);
    return f && s.damping <= f->max_damping;
  };
  std::map<std::string, firmware::ShaperSetting> out;
  for (const auto& [axis, in] : d.axes) {
    // A Z shaper in the results is written only where the firmware reads one (Klipper); elsewhere
    // the X and Y shapers are exported and the Z one is reported (--shaper-z is refused instead).
    if (axis == "z" && fw != firmware::ExportFirmware::klipper) {
      env.warn(fmt::format("{}: the Z shaper is not exported: {}", in.origin, firmware::z_shaper_refusal(fw)));
      continue;
    }
    if (usable(in.recommended)) {
      out[axis] = in.recommended;
      continue;
    }
    // The overall recommendation is not available on this firmware: the best-scoring candidate
    // the firmware has (the results list every type's best frequency).
    const ScoredShaper* best = nullptr;
    for (const auto& c : in.candidates)
      if (usable(c.setting) && std::isfinite(c.score) && (!best || c.score < best->score)) best = &c;
    const std::string title = firmware::limits::firmware_title(fw);
    if (!best)
      throw InputError(fmt::format("axes.{}: the recommended shaper {} is not available in {} and no candidate is ({} "
                                   "has {}{}); run 'tunekit shaper --firmware {}'",
                                   axis, in.recommended.type, title, title, firmware::limits::shaper_list(fw),
                                   fw == firmware::ExportFirmware::marlin ? ": its input shaping is ZV only" : "",
                                   firmware::to_string(fw)),
                       in.origin);
    env.warn(
        fmt::format("{}: axis {}: the recommended {} shaper is not available in {} (it has {}); using the "
                    "best-scoring candidate it has: {} at {:.1f} Hz",
                    in.origin, axis, in.recommended.type, title, firmware::limits::shaper_list(fw), best->setting.type,
                    best->setting.freq_hz));
    out[axis] = best->setting;
  }
  return out;
}

namespace {

/// The whole-record model as the flow design's inputs: tau = a Q^b (in flow) at flows spread over
/// the record's inputs, so that the advance is V(Q)/Q = a Q^b / (b+1) of the model.
design::FlowAdvanceInputs model_flow_inputs(const LiquefierInputs& li, const design::AdvanceDesign& design) {
  const design::AdvanceInputs& in = li.in;
  const StepModelInput& m = *li.model;
  const double to_flow = li.levels_in_flow ? 1.0 : in.filament_area_mm2;  // feed mm/s -> mm^3/s
  design::FlowAdvanceInputs fin;
  fin.filament_area_mm2 = in.filament_area_mm2;
  // tau = a u^b with u = Q / to_flow: in flow, a to_flow^-b Q^b.
  fin.trend = design::TauPowerLaw{m.a.value * std::pow(to_flow, -m.b.value), m.b.value};
  // The flows the record reached (a record at one flow: half as much again, for a spread).
  const double q_lo = m.u_min * to_flow, q_hi = m.u_max * to_flow > q_lo ? m.u_max * to_flow : 1.5 * q_lo;
  for (int i = 0; i < 6; ++i) {
    const double q = q_lo * std::pow(q_hi / q_lo, i / 5.0);
    fin.levels.push_back({q, fin.trend->a * std::pow(q, fin.trend->b), fitting::kNaN, fitting::kNaN});
  }
  // The melt below the data: read by a pressure sensor at every level, or measured at the first
  // level from the record's start-up transient; else bounded by the flow design.
  fin.trend_rel_half_width = m.tau_rel_ci95;
  fin.volume_measured = m.sensor_reads_volume;
  fin.volume_rel_half_width = m.volume_rel_ci95;
  if (m.u_ref > 0 && std::isfinite(m.ln_tau_b_cov[0]))
    fin.trend_covariance = design::FlowAdvanceInputs::TrendCovariance{m.u_ref * to_flow, m.ln_tau_b_cov[0],
                                                                      m.ln_tau_b_cov[1], m.ln_tau_b_cov[2]};
  if (const auto& rv = m.rest_volume; rv && !m.sensor_reads_volume)
    fin.low_volume =
        design::MeasuredVolume{rv->u * to_flow, rv->value * to_flow, 0.5 * (rv->ci95_hi - rv->ci95_lo) * to_flow};
  fin.design_flow_mm3_s = design.design_flow_mm3_s;
  fin.theta_s = std::isfinite(m.theta_s.value) ? m.theta_s.value : design.theta_s;
  if (std::isfinite(in.print_accel_mm_s2) && in.print_accel_mm_s2 > 0) fin.orca_accels_mm_s2 = {in.print_accel_mm_s2};
  return fin;
}

std::string model_note(double b, bool linear, bool rest_volume) {
  if (rest_volume)
    return fmt::format(
        "designed from the whole-record model tau = a Q^b with b = {:.3g} above the first level Q1 and the volume V1 "
        "held at Q1, measured from the record's start-up transient: the advance at flow Q is V(Q)/Q = (V1 + a (Q^(b+1) "
        "- Q1^(b+1)) / (b + 1)) / Q",
        b);
  if (linear)
    return "designed from the whole-record model with b = 0 (the data do not support a flow-dependent tau): the "
           "advance is tau";
  return fmt::format(
      "designed from the whole-record model tau = a Q^b with b = {:.3g}: the advance at flow Q is V(Q)/Q = a Q^b / "
      "(b + 1)",
      b);
}

bool model_usable(const LiquefierInputs& li) {
  return li.model && std::isfinite(li.model->a.value) && li.model->a.value > 0 && std::isfinite(li.model->b.value) &&
         li.model->b.value > -1 && li.model->u_min > 0 && std::isfinite(li.model->u_max);
}

/// The levels as flows (mm^3/s) for the flow-dependent design.
design::FlowAdvanceInputs flow_inputs(const LiquefierInputs& li, const design::AdvanceDesign& design) {
  if (model_usable(li)) return model_flow_inputs(li, design);
  const design::AdvanceInputs& in = li.in;
  design::FlowAdvanceInputs fin;
  fin.filament_area_mm2 = in.filament_area_mm2;
  for (const auto& l : li.levels) {
    const double flow = std::isfinite(l.flow_mm3_s) ? l.flow_mm3_s
                        : li.levels_in_flow         ? l.u
                                                    : l.u * in.filament_area_mm2;  // feed mm/s -> mm^3/s
    fin.levels.push_back({flow, l.tau_s, l.tau_ci95_lo, l.tau_ci95_hi});
  }
  if (li.trend_u) {
    // tau = a u^b with u a feed (mm/s): in flow, a (Q/A)^b = (a A^-b) Q^b.
    design::TauPowerLaw t = *li.trend_u;
    if (!li.levels_in_flow) t.a *= std::pow(in.filament_area_mm2, -t.b);
    fin.trend = t;
  }
  fin.design_flow_mm3_s = design.design_flow_mm3_s;
  fin.theta_s = design.theta_s;
  if (std::isfinite(in.print_accel_mm_s2) && in.print_accel_mm_s2 > 0) fin.orca_accels_mm_s2 = {in.print_accel_mm_s2};
  return fin;
}

// A rheology prediction whose shape of tau(Q) differs from the measured one by more than this
// fraction over the identified flows is warned about: beyond the few-% scatter of the levels'
// own intervals, it says the melt model or the nozzle geometry given to rheo is not this machine's.
constexpr double kRheologyGapWarning = 0.2;

/// The predicted shape of tau(Q), scaled to the measured tau at the prediction's reference flow,
/// against the measured tau(Q) over the identified flows.
nlohmann::json rheology_cross_check(const design::AdvanceInputs& in, const design::FlowAdvanceInputs& fin,
                                    const design::FlowAdvanceDesign& flow, Envelope& env) {
  const auto& rq = in.rheo_flow_mm3_s;
  const auto& rr = in.rheo_relative_tau;
  auto rel_at = [&](double q) { return fitting::interp_linear(rq, rr, q); };
  const double qref =
      std::isfinite(in.rheo_reference_flow_mm3_s) ? in.rheo_reference_flow_mm3_s : flow.design_flow_mm3_s;
  const double scale = design::flow_tau_s(fin, qref) / rel_at(qref);
  std::vector<double> fq, ft;
  double gap = 0;
  for (const auto& c : flow.curve) {
    fq.push_back(c.flow_mm3_s);
    ft.push_back(scale * rel_at(c.flow_mm3_s));
    gap = std::max(gap, std::abs(ft.back() - c.tau_s) / c.tau_s);
  }
  if (gap > kRheologyGapWarning)
    env.warn(
        fmt::format("the rheology prediction of tau(Q) differs from the measured one by up to {:.0f} % over the "
                    "identified flows (scaled to agree at {:.3g} mm^3/s)",
                    100 * gap, qref));
  return {{"flow_mm3_s", fq}, {"tau_pred_s", ft}, {"max_gap_rel", gap}, {"reference_flow_mm3_s", qref}};
}

firmware::KalicoAdvanceSetting kalico_setting(const design::FlowAdvanceDesign& flow) {
  firmware::KalicoAdvanceSetting k;
  k.model = design::to_string(flow.kalico.model);
  k.linear_advance_s = flow.kalico.linear_advance_s;
  k.nonlinear_offset_mm = flow.kalico.nonlinear_offset_mm;
  k.linearization_velocity_mm_s = flow.kalico.linearization_velocity_mm_s;
  if (std::isfinite(flow.kalico_time_offset_s)) k.time_offset_s = flow.kalico_time_offset_s;
  return k;
}

/// The widest relative 95 % interval of the levels' tau (NaN when a level has none).
double widest_level_interval(const LiquefierInputs& li) {
  double widest = 0;
  for (const auto& l : li.levels) {
    if (!(l.tau_s > 0) || !std::isfinite(l.tau_ci95_lo) || !std::isfinite(l.tau_ci95_hi)) return fitting::kNaN;
    widest = std::max({widest, (l.tau_s - l.tau_ci95_lo) / l.tau_s, (l.tau_ci95_hi - l.tau_s) / l.tau_s});
  }
  return !li.levels.empty() && widest < 1 ? widest : fitting::kNaN;
}

}  // namespace

std::optional<std::pair<double, double>> advance_interval(const LiquefierInputs& li, const ExportOutcome& outcome) {
  const auto& design = outcome.design;
  if (!design || !outcome.settings.pa_k_s) return std::nullopt;
  const double k = *outcome.settings.pa_k_s;
  if (!outcome.flow) {
    // K is tau (or tau times a factor): its interval is tau's, as the fit that gave tau reports it
    // (a t quantile, a cluster-robust variance), not a normal one from the standard error.
    const double tau = li.in.tau_s;
    if (tau > 0 && std::isfinite(li.tau_ci95_lo) && std::isfinite(li.tau_ci95_hi))
      return std::pair{k * li.tau_ci95_lo / tau, k * li.tau_ci95_hi / tau};
    if (!std::isfinite(design->k_stderr_s)) return std::nullopt;
    return std::pair{k - fitting::kZ95 * design->k_stderr_s, k + fitting::kZ95 * design->k_stderr_s};
  }
  const auto& flow = *outcome.flow;
  if (!std::isfinite(flow.k_design_lo_s) || !std::isfinite(flow.k_design_hi_s)) return std::nullopt;
  if (flow.band_from_levels) return std::pair{flow.k_design_lo_s, flow.k_design_hi_s};
  // A measured interval of V(Q)/Q: none when it reaches 0 or beyond twice K (a relative half-width
  // of 100 % and more says nothing; a results file's hostile variances give such widths).
  if (flow.band_is_interval) {
    if (!(flow.k_design_lo_s > 0 && flow.k_design_hi_s < 2 * k)) return std::nullopt;
    return std::pair{flow.k_design_lo_s, flow.k_design_hi_s};
  }
  // Designed from the whole-record model: the model's own uncertainty of tau over the flows it
  // saw (the levels' separate fits are narrower than the model they do not feed: on the camera's
  // two-level line test they covered the simulator's tau 49 % of the time).
  const double widest = model_usable(li) ? li.model->tau_rel_ci95 : widest_level_interval(li);
  if (!(widest >= 0 && widest < 1)) return std::nullopt;  // NaN, negative or a width of 100 % and more
  return std::pair{flow.k_design_lo_s * (1 - widest), flow.k_design_hi_s * (1 + widest)};
}

nlohmann::json design_advance(const ExportOptions& a, LiquefierInputs& li, ExportOutcome& outcome) {
  Envelope& env = outcome.envelope;
  firmware::CompensatorSettings& settings = outcome.settings;
  const design::AdvanceInputs& in = li.in;
  const bool have_tau = std::isfinite(in.tau_s) || !in.points.empty();
  if (a.no_pa || !have_tau) return nullptr;
  static const std::string no_profile =
      "no --profile: assuming 1.75 mm filament, a 0.45 x 0.2 mm line at 60 mm/s, and no acceleration limits "
      "(the smoothing time is not designed)";
  if (a.profile.empty()) env.warn(no_profile);
  auto& design = outcome.design;
  design = design::design_advance(in);
  settings.pa_k_s = design->k_s;
  settings.pa_smooth_s = firmware::smoothing_time_for(outcome.firmware, *design);
  for (const auto& w : design->warnings) env.warn(w);
  // Flow-dependent design (flow_advance.hpp) when two or more levels were identified; its own
  // warning says when the design flow lies outside the flows identified.
  if (!model_usable(li) && !(design->schedule.size() >= 2 && design->k_source == "operating points")) {
    if (!design->outside_range_warning.empty()) env.warn(design->outside_range_warning);
    return nullptr;
  }
  const design::FlowAdvanceInputs fin = flow_inputs(li, *design);
  outcome.flow = design::design_flow_advance(fin);
  auto& flow = *outcome.flow;
  if (model_usable(li)) {
    const bool rest = fin.low_volume.has_value();
    std::string note = li.model->linear ? model_note(0.0, true, rest) : model_note(li.model->b.value, false, rest);
    flow.notes.insert(flow.notes.begin(), std::move(note));
  }
  for (const auto& w : flow.warnings) env.warn(w);
  nlohmann::json rheology;
  if (in.rheo_flow_mm3_s.size() >= 2 && in.rheo_flow_mm3_s.size() == in.rheo_relative_tau.size())
    rheology = rheology_cross_check(in, fin, flow, env);
  settings.pa_k_s = flow.k_design_s;
  // One design everywhere: the per-flow schedule and K follow the flow design (which uses the
  // power-law trend when the step analysis gave one).
  design->k_s = flow.k_design_s;
  if (std::isfinite(flow.low_flow_share)) {
    // The operating points' note holds tau below the lowest level; the flow design says what it did
    // there (design::design_flow_advance's notes): measured from a start at rest, or bounded.
    std::erase_if(design->notes, [](const std::string& n) { return n.rfind("K at each flow is", 0) == 0; });
    design->notes.push_back(fmt::format(
        "K at each flow is the stored melt volume over the flow (the integral of tau over 0..Q, divided by Q), not "
        "tau at that flow; {:.0f} % of it at the design flow lies below the lowest identified flow, {}",
        100 * flow.low_flow_share,
        fin.low_volume ? "measured from the record's start at rest"
                       : "bounded by tau held there and the fitted power law followed to zero flow (K is the middle "
                         "of the two, its interval spans both)"));
  }
  for (auto& s : design->schedule) s.k_s = design::needed_advance_s(fin, s.flow_mm3_s);
  if (outcome.firmware == firmware::ExportFirmware::kalico) settings.kalico = kalico_setting(flow);
  return rheology;
}

}  // namespace tunekit::calibration::export_design
