#include "tunekit/ident/step_analysis.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/stats.hpp"

namespace tunekit::ident {
namespace {

using fitting::FitResult;
using fitting::StepRecord;

fitting::InputHold input_hold(StepInstant instant) {
  return instant == StepInstant::first_sample ? fitting::InputHold::from_stamp : fitting::InputHold::centred;
}

// One step's samples with the input that drives its model (step_fit_record) and the units.
StepRecord make_record(const StepAnalysis& a, std::span<const double> t, std::span<const double> u,
                       std::span<const double> y, const DetectedStep& s, const StepAnalysisOptions& o) {
  StepRecord r = step_fit_record(a, s, t, u, y);
  r.output_unit = o.output_unit;
  r.gain_unit = o.gain_unit;
  return r;
}

// First sample of the settled stretch of y in [begin, first): while the two halves of the
// pre-step window differ in mean by more than four standard errors (a warm-up from rest, or the
// previous response not yet settled), the earlier half is dropped. At least 20 samples stay.
std::size_t settled_begin(std::span<const double> y, std::size_t begin, std::size_t first) {
  auto stats = [&](std::size_t b, std::size_t e) {
    double m = 0;
    for (std::size_t i = b; i < e; ++i) m += y[i];
    m /= static_cast<double>(e - b);
    double v = 0;
    for (std::size_t i = b; i < e; ++i) v += (y[i] - m) * (y[i] - m);
    return std::pair{m, v / static_cast<double>(std::max<std::size_t>(e - b - 1, 1))};
  };
  while (first - begin >= 40) {
    const std::size_t mid = begin + (first - begin) / 2;
    const auto [m1, v1] = stats(begin, mid);
    const auto [m2, v2] = stats(mid, first);
    const double se = std::sqrt(v1 / static_cast<double>(mid - begin) + v2 / static_cast<double>(first - mid));
    if (std::abs(m1 - m2) <= 4 * se) break;
    begin = mid;
  }
  return begin;
}

// The pooled fit over every step, the operating points (the arrival levels) and their trends.
void finish(StepAnalysis& a, const std::vector<StepRecord>& recs, const StepAnalysisOptions& o) {
  std::vector<std::size_t> ok;
  for (std::size_t i = 0; i < a.steps.size(); ++i)
    if (a.steps[i].fit) ok.push_back(i);
  if (ok.empty()) {
    // Every step failed on its own: report the first reason (they usually share it).
    throw FitError(a.steps.front().error);
  }
  // Pooled over all steps (including ones that failed alone: shared tau can still be seen).
  try {
    a.pooled = fitting::fit_steps_pooled(recs, o.model, &*a.steps[ok.front()].fit);
  } catch (const FitError& e) {
    if (ok.size() == 1 && recs.size() == 1) throw;
    a.warnings.push_back("pooled fit over all steps failed: " + e.message());
  }
  if (a.pooled) {
    std::vector<const FitResult*> members;
    for (std::size_t i : ok) members.push_back(&*a.steps[i].fit);
    if (auto w = pooled_whiteness_warning(*a.pooled, members, "pooled fit over all steps"); !w.empty())
      a.warnings.push_back(std::move(w));
  }
  analyze_arrival_levels(a, recs, o);
}

// Standard deviation of the input's own noise: the median absolute difference of neighbouring
// samples scaled to a Gaussian's sigma (1.4826, the median absolute deviation of a unit normal's
// inverse, over sqrt 2, a difference holding two samples' noise). A commanded, piecewise-constant
// input, whose neighbours are mostly equal, has none.
double input_noise(std::span<const double> u) {
  std::vector<double> d;
  for (std::size_t i = 1; i < u.size(); ++i) d.push_back(std::abs(u[i] - u[i - 1]));
  return 1.4826 * fitting::median(std::move(d)) / std::sqrt(2.0);
}

struct Change {
  std::size_t first;            // first sample away from the old level
  std::size_t settled;          // first sample at the new level
  std::size_t level_begin = 0;  // first sample of the old level
};

// The input holds one level over [b, e): the means of its two halves differ by at most thr / 4.
// A piece of a ramp that drifts by thr has halves thr / 2 apart; noise, at most thr / 8
// (kStepNoiseSigmas), keeps them well within thr / 4 from a few samples on. A ramp slow enough to
// be cut into pieces (below thr / 4 a sample) leaves pieces of at least four samples: a shorter
// stretch is taken as a level.
bool holds_level(std::span<const double> u, std::size_t b, std::size_t e, double thr) {
  if (e < b + 4) return true;
  const std::size_t mid = b + (e - b) / 2;
  double m1 = 0, m2 = 0;
  for (std::size_t i = b; i < mid; ++i) m1 += u[i] / static_cast<double>(mid - b);
  for (std::size_t i = mid; i < e; ++i) m2 += u[i] / static_cast<double>(e - mid);
  return std::abs(m1 - m2) <= thr / 4;
}

// Change points: the input leaves the current level by more than thr; the transition ends when
// the sample-to-sample change falls below thr / 4.
std::vector<Change> raw_changes(std::span<const double> u, double thr) {
  std::vector<Change> changes;
  double ref = u[0];
  for (std::size_t i = 1; i < u.size(); ++i) {
    if (std::abs(u[i] - ref) > thr) {
      std::size_t k = i;
      while (k + 1 < u.size() && std::abs(u[k + 1] - u[k]) > thr / 4) ++k;
      changes.push_back({i, k, changes.empty() ? 0 : changes.back().settled});
      ref = u[k];
      i = k;
    }
  }
  return changes;
}

// The steps between levels the input holds: changes into a ramp are one transition, from the
// last level held to the next one; a ramp at the start or the end of the record is no step.
std::vector<Change> level_changes(std::span<const double> u, double thr) {
  const auto raw = raw_changes(u, thr);
  std::vector<Change> out;
  bool in_ramp = !raw.empty() && !holds_level(u, 0, raw.front().first, thr);
  for (std::size_t j = 0; j < raw.size(); ++j) {
    if (in_ramp && !out.empty()) out.back().settled = raw[j].settled;
    else if (!in_ramp) out.push_back(raw[j]);
    const std::size_t next = j + 1 < raw.size() ? raw[j + 1].first : u.size();
    in_ramp = !holds_level(u, raw[j].settled, next, thr);
  }
  if (in_ramp && !out.empty()) out.pop_back();
  return out;
}

}  // namespace

std::vector<DetectedStep> detect_steps(std::span<const double> t, std::span<const double> u,
                                       const StepDetectOptions& o) {
  const std::size_t n = u.size();
  if (t.size() != n) throw InputError("step detection: time and input have different lengths");
  if (n < 10) throw InputError(fmt::format("too few samples ({}) for a step analysis; at least 10 are needed", n));
  const auto [lo, hi] = std::minmax_element(u.begin(), u.end());
  const double range = *hi - *lo;
  if (!(range > 1e-12 * std::max(1.0, std::abs(*hi)))) throw InputError("no step found: the input column is constant");
  const double thr = std::max(o.min_step_fraction * range, kStepNoiseSigmas * input_noise(u));
  const auto changes = level_changes(u, thr);
  if (changes.empty()) throw InputError("no step found in the input column");
  auto level = [&](std::size_t b, std::size_t e) {  // median-free robust enough: mean of [b, e)
    double s = 0;
    for (std::size_t i = b; i < e; ++i) s += u[i];
    return e > b ? s / static_cast<double>(e - b) : u[std::min(b, n - 1)];
  };
  std::vector<DetectedStep> steps;
  for (std::size_t j = 0; j < changes.size(); ++j) {
    const std::size_t prev_end = changes[j].level_begin;
    const std::size_t next = j + 1 < changes.size() ? changes[j + 1].first : n;
    DetectedStep s;
    s.sample = changes[j].first;
    s.u_before = level(prev_end, changes[j].first);
    s.u_after = level(changes[j].settled, next);
    s.t_step_s = t[s.sample];  // the first sample that shows the new level
    if (o.instant == StepInstant::midpoint) {
      // Where the input crosses half-way between the levels, linear between samples.
      const double half = 0.5 * (s.u_before + s.u_after);
      for (std::size_t k = s.sample - 1; k < changes[j].settled && k + 1 < n; ++k) {
        const double a = u[k] - half, b = u[k + 1] - half;
        if (a * b <= 0 && u[k + 1] != u[k]) {
          s.t_step_s = t[k] + (half - u[k]) / (u[k + 1] - u[k]) * (t[k + 1] - t[k]);
          break;
        }
      }
    }
    const std::size_t pre = changes[j].first - prev_end;
    // The first level is treated like the others: a record usually starts from rest, and the
    // start of the first level is the machine warming up, not the steady state before the step.
    s.begin = changes[j].first - static_cast<std::size_t>(std::ceil(o.pre_fraction * pre));
    s.end = next;
    if (s.end - changes[j].first < 5) continue;  // too short to fit
    s.index = steps.size();
    steps.push_back(s);
  }
  if (steps.empty()) throw InputError("no step found that is followed by enough samples (at least 5) to fit");
  return steps;
}

fitting::StepRecord step_fit_record(const StepAnalysis& a, const DetectedStep& s, std::span<const double> t,
                                    std::span<const double> u, std::span<const double> y) {
  StepRecord r;
  const auto b = static_cast<std::ptrdiff_t>(s.begin);
  const auto e = static_cast<std::ptrdiff_t>(std::min(s.end, t.size()));
  r.t.assign(t.begin() + b, t.begin() + e);
  if (!y.empty()) r.y.assign(y.begin() + b, y.begin() + e);
  r.t_step = s.t_step_s;
  r.du = s.u_after - s.u_before;
  if (!a.input_track.empty()) {
    fitting::set_input_track(r, a.input_track.t, a.input_track.u);
    return r;
  }
  r.u.assign(u.begin() + b, u.begin() + e);
  r.u_hold = a.input_hold;
  if (fitting::logged_input_is_ideal_step(r)) r.u.clear();  // the same model, computed faster
  return r;
}

StepAnalysis analyze_steps(std::span<const double> t, std::span<const double> u, std::span<const double> y,
                           const StepAnalysisOptions& o, const FeedTrack* track) {
  if (y.size() != t.size()) throw InputError("time and output have different lengths");
  {
    const auto [lo, hi] = std::minmax_element(y.begin(), y.end());
    if (!(*hi > *lo)) throw InputError("the output column is constant; there is no response to fit");
  }
  StepAnalysis a;
  a.input_hold = input_hold(o.detect.instant);
  if (track != nullptr) a.input_track = *track;
  auto det = detect_steps(t, u, o.detect);
  std::vector<StepRecord> recs;
  for (auto& s : det) {
    s.begin = settled_begin(y, s.begin, s.sample);
    recs.push_back(make_record(a, t, u, y, s, o));
    StepFit sf;
    sf.step = s;
    try {
      sf.fit = fitting::fit_step(recs.back(), o.model);
    } catch (const Error& e) {
      if (e.code() == ExitCode::bad_input && det.size() == 1) throw;
      sf.error = e.message();
      a.warnings.push_back(fmt::format("step {} at t = {:.6g} s: {}", s.index, s.t_step_s, e.message()));
    }
    a.steps.push_back(std::move(sf));
  }
  finish(a, recs, o);
  return a;
}

StepAnalysis analyze_known_steps(const std::vector<KnownStep>& steps, const StepAnalysisOptions& o) {
  if (steps.empty()) throw InputError("no step records");
  StepAnalysis a;
  std::vector<StepRecord> recs;
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const auto& ks = steps[i];
    StepRecord r = ks.record;
    r.output_unit = o.output_unit;
    r.gain_unit = o.gain_unit;
    recs.push_back(r);
    StepFit sf;
    sf.step.index = i;
    sf.step.t_step_s = r.t_step;
    sf.step.u_before = ks.u_before;
    sf.step.u_after = ks.u_after;
    sf.step.begin = 0;
    sf.step.end = r.t.size();
    try {
      sf.fit = fitting::fit_step(r, o.model);
    } catch (const Error& e) {
      if (e.code() == ExitCode::bad_input || steps.size() == 1) throw;
      sf.error = e.message();
      a.warnings.push_back(fmt::format("step {} (u = {:.6g}): {}", i, sf.step.u_after, e.message()));
    }
    a.steps.push_back(std::move(sf));
  }
  finish(a, recs, o);
  return a;
}

FitResult fit_power_law(std::span<const double> x, std::span<const double> y, const std::string& yname,
                        const std::string& xunit, const std::string& yunit) {
  if (x.size() != y.size() || x.size() < 2) throw InputError("power law: at least two points are needed");
  std::vector<double> lx, ly;
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!(x[i] > 0) || !(y[i] > 0)) throw InputError("power law: values must be positive");
    lx.push_back(std::log(x[i]));
    ly.push_back(std::log(y[i]));
  }
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < lx.size(); ++i) {
    mx += lx[i];
    my += ly[i];
  }
  mx /= static_cast<double>(lx.size());
  my /= static_cast<double>(lx.size());
  double sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < lx.size(); ++i) {
    sxx += (lx[i] - mx) * (lx[i] - mx);
    sxy += (lx[i] - mx) * (ly[i] - my);
  }
  if (!(sxx > 0)) throw InputError("power law: all operating points are at the same input level");
  const double b0 = sxy / sxx;
  const double a0 = std::exp(my - b0 * mx);
  fitting::LsqProblem prob;
  const std::string aunit = yunit + "/(" + xunit + ")^b";
  prob.params = {{"a", aunit, a0, 1e-300}, {"b", "1", b0}};
  prob.num_residuals = static_cast<int>(lx.size());
  prob.observed = ly;
  prob.residuals_are_time_ordered = false;
  prob.residuals_and_jacobian = [lx, ly](const double* p, double* r, double* jac) {
    if (!(p[0] > 0)) return false;
    for (std::size_t i = 0; i < lx.size(); ++i) {
      r[i] = std::log(p[0]) + p[1] * lx[i] - ly[i];
      if (jac != nullptr) {
        jac[2 * i] = 1.0 / p[0];
        jac[2 * i + 1] = lx[i];
      }
    }
    return true;
  };
  fitting::LsqOptions opt;
  opt.compute_covariance = lx.size() > 2;
  auto f = fitting::solve_least_squares("power_law: " + yname + " = a * u^b (fitted in log space)", prob, opt);
  if (lx.size() == 2) f.warnings.push_back("two operating points: the power law passes through both; no uncertainty");
  return f;
}

nlohmann::json to_json(const StepAnalysis& a) {
  using nlohmann::json;
  json steps = json::array();
  for (const auto& s : a.steps) {
    json j;
    if (s.fit) j = fitting::to_json(*s.fit);
    else j["error"] = s.error;
    j["index"] = s.step.index;
    j["direction"] = s.step.rising() ? "rising" : "falling";
    j["t_step_s"] = s.step.t_step_s;
    j["fit_samples"] = {s.step.begin, s.step.end};  // [first, last + 1) sample of the record in this step's fit
    j["u_before"] = s.step.u_before;
    j["u_after"] = s.step.u_after;
    steps.push_back(j);
  }
  return {{"steps", steps},
          // What the step fits' model followed: the commanded feed track, or the logged input.
          {"steps_driven_by", a.input_track.empty() ? "logged input" : "feed track"},
          {"pooled", a.pooled ? fitting::to_json(*a.pooled) : json(nullptr)},
          {"operating_points", arrival_levels_json(a)},
          {"trend", level_trends_json(a)}};
}

}  // namespace tunekit::ident
