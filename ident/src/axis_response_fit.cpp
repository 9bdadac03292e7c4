// Output-error fit of an axis' modes against its commanded motion (axis_response_fit.hpp).
#include "tunekit/ident/axis_response_fit.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/least_squares.hpp"
#include "tunekit/fitting/stats.hpp"
#include "tunekit/ident/base_excited_mode.hpp"

namespace tunekit::ident {
namespace {

/// Parameters per mode: frequency, damping ratio, gain, deflection and its rate at the first sample.
constexpr std::size_t kParamsPerMode = 5;

/// The commanded acceleration between two samples, piece by piece (fixed for the fit).
struct Sub {
  double h_s, a0, jerk;
};

/// The record's time axis cut at every piece boundary: subs[sample_end[i-1], sample_end[i]) run
/// from sample i-1 to sample i; whole[i] when one piece covers that whole interval (the mode's
/// step of one sample interval then applies).
struct Schedule {
  double dt_s = 0;
  std::vector<Sub> subs;
  std::vector<std::size_t> sample_end;
  std::vector<char> whole;
  std::vector<double> accel_at;  ///< the commanded acceleration at each sample
  std::size_t pieces_used = 0;
};

double accel_of(const AccelPiece& p, double t) { return p.accel_mm_s2 + p.jerk_mm_s3 * (t - p.t0_s); }

Schedule make_schedule(const std::vector<AccelPiece>& motion, double t0, double dt, std::size_t n) {
  Schedule s;
  s.dt_s = dt;
  s.sample_end.assign(n, 0);
  s.whole.assign(n, 0);
  s.accel_at.assign(n, 0.0);
  std::size_t c = 0;
  auto skip_ended = [&](double t) {
    while (c < motion.size() && motion[c].t0_s + motion[c].duration_s <= t) ++c;
  };
  skip_ended(t0);
  if (c < motion.size() && motion[c].t0_s <= t0) s.accel_at[0] = accel_of(motion[c], t0);
  const std::size_t first_piece = c;
  for (std::size_t i = 1; i < n; ++i) {
    const double ta = t0 + static_cast<double>(i - 1) * dt, tb = t0 + static_cast<double>(i) * dt;
    const std::size_t begin = s.subs.size();
    double t = ta;
    while (t < tb) {
      skip_ended(t);
      if (c < motion.size() && motion[c].t0_s <= t) {
        const double to = std::min(tb, motion[c].t0_s + motion[c].duration_s);
        s.subs.push_back({to - t, accel_of(motion[c], t), motion[c].jerk_mm_s3});
        t = to;
      } else {
        const double to = c < motion.size() ? std::min(tb, motion[c].t0_s) : tb;
        s.subs.push_back({to - t, 0.0, 0.0});
        t = to;
      }
    }
    s.sample_end[i] = s.subs.size();
    s.whole[i] = s.subs.size() - begin == 1;
    skip_ended(tb);
    if (c < motion.size() && motion[c].t0_s <= tb) s.accel_at[i] = accel_of(motion[c], tb);
  }
  s.pieces_used = c - first_piece;
  return s;
}

/// The record's model for parameters p (see axis_response_fit.hpp): y_i = a_i + sum_k g_k z_k''
/// + offset.
void model(const Schedule& s, std::size_t modes, const double* p, std::vector<double>& y) {
  const std::size_t n = s.accel_at.size();
  const double offset = p[kParamsPerMode * modes];
  for (std::size_t i = 0; i < n; ++i) y[i] = s.accel_at[i] + offset;
  for (std::size_t k = 0; k < modes; ++k) {
    const double* q = p + kParamsPerMode * k;
    const BaseExcitedMode mode(q[0], q[1]);
    const ModeStep step = mode.step(s.dt_s);
    const double gain = q[2];
    ModeState x{q[3], q[4]};
    y[0] += gain * mode.relative_accel(x, s.accel_at[0]);
    for (std::size_t i = 1; i < n; ++i) {
      if (s.whole[i]) {
        const Sub& u = s.subs[s.sample_end[i - 1]];
        x = BaseExcitedMode::apply(step, x, u.a0, u.jerk);
      } else {
        for (std::size_t j = s.sample_end[i - 1]; j < s.sample_end[i]; ++j)
          x = mode.advance(x, s.subs[j].h_s, s.subs[j].a0, s.subs[j].jerk);
      }
      y[i] += gain * mode.relative_accel(x, s.accel_at[i]);
    }
  }
}

const std::vector<double>& axis_channel(const AccelRecord& r) {
  const std::string want = fmt::format("accel_{}", r.axis);
  for (std::size_t c = 0; c < r.channel_names.size(); ++c)
    if (r.channel_names[c] == want) return r.channels[c];
  throw InputError(fmt::format("the record has no {} column for its axis", want), r.path);
}

std::vector<fitting::ParamSpec> params_for(const std::vector<fitting::ModeStart>& starts, double max_zeta) {
  std::vector<fitting::ParamSpec> ps;
  for (std::size_t k = 0; k < starts.size(); ++k) {
    const auto idx = std::to_string(k + 1);
    const double f0 = starts[k].freq_hz;
    ps.push_back({"freq_hz_" + idx, "Hz", f0, 0.5 * f0, 1.5 * f0});
    ps.push_back({"zeta_" + idx, "1", std::clamp(starts[k].zeta, 2e-4, max_zeta), 1e-4, max_zeta});
    ps.push_back({"gain_" + idx, "1", 1.0 / static_cast<double>(starts.size())});
    ps.push_back({"z0_mm_" + idx, "mm", 0.0});
    ps.push_back({"v0_mm_s_" + idx, "mm/s", 0.0});
  }
  ps.push_back({"offset_mm_s2", "mm/s^2", 0.0});
  return ps;
}

/// Inflates the intervals by the residuals' correlation and collects the modes.
void finish(AxisResponseFit& out, std::size_t modes, double confidence) {
  const auto& d = out.fit.diagnostics;
  const double dof = std::max(1.0, (d.num_observations - d.num_parameters) / out.variance_inflation);
  const double tq = fitting::t_multiplier(confidence, dof), s = std::sqrt(out.variance_inflation);
  for (auto& p : out.fit.params) {
    if (p.fixed || !std::isfinite(p.std_error)) continue;
    p.std_error *= s;
    p.ci95_lo = p.value - tq * p.std_error;
    p.ci95_hi = p.value + tq * p.std_error;
  }
  for (std::size_t k = 0; k < modes; ++k) {
    const auto& pf = out.fit.params[kParamsPerMode * k];
    const auto& pz = out.fit.params[kParamsPerMode * k + 1];
    fitting::ModeEstimate m;
    m.freq_hz = pf.value;
    m.zeta = pz.value;
    m.gain = out.fit.params[kParamsPerMode * k + 2].value;
    m.freq_stderr_hz = pf.std_error;
    m.zeta_stderr = pz.std_error;
    m.freq_ci95_lo = pf.ci95_lo;
    m.freq_ci95_hi = pf.ci95_hi;
    m.zeta_ci95_lo = std::max(0.0, pz.ci95_lo);
    m.zeta_ci95_hi = pz.ci95_hi;
    out.modes.push_back(m);
  }
  std::sort(out.modes.begin(), out.modes.end(), [](const auto& a, const auto& b) { return a.freq_hz < b.freq_hz; });
}

}  // namespace

AxisResponseFit fit_axis_response(const AccelRecord& record, const std::vector<AccelPiece>& motion,
                                  const std::vector<fitting::ModeStart>& starts, const AxisResponseOptions& o) {
  if (starts.empty()) throw InputError("output-error fit: no modes to start from");
  const std::vector<double>& channel = axis_channel(record);
  const double dt = 1.0 / record.sampling.sample_rate_hz;
  // The record from the first piece of motion that starts within it: before that the axis rests,
  // and what rings there is the motion before the record, of every mode the sensor feels (another
  // axis' too, through its cross-axis sensitivity), which the model does not follow. Each mode's
  // state where the fit starts is estimated; by the motion's start the ringing has mostly died out.
  const auto first =
      std::find_if(motion.begin(), motion.end(), [&](const AccelPiece& p) { return p.t0_s > record.start_time_s; });
  const std::size_t skip =
      first == motion.end() ? 0
                            : std::min(channel.size() - 1,
                                       static_cast<std::size_t>(std::floor((first->t0_s - record.start_time_s) / dt)));
  const std::vector<double> y(channel.begin() + static_cast<std::ptrdiff_t>(skip), channel.end());
  const std::size_t n = y.size();
  const double t_first = record.start_time_s + static_cast<double>(skip) * dt;
  if (n < 16) throw InputError("the record ends where the commanded motion starts", record.path);
  const Schedule sched = make_schedule(motion, t_first, dt, n);
  if (sched.pieces_used == 0)
    throw InputError(fmt::format("the commanded motion does not overlap the record ({:.6g} s to {:.6g} s)", t_first,
                                 t_first + static_cast<double>(n - 1) * dt),
                     record.path);
  const std::size_t modes = starts.size();
  fitting::LsqProblem prob;
  prob.params = params_for(starts, o.max_zeta);
  prob.num_residuals = static_cast<int>(n);
  prob.observed = y;
  std::vector<double> m(n);
  prob.residuals = [&](const double* p, double* r) {
    for (std::size_t k = 0; k < modes; ++k)
      if (!(p[kParamsPerMode * k] > 0) || !(p[kParamsPerMode * k + 1] > 0)) return false;
    model(sched, modes, p, m);
    for (std::size_t i = 0; i < n; ++i) r[i] = y[i] - m[i];
    return true;
  };
  fitting::LsqOptions lo;
  lo.max_iterations = 100;
  lo.function_tolerance = 1e-12;
  lo.parameter_tolerance = 1e-12;
  lo.gradient_tolerance = 1e-14;
  lo.confidence = o.confidence;
  AxisResponseFit out;
  out.fit = fitting::solve_least_squares("axis_output_error", prob, lo);
  out.samples = n;
  out.pieces = sched.pieces_used;
  std::vector<double> p;
  for (const auto& q : out.fit.params) p.push_back(q.value);
  model(sched, modes, p.data(), m);
  std::vector<double> res(n);
  for (std::size_t i = 0; i < n; ++i) res[i] = y[i] - m[i];
  out.variance_inflation = fitting::residual_variance_factor(res);
  finish(out, modes, o.confidence);
  return out;
}

namespace {

/// Why the fit against the motion is not believed beside the spectrum's (empty: it is).
std::string disagreement(const std::vector<fitting::ModeEstimate>& spectrum,
                         const std::vector<fitting::ModeEstimate>& motion) {
  for (std::size_t k = 0; k < spectrum.size() && k < motion.size(); ++k) {
    const auto& s = spectrum[k];
    const auto& t = motion[k];
    const double f_hw = 0.5 * (s.freq_ci95_hi - s.freq_ci95_lo), z_hw = 0.5 * (s.zeta_ci95_hi - s.zeta_ci95_lo);
    if (std::abs(t.freq_hz - s.freq_hz) > kMotionFitAgreementHalfWidths * f_hw ||
        std::abs(t.zeta - s.zeta) > kMotionFitAgreementHalfWidths * z_hw)
      return fmt::format(
          "against the commanded motion f {:.4g} Hz, zeta {:.4g}; the spectrum's f {:.4g} Hz "
          "[{:.4g}, {:.4g}], zeta {:.4g} [{:.4g}, {:.4g}]",
          t.freq_hz, t.zeta, s.freq_hz, s.freq_ci95_lo, s.freq_ci95_hi, s.zeta, s.zeta_ci95_lo, s.zeta_ci95_hi);
  }
  return {};
}

}  // namespace

void refine_modes_with_motion(AxisModes& m, const AccelRecord& record, const std::vector<AccelPiece>& motion) {
  if (m.modes.empty()) return;
  std::vector<fitting::ModeStart> starts;
  for (const auto& e : m.modes) starts.push_back({e.freq_hz, e.zeta, 1.0});
  try {
    auto fit = fit_axis_response(record, motion, starts);
    if (const auto why = disagreement(m.modes, fit.modes); !why.empty()) {
      m.warnings.push_back("the fit against the commanded motion does not agree with the spectrum's (" + why +
                           "); the modes are the spectrum's. Is the motion on the samples' clock?");
      return;
    }
    const double strongest = m.peaks.front().freq_hz;
    m.modes = fit.modes;
    m.method = "output_error";
    m.time_fit_variance_inflation = fit.variance_inflation;
    m.time_fit = std::move(fit.fit);
    double best = 1e300;
    for (std::size_t k = 0; k < m.modes.size(); ++k)
      if (std::abs(m.modes[k].freq_hz - strongest) < best) {
        best = std::abs(m.modes[k].freq_hz - strongest);
        m.dominant = static_cast<int>(k);
      }
  } catch (const Error& e) {
    m.warnings.push_back("the fit against the commanded motion failed (" + e.message() +
                         "); the modes are the spectrum's");
  }
}

}  // namespace tunekit::ident
