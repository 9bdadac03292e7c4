#include "tunekit/ident/step_analysis.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::ident {
namespace {

using fitting::FitResult;
using fitting::StepRecord;

StepRecord make_record(std::span<const double> t, std::span<const double> y, const DetectedStep& s,
                       const StepAnalysisOptions& o) {
  StepRecord r;
  r.t.assign(t.begin() + static_cast<std::ptrdiff_t>(s.begin), t.begin() + static_cast<std::ptrdiff_t>(s.end));
  r.y.assign(y.begin() + static_cast<std::ptrdiff_t>(s.begin), y.begin() + static_cast<std::ptrdiff_t>(s.end));
  r.t_step = s.t_step_s;
  r.du = s.u_after - s.u_before;
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

void group_by_operating_point(StepAnalysis& a, const std::vector<StepRecord>& recs, const std::vector<std::size_t>& ok,
                              const StepAnalysisOptions& o);
void fit_operating_point_trend(StepAnalysis& a);

// The pooled fit over every step, the arrival levels, the operating points and their trends.
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
  if (o.operating_points_by_arrival) {
    for (const auto& l : a.arrival_levels) a.operating_points.push_back({l.u, static_cast<int>(l.steps.size()), l.fit});
  } else {
    group_by_operating_point(a, recs, ok, o);
  }
  fit_operating_point_trend(a);
}

// Groups steps by operating point (levels within 2 % of the largest level are one point) and
// fits each group pooled.
void group_by_operating_point(StepAnalysis& a, const std::vector<StepRecord>& recs, const std::vector<std::size_t>& ok,
                              const StepAnalysisOptions& o) {
  double umax = 0;
  for (const auto& s : a.steps) umax = std::max(umax, std::abs(s.step.operating_point()));
  const double tol = 0.02 * std::max(umax, 1e-300);
  std::vector<std::pair<double, std::vector<std::size_t>>> groups;
  for (std::size_t i : ok) {
    const double u = a.steps[i].step.operating_point();
    auto it = std::find_if(groups.begin(), groups.end(), [&](const auto& g) { return std::abs(g.first - u) <= tol; });
    if (it == groups.end()) groups.push_back({u, {i}});
    else it->second.push_back(i);
  }
  std::sort(groups.begin(), groups.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  for (const auto& [u, idx] : groups) {
    OperatingPoint op;
    op.u = u;
    op.n_steps = static_cast<int>(idx.size());
    if (idx.size() == 1) {
      op.fit = *a.steps[idx.front()].fit;
    } else {
      std::vector<StepRecord> sub;
      for (std::size_t i : idx) sub.push_back(recs[i]);
      try {
        op.fit = fitting::fit_steps_pooled(sub, o.model, &*a.steps[idx.front()].fit);
      } catch (const FitError& e) {
        a.warnings.push_back(fmt::format("operating point u = {:.6g}: {}", u, e.message()));
        continue;
      }
    }
    if (idx.size() > 1) {
      std::vector<const FitResult*> members;
      for (std::size_t i : idx) members.push_back(&*a.steps[i].fit);
      if (auto w = pooled_whiteness_warning(op.fit, members, fmt::format("operating point u = {:.6g}", u)); !w.empty())
        a.warnings.push_back(std::move(w));
    }
    a.operating_points.push_back(std::move(op));
  }
}

// The power-law trends of the operating points.
void fit_operating_point_trend(StepAnalysis& a) {
  const std::string& unit = a.input_unit;
  const std::string gain_unit = a.operating_points.empty() ? "1" : a.operating_points.front().fit.param("K").unit;
  std::vector<double> us, taus, ks;
  for (const auto& op : a.operating_points) {
    if (op.u > 0 && op.fit.value("tau_s") > 0 && op.fit.value("K") > 0) {
      us.push_back(op.u);
      taus.push_back(op.fit.value("tau_s"));
      ks.push_back(op.fit.value("K"));
    }
  }
  if (us.size() >= 2) {
    try {
      a.trend_tau = fit_power_law(us, taus, "tau_s", unit, "s");
      a.trend_K = fit_power_law(us, ks, "K", unit, gain_unit);
    } catch (const Error& e) {
      a.warnings.push_back("trend: " + e.message());
      a.trend_tau.reset();
      a.trend_K.reset();
    }
  } else if (a.operating_points.size() >= 2) {
    a.warnings.push_back("trend: fewer than two operating points with positive u, K and tau; no power law fitted");
  }
}

}  // namespace

StepInstant parse_step_instant(const std::string& name) {
  if (name == "midpoint") return StepInstant::midpoint;
  if (name == "first") return StepInstant::first_sample;
  throw InputError("unknown step instant '" + name + "' (expected midpoint or first)");
}

std::vector<DetectedStep> detect_steps(std::span<const double> t, std::span<const double> u,
                                       const StepDetectOptions& o) {
  const std::size_t n = u.size();
  if (t.size() != n) throw InputError("step detection: time and input have different lengths");
  if (n < 10) throw InputError(fmt::format("too few samples ({}) for a step analysis; at least 10 are needed", n));
  const auto [lo, hi] = std::minmax_element(u.begin(), u.end());
  const double range = *hi - *lo;
  if (!(range > 1e-12 * std::max(1.0, std::abs(*hi)))) throw InputError("no step found: the input column is constant");
  const double thr = o.min_step_fraction * range;
  // Change points: the input leaves the current level by more than thr; the transition ends when
  // the sample-to-sample change falls below thr / 4.
  struct Change {
    std::size_t first;    // first sample away from the old level
    std::size_t settled;  // first sample at the new level
  };
  std::vector<Change> changes;
  double ref = u[0];
  for (std::size_t i = 1; i < n; ++i) {
    if (std::abs(u[i] - ref) > thr) {
      std::size_t k = i;
      while (k + 1 < n && std::abs(u[k + 1] - u[k]) > thr / 4) ++k;
      changes.push_back({i, k});
      ref = u[k];
      i = k;
    }
  }
  if (changes.empty()) throw InputError("no step found in the input column");
  auto level = [&](std::size_t b, std::size_t e) {  // median-free robust enough: mean of [b, e)
    double s = 0;
    for (std::size_t i = b; i < e; ++i) s += u[i];
    return e > b ? s / static_cast<double>(e - b) : u[std::min(b, n - 1)];
  };
  std::vector<DetectedStep> steps;
  for (std::size_t j = 0; j < changes.size(); ++j) {
    const std::size_t prev_end = j == 0 ? 0 : changes[j - 1].settled;
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

StepAnalysis analyze_steps(std::span<const double> t, std::span<const double> u, std::span<const double> y,
                           const StepAnalysisOptions& o) {
  if (y.size() != t.size()) throw InputError("time and output have different lengths");
  {
    const auto [lo, hi] = std::minmax_element(y.begin(), y.end());
    if (!(*hi > *lo)) throw InputError("the output column is constant; there is no response to fit");
  }
  StepAnalysis a;
  auto det = detect_steps(t, u, o.detect);
  std::vector<StepRecord> recs;
  for (auto& s : det) {
    s.begin = settled_begin(y, s.begin, s.sample);
    recs.push_back(make_record(t, y, s, o));
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
      a.warnings.push_back(fmt::format("step {} (u = {:.6g}): {}", i, sf.step.operating_point(), e.message()));
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
    j["operating_point"] = s.step.operating_point();
    steps.push_back(j);
  }
  json ops = json::array();
  for (const auto& op : a.operating_points) {
    json stderr_j;
    for (const char* n : {"K", "tau_s", "theta_s"}) stderr_j[n] = op.fit.param(n).std_error;
    ops.push_back({{"u", op.u},
                   {"n_steps", op.n_steps},
                   {"K", op.fit.value("K")},
                   {"tau_s", op.fit.value("tau_s")},
                   {"theta_s", op.fit.value("theta_s")},
                   {"stderr", stderr_j},
                   {"fit", fitting::to_json(op.fit)}});
  }
  json out{
      {"steps", steps}, {"pooled", a.pooled ? fitting::to_json(*a.pooled) : json(nullptr)}, {"operating_points", ops}};
  json trend = json::object();
  if (a.trend_tau) trend["tau_s"] = fitting::to_json(*a.trend_tau);
  if (a.trend_K) trend["K"] = fitting::to_json(*a.trend_K);
  out["trend"] = trend;
  out["flow_levels"] = arrival_levels_json(a);
  out["flow_trend"] = level_trends_json(a);
  return out;
}

}  // namespace tunekit::ident
