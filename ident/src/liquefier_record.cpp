// The whole-record liquefier model beside the per-step fits (liquefier_record.hpp).
#include "tunekit/ident/liquefier_record.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/first_order.hpp"
#include "tunekit/fitting/stats.hpp"

namespace tunekit::ident {
namespace {

/// P(X >= k) for X ~ Binomial(n, p).
double binomial_upper_tail(std::size_t n, std::size_t k, double p) {
  double tail = 0;
  for (std::size_t j = k; j <= n; ++j)
    tail += std::exp(std::lgamma(n + 1.0) - std::lgamma(j + 1.0) - std::lgamma(n - j + 1.0) +
                     static_cast<double>(j) * std::log(p) + static_cast<double>(n - j) * std::log1p(-p));
  return tail;
}

nlohmann::json number_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::json param_json(const fitting::Param& p) {
  return {{"value", number_or_null(p.value)},
          {"stderr", number_or_null(p.std_error)},
          {"ci95", {number_or_null(p.ci95_lo), number_or_null(p.ci95_hi)}},
          {"unit", p.unit},
          {"fixed", p.fixed},
          {"ci95_method", p.fixed ? std::string("fixed") : p.ci95_method}};
}

// A step from no feed: the liquefier filling from rest, through flows below every level, where a
// melt's viscosity levels off and the model's power law does not follow it. The model is fitted
// from the first step between two flows on; the filling is measured by its area instead
// (rest_volume.hpp).
constexpr double kRestInputShare = 0.02;
bool rises_from_rest(const StepFit& s) {
  return std::abs(s.step.u_before) <= kRestInputShare * std::abs(s.step.u_after);
}

/// The model's response over one step's window, fitted as the step was (following the same
/// input: the analysis' feed track, or the logged feed; step_fit_record).
void check_step(const WholeRecordModel& m, const fitting::LiquefierRecord& rec, const std::vector<double>& sim,
                const StepAnalysis& steps, std::size_t index, std::vector<StepModelCheck>& out) {
  const StepFit& s = steps.steps[index];
  if (!s.fit) return;
  const fitting::StepRecord r = step_fit_record(steps, s.step, rec.t, rec.u, sim);
  StepModelCheck c;
  c.step = index;
  c.u_after = s.step.u_after;
  c.tau_step_s = s.fit->value("tau_s");
  c.tau_step_stderr_s = s.fit->param("tau_s").std_error;
  try {
    fitting::LsqOptions lo;
    lo.compute_covariance = false;
    const auto f = fitting::fit_step(r, fitting::StepModel::fopdt, lo);
    c.tau_model_s = f.value("tau_s");
  } catch (const Error&) {
    return;  // the model's own response is not first order enough to fit: nothing to compare
  }
  // The model's uncertainty for that step: the relative standard error of its tau at the level
  // the step arrives at (the level that dominates the step's time constant).
  const double q = std::max(c.u_after, 1e-9);
  c.tau_model_stderr_s = c.tau_model_s * m.tau_stderr_at(q) / m.tau_at(q);
  const double comb = std::hypot(c.tau_step_stderr_s, c.tau_model_stderr_s);
  c.disagrees = std::isfinite(comb) && std::abs(c.tau_step_s - c.tau_model_s) > fitting::kZ95 * comb;
  out.push_back(c);
}

}  // namespace

bool step_checks_contradict_model(std::size_t checks, std::size_t disagreeing) {
  return disagreeing > 0 && binomial_upper_tail(checks, disagreeing, 0.05) < 0.01;
}

std::size_t disagreeing_checks(const std::vector<StepModelCheck>& checks) {
  return static_cast<std::size_t>(
      std::count_if(checks.begin(), checks.end(), [](const StepModelCheck& c) { return c.disagrees; }));
}

bool step_checks_contradict_model(const std::vector<StepModelCheck>& checks) {
  return step_checks_contradict_model(checks.size(), disagreeing_checks(checks));
}

fitting::LiquefierSensor sensor_for_output_unit(const std::string& unit) {
  for (const char* p : {"N", "kN", "Pa", "kPa", "MPa", "bar", "lbf", "g", "kg"})
    if (unit == p) return fitting::LiquefierSensor::pressure;
  return fitting::LiquefierSensor::flow;
}

bool output_is_flow(const std::string& unit) { return unit == "mm/s" || unit == "mm^3/s"; }

fitting::LiquefierSensor sensor_for_record(const StepAnalysis& steps, fitting::LiquefierSensor by_unit,
                                           std::string* basis) {
  if (basis != nullptr) *basis = "unit";
  const auto& tr = steps.level_trends;
  if (!tr.tau || !tr.K) return by_unit;
  const auto& bt = tr.tau->param("b");
  const auto& bk = tr.K->param("b");
  if (!(bt.std_error > 0) || !(bk.std_error > 0) || !(std::abs(bt.value) > 2 * bt.std_error)) return by_unit;
  // Standard errors of K's exponent from each sensor's prediction: g tau(u) (pressure), constant (flow).
  const double off_pressure = std::abs(bk.value - bt.value) / std::hypot(bk.std_error, bt.std_error);
  const double off_flow = std::abs(bk.value) / bk.std_error;
  if (basis != nullptr) *basis = "operating points";
  return off_pressure < off_flow ? fitting::LiquefierSensor::pressure : fitting::LiquefierSensor::flow;
}

double WholeRecordModel::tau_at(double q) const {
  return model.fit.value("tau_ref_s") * std::pow(q / model.reference_input, model.fit.value("b"));
}

namespace {

/// The standard error of ln tau_ref + L b (the fit's covariance, widened by its variance factor).
double log_stderr(const WholeRecordModel& m, double L) {
  const auto c = m.ln_tau_ref_b_covariance();
  return std::sqrt(std::max(c[0] + 2 * L * c[1] + L * L * c[2], 0.0));
}

/// The widest relative 95 % half-width of a quantity over the input range, given its relative
/// standard error at an input (the variance of a logarithm quadratic in ln q: widest at the ends).
template <class RelativeError>
double widest_over_range(const WholeRecordModel& m, RelativeError rel_se) {
  // Two-sided 95 % quantile of the normal distribution.
  if (!(m.input_min_positive > 0) || !(m.input_max >= m.input_min_positive)) return fitting::kNaN;
  double widest = 0;
  for (const double q : {m.input_min_positive, m.input_max}) {
    const double rel = fitting::kZ95 * rel_se(q);
    if (!std::isfinite(rel)) return fitting::kNaN;
    widest = std::max(widest, rel);
  }
  return widest;
}

}  // namespace

std::array<double, 3> WholeRecordModel::ln_tau_ref_b_covariance() const {
  const auto& f = model.fit;
  const auto& tau = f.param("tau_ref_s");
  const auto& b = f.param("b");
  std::array<double, 3> c{std::pow(tau.std_error / tau.value, 2), 0.0, 0.0};
  const std::size_t k = f.params.size();
  if (!b.fixed && f.covariance.size() == k * k) {
    c[1] = f.covariance[1] * model.variance_factor / tau.value;
    c[2] = b.std_error * b.std_error;
  }
  return c;
}

double WholeRecordModel::tau_stderr_at(double q) const {
  return tau_at(q) * log_stderr(*this, std::log(q / model.reference_input));
}

double WholeRecordModel::tau_relative_half_width_over_range() const {
  return widest_over_range(*this, [this](double q) { return tau_stderr_at(q) / tau_at(q); });
}

double WholeRecordModel::volume_at(double q) const { return fitting::liquefier_volume(model.params(), q); }

double WholeRecordModel::volume_stderr_at(double q) const {
  // ln V = ln tau_ref + b ln(q / q_ref) + ln q - ln(b + 1): d/db = ln(q / q_ref) - 1 / (b + 1).
  const double b = model.fit.value("b");
  const double L = std::log(q / model.reference_input) - (model.fit.param("b").fixed ? 0.0 : 1.0 / (b + 1));
  return volume_at(q) * log_stderr(*this, L);
}

double WholeRecordModel::volume_relative_half_width_over_range() const {
  return widest_over_range(*this, [this](double q) { return volume_stderr_at(q) / volume_at(q); });
}

namespace {

/// The record from `first` on, with the track when it matches (else a warning in m).
fitting::LiquefierRecord whole_record_input(std::span<const double> t, std::span<const double> u,
                                            std::span<const double> y, std::size_t first,
                                            const FeedTrackAlignment* track, WholeRecordModel& m) {
  fitting::LiquefierRecord rec;
  rec.t.assign(t.begin() + static_cast<std::ptrdiff_t>(first), t.end());
  rec.u.assign(u.begin() + static_cast<std::ptrdiff_t>(first), u.end());
  rec.y.assign(y.begin() + static_cast<std::ptrdiff_t>(first), y.end());
  if (track == nullptr) return rec;
  m.track_alignment = *track;
  if (m.track_alignment->matches) {
    m.input_track = m.track_alignment->aligned;
    rec.input_t = m.input_track.t;
    rec.input_u = m.input_track.u;
  } else {
    m.warnings.push_back(fmt::format(
        "the feed track does not match the record's feed (rms {:.3g} against at most {:.3g}, {:.0f} % of the largest "
        "feed): the model is driven by the logged feed",
        m.track_alignment->rms_mismatch, kFeedTrackMismatch * m.track_alignment->feed_scale, 100 * kFeedTrackMismatch));
  }
  return rec;
}

}  // namespace

std::vector<double> whole_record_output(const WholeRecordModel& m, const std::vector<double>& t,
                                        const std::vector<double>& u) {
  std::vector<double> out(t.size(), fitting::kNaN);
  if (m.first_sample >= t.size()) return out;
  const std::vector<double> tt(t.begin() + static_cast<std::ptrdiff_t>(m.first_sample), t.end());
  const std::vector<double> uu(u.begin() + static_cast<std::ptrdiff_t>(m.first_sample), u.end());
  const auto sim = m.input_track.empty() ? fitting::simulate_liquefier(tt, uu, m.model.params(), m.model.sensor)
                                         : fitting::simulate_liquefier(tt, m.input_track.t, m.input_track.u,
                                                                       m.model.params(), m.model.sensor);
  std::copy(sim.begin(), sim.end(), out.begin() + static_cast<std::ptrdiff_t>(m.first_sample));
  return out;
}

WholeRecordModel analyze_whole_record(std::span<const double> t, std::span<const double> u, std::span<const double> y,
                                      fitting::LiquefierSensor sensor, const std::string& input_unit,
                                      const std::string& output_unit, const StepAnalysis* steps,
                                      const fitting::LiquefierFitOptions& options, const FeedTrackAlignment* track) {
  WholeRecordModel m;
  m.input_unit = input_unit;
  m.output_unit = output_unit;
  if (steps != nullptr && !steps->steps.empty()) {
    std::size_t first = t.size();
    for (const auto& s : steps->steps)
      if (!rises_from_rest(s)) first = std::min(first, s.step.begin);
    m.first_sample = first < t.size() ? first : 0;
  }
  fitting::LiquefierRecord rec = whole_record_input(t, u, y, m.first_sample, track, m);
  rec.sensor = sensor;
  rec.input_unit = input_unit;
  rec.output_unit = output_unit;
  m.model = fitting::fit_liquefier_model(rec, options);
  m.input_max = *std::max_element(rec.u.begin(), rec.u.end());
  for (double v : rec.u)
    if (v > 0 && !(v >= m.input_min_positive)) m.input_min_positive = v;
  const auto fit_warnings = m.model.fit.warnings;
  m.warnings.insert(m.warnings.end(), fit_warnings.begin(), fit_warnings.end());
  // Correlated residuals are not a warning: the intervals are already widened for them, and
  // to_json reports the factor (variance_factor) beside the Ljung-Box test.
  if (steps != nullptr) {
    const std::vector<double> tv(t.begin(), t.end()), uv(u.begin(), u.end());
    const std::vector<double> sim = whole_record_output(m, tv, uv);
    fitting::LiquefierRecord full;
    full.t = tv;
    full.u = uv;
    for (std::size_t i = 0; i < steps->steps.size(); ++i)
      if (steps->steps[i].step.begin >= m.first_sample) check_step(m, full, sim, *steps, i, m.checks);
    const std::size_t bad = disagreeing_checks(m.checks);
    if (step_checks_contradict_model(m.checks.size(), bad))
      m.warnings.push_back(fmt::format(
          "{} of {} step fits disagree with the whole-record model's prediction for that step beyond their combined "
          "uncertainty (flagged in whole_record.step_checks)",
          bad, m.checks.size()));
  }
  m.rest_volume = measure_rest_volume(t, y, m, &m.rest_volume_why);
  return m;
}

namespace {

/// How the model was driven: by the feed track (its offset and how well it matched) or the log.
nlohmann::json track_json(const WholeRecordModel& m) {
  if (!m.track_alignment) return {{"used", false}, {"why", "no feed track given: driven by the logged feed"}};
  const auto& a = *m.track_alignment;
  return {{"used", !m.input_track.empty()},
          {"offset_s", number_or_null(a.offset_s)},
          {"rms_mismatch", number_or_null(a.rms_mismatch)},
          {"breakpoints", a.aligned.t.size()}};
}

}  // namespace

namespace {

/// {var_ln_tau_ref, cov_ln_tau_ref_b, var_b}: what a design from the model needs for the delta method.
nlohmann::json ln_covariance_json(const WholeRecordModel& m) {
  const auto c = m.ln_tau_ref_b_covariance();
  return {{"var_ln_tau_ref", number_or_null(c[0])},
          {"cov_ln_tau_ref_b", number_or_null(c[1])},
          {"var_b", number_or_null(c[2])}};
}

}  // namespace

nlohmann::json to_json(const WholeRecordModel& m) {
  const auto& f = m.model.fit;
  nlohmann::json checks = nlohmann::json::array();
  for (const auto& c : m.checks)
    checks.push_back({{"step", c.step},
                      {"u_after", number_or_null(c.u_after)},
                      {"tau_step_s", number_or_null(c.tau_step_s)},
                      {"tau_step_stderr_s", number_or_null(c.tau_step_stderr_s)},
                      {"tau_model_s", number_or_null(c.tau_model_s)},
                      {"tau_model_stderr_s", number_or_null(c.tau_model_stderr_s)},
                      {"disagrees", c.disagrees}});
  return {{"model", fitting::to_json(f)},
          {"form", "dV/dt = u(t - theta) - q, V(q) = a q^(b+1)/(b+1), tau(q) = a q^b"},
          {"sensor", fitting::to_string(m.model.sensor)},
          {"sensor_chosen_by", m.sensor_basis},
          {"sensor_form", m.model.sensor == fitting::LiquefierSensor::flow ? "y = g q + c" : "y = g V + c"},
          {"reference_input", number_or_null(m.model.reference_input)},
          {"input_unit", m.input_unit},
          {"input_range", {number_or_null(m.input_min_positive), number_or_null(m.input_max)}},
          {"tau_rel_ci95_over_range", number_or_null(m.tau_relative_half_width_over_range())},
          {"volume_rel_ci95_over_range", number_or_null(m.volume_relative_half_width_over_range())},
          {"ln_tau_ref_b_covariance", ln_covariance_json(m)},
          {"rest_volume", to_json(m.rest_volume, m.rest_volume_why)},
          {"a", param_json(f.derived.front())},
          {"b", param_json(f.param("b"))},
          {"theta_s", param_json(f.param("theta_s"))},
          {"tau_ref_s", param_json(f.param("tau_ref_s"))},
          {"linear_chosen", m.model.linear_chosen},
          {"b_nonlinear", param_json(m.model.nonlinear.param("b"))},
          {"test",
           {{"name", "F-test of b = 0 at 5 % (the linear model is kept when b's 95 % profile interval holds 0)"},
            {"statistic", number_or_null(m.model.f_statistic)},
            {"threshold", number_or_null(m.model.f_threshold)}}},
          {"variance_factor", number_or_null(m.model.variance_factor)},
          {"substeps", m.model.substeps},
          {"step_checks", checks},
          {"fitted_from_sample", m.first_sample},
          {"input_track", track_json(m)},
          {"warnings", m.warnings}};
}

}  // namespace tunekit::ident
