#include "tunekit/fitting/rheology_fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include <cstdarg>
#include <cstdio>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/profile_likelihood.hpp"
#include "tunekit/fitting/stats.hpp"
#include "rheology_fit_detail.hpp"

namespace tunekit::fitting {
namespace rheology_detail {

std::string strf(const char* f, ...) {
  char buf[1024];
  va_list ap;
  va_start(ap, f);
  std::vsnprintf(buf, sizeof buf, f, ap);
  va_end(ap);
  return buf;
}

DataStats stats_of(const RheologyData& d) {
  DataStats s;
  for (double v : d.viscosity_Pa_s) s.eta_min = std::min(s.eta_min, v), s.eta_max = std::max(s.eta_max, v);
  s.eta_med = median(d.viscosity_Pa_s);
  s.g_med = median(d.shear_rate_1_s);
  s.levels = d.temperature_levels_K();
  return s;
}

double default_T_ref(const std::vector<double>& levels) {
  std::vector<double> l = levels;
  return l[(l.size() - 1) / 2];
}

void validate_data(const RheologyData& d) {
  const std::size_t n = d.size();
  if (n == 0) throw InputError("no rheology data points");
  if (d.viscosity_Pa_s.size() != n || d.temperature_K.size() != n ||
      (!d.pressure_Pa.empty() && d.pressure_Pa.size() != n) || (!d.weight.empty() && d.weight.size() != n))
    throw InputError("rheology data columns differ in length");
  for (std::size_t i = 0; i < n; ++i) {
    if (!(d.shear_rate_1_s[i] > 0))
      throw InputError(strf("point %zu: the shear rate must be positive (is %g)", i + 1, d.shear_rate_1_s[i]));
    if (!(d.viscosity_Pa_s[i] > 0))
      throw InputError(strf("point %zu: the viscosity must be positive (is %g)", i + 1, d.viscosity_Pa_s[i]));
    if (!(d.temperature_K[i] > 0))
      throw InputError(
          strf("point %zu: the temperature must be positive in kelvin (is %g)", i + 1, d.temperature_K[i]));
    if (!d.weight.empty() && !(d.weight[i] > 0)) throw InputError(strf("point %zu: weights must be positive", i + 1));
  }
}

void finish_params(FitResult& fit, const std::vector<PSpec>& specs) {
  fit.warnings.erase(
      std::remove_if(fit.warnings.begin(), fit.warnings.end(),
                     [](const std::string& w) { return w.find("ended on its bound") != std::string::npos; }),
      fit.warnings.end());
  for (std::size_t j = 0; j < specs.size(); ++j) {
    auto& p = fit.params[j];
    const auto& s = specs[j];
    const double raw = p.value;
    if (s.log) {
      p.value = std::exp(raw);
      p.std_error = p.value * p.std_error;
      p.ci95_lo = std::exp(p.ci95_lo);
      p.ci95_hi = std::exp(p.ci95_hi);
    }
    // The parameter cannot leave its search box, so neither can its interval; an interval that
    // would (or that overflows: exp of a wide interval in ln) ends at the box and says so.
    if (!s.fixed && std::isfinite(p.std_error)) {
      const bool lo_cut = !(p.ci95_lo >= s.lo) && std::isfinite(s.lo);
      const bool hi_cut = !(p.ci95_hi <= s.hi) && std::isfinite(s.hi);
      if (lo_cut) p.ci95_lo = s.lo;
      if (hi_cut) p.ci95_hi = s.hi;
      if (lo_cut || hi_cut)
        fit.warnings.push_back(
            strf("the 95 %% interval of %s reaches its search bound (%.6g %s); the data do not bound it",
                 s.name.c_str(), lo_cut ? s.lo : s.hi, s.unit.c_str()));
    }
    if (!s.fixed) {
      const double lo = s.log ? std::log(s.lo) : s.lo, hi = s.log ? std::log(s.hi) : s.hi;
      if (raw <= lo + 1e-9 * std::max(1.0, std::abs(lo)) || raw >= hi - 1e-9 * std::max(1.0, std::abs(hi)))
        fit.warnings.push_back(strf("%s ended on its bound (%.6g %s); the data do not determine it well",
                                    s.name.c_str(), p.value, s.unit.c_str()));
    }
  }
}

int free_count(const std::vector<PSpec>& specs) {
  return static_cast<int>(std::count_if(specs.begin(), specs.end(), [](const PSpec& s) { return !s.fixed; }));
}

}  // namespace rheology_detail

namespace {

using rheology_detail::DataStats;
using rheology_detail::default_T_ref;
using rheology_detail::finish_params;
using rheology_detail::free_count;
using rheology_detail::kInf;
using rheology_detail::LnViscosity;
using rheology_detail::PSpec;
using rheology_detail::stats_of;
using rheology_detail::strf;
using rheology_detail::validate_data;
using rheology_detail::viscosity_problem;
using rheology_detail::ViscosityProblem;
using rheology_detail::ViscosityRows;

// |correlation| above which Cross-WLF's temperature parameters are reported as a ridge.
constexpr double kRidgeCorrelation = 0.99;

// Viscosity from public values in the order of `names` (model names, shift names, T_ref_K).
struct Evaluator {
  Evaluator(ViscosityModel m, TemperatureShift s) : model(m), shift(s), k(viscosity_param_names(m).size()) {}
  ViscosityModel model;
  TemperatureShift shift;
  std::size_t k;  // where the shift's values start (the model's parameter count)
  double operator()(const double* v, double g, double T, double p) const {
    double aT = 1.0;
    if (shift == TemperatureShift::arrhenius) aT = arrhenius_shift(T, v[k], v[k + 1]);
    else if (shift == TemperatureShift::wlf) aT = wlf_shift(T, v[k], v[k + 1], v[k + 2]);
    switch (model) {
      case ViscosityModel::newtonian: return v[0] * aT;
      case ViscosityModel::power_law: return power_law_viscosity(v[0] * aT, v[1], g);
      case ViscosityModel::cross: return cross_viscosity(v[0] * aT, v[1], v[2], g);
      case ViscosityModel::cross_wlf: return cross_wlf_viscosity({v[0], v[1], v[2], v[3], v[4], v[5], v[6]}, g, T, p);
      case ViscosityModel::carreau_yasuda:
        return carreau_yasuda_viscosity(v[0] * aT, v[1] * aT, v[2] * aT, v[3], v[4], g);
    }
    return kNaN;
  }
};

std::vector<PSpec> default_specs(const ViscosityFitOptions& o, const DataStats& s, double T_ref) {
  std::vector<PSpec> p;
  const double e_lo = s.eta_min / 10, e_hi = s.eta_max * 1e4;
  const double T_min = s.levels.front();
  switch (o.model) {
    case ViscosityModel::newtonian:
      p.push_back({"eta0_Pa_s", "Pa.s", true, s.eta_min / 10, s.eta_max * 10, s.eta_med});
      break;
    case ViscosityModel::power_law:
      p.push_back({"K_Pa_s_n", "Pa.s^n", true, 1e-3, 1e10, s.eta_med * std::sqrt(s.g_med)});
      p.push_back({"n", "1", false, 0.01, 1.5, 0.5});
      break;
    case ViscosityModel::cross:
      p.push_back({"eta0_Pa_s", "Pa.s", true, e_lo, e_hi, s.eta_max});
      p.push_back({"tau_star_Pa", "Pa", true, 1, 1e8, 1e5});
      p.push_back({"n", "1", false, 0.01, 1.0, 0.4});
      break;
    case ViscosityModel::carreau_yasuda:
      p.push_back({"eta0_Pa_s", "Pa.s", true, e_lo, e_hi, s.eta_max});
      p.push_back({"eta_inf_Pa_s", "Pa.s", false, 0, s.eta_min, 0, true});
      p.push_back({"lambda_s", "s", true, 1e-7, 1e4, 0.01});
      p.push_back({"a", "1", false, 0.1, 5, 2});
      p.push_back({"n", "1", false, 0.01, 1.0, 0.4});
      break;
    case ViscosityModel::cross_wlf:
      p.push_back({"n", "1", false, 0.01, 1.0, 0.4});
      p.push_back({"tau_star_Pa", "Pa", true, 1, 1e8, 1e5});
      p.push_back({"D1_Pa_s", "Pa.s", true, 1e3, 1e50, 1e12});
      p.push_back({"D2_K", "K", false, 100, T_min - 5, std::max(100.0, T_min - 200)});
      p.push_back({"D3_K_per_Pa", "K/Pa", false, 0, 1e-6, 0, true});
      p.push_back({"A1", "1", false, 1, 100, 30});
      p.push_back({"A2_K", "K", false, 1, 500, 51.6, true});
      break;
  }
  if (o.model != ViscosityModel::cross_wlf) {
    if (o.shift == TemperatureShift::arrhenius) {
      p.push_back({"Ea_J_per_mol", "J/mol", false, 1e3, 1e6, 1e5});
    } else if (o.shift == TemperatureShift::wlf) {
      p.push_back({"C1", "1", false, 0.5, 100, 17});
      p.push_back({"C2_K", "K", false, std::max(1.0, T_ref - T_min + 1), 2000, std::max(100.0, T_ref - T_min + 50)});
    }
    if (o.shift != TemperatureShift::none) p.push_back({"T_ref_K", "K", false, -kInf, kInf, T_ref, true});
  }
  for (auto& ps : p) {
    if (o.fixed.count(ps.name)) {
      ps.fixed = true;
      ps.start = o.fixed.at(ps.name);
    }
    if (std::find(o.free.begin(), o.free.end(), ps.name) != o.free.end() && ps.name != "T_ref_K") ps.fixed = false;
    ps.start = std::clamp(ps.start, ps.lo, ps.hi);
    if (ps.fixed) ps.lo = -kInf, ps.hi = kInf;
  }
  for (const auto& [k, v] : o.fixed) {
    if (std::none_of(p.begin(), p.end(), [&key = k](const PSpec& ps) { return ps.name == key; }))
      throw InputError(strf("--fix %s: %s has no parameter of that name", k.c_str(),
                            ViscositySpec{o.model, o.shift, {}}.name().c_str()));
    (void)v;
  }
  for (const auto& k : o.free)
    if (std::none_of(p.begin(), p.end(), [&](const PSpec& ps) { return ps.name == k; }))
      throw InputError(strf("--free %s: %s has no parameter of that name", k.c_str(),
                            ViscositySpec{o.model, o.shift, {}}.name().c_str()));
  return p;
}

}  // namespace

std::vector<double> RheologyData::temperature_levels_K() const {
  std::vector<double> t = temperature_K;
  std::sort(t.begin(), t.end());
  std::vector<double> levels;
  for (double v : t)
    if (levels.empty() || v - levels.back() > 0.05) levels.push_back(v);
  return levels;
}

namespace {

// The data's temperatures must suit the model: one without a shift, or as many as its
// temperature parameters. InputError naming the model otherwise.
void check_temperatures(const ViscosityFitOptions& o, const DataStats& st, const std::vector<PSpec>& specs,
                        const std::string& name, std::size_t points) {
  const bool temp_model = o.model == ViscosityModel::cross_wlf || o.shift != TemperatureShift::none;
  if (!temp_model && st.levels.size() > 1)
    throw InputError(
        strf("%s: the data hold %zu temperatures (%.2f..%.2f K); a model without a temperature "
             "shift needs data at one temperature (choose a shift: arrhenius or wlf)",
             name.c_str(), st.levels.size(), st.levels.front(), st.levels.back()));
  if (temp_model) {
    // Parameters of the temperature dependence; the data need at least that many temperatures.
    int t_params = 0;
    for (const auto& s : specs) {
      if (s.fixed) continue;
      if (s.name == "D1_Pa_s" || s.name == "D2_K" || s.name == "A1" || s.name == "A2_K" || s.name == "Ea_J_per_mol" ||
          s.name == "C1" || s.name == "C2_K")
        ++t_params;
    }
    if (o.model != ViscosityModel::cross_wlf) ++t_params;  // the reference eta0 / K
    if (st.levels.size() < 2)
      throw InputError(
          strf("%s is temperature dependent but the data hold a single temperature (%.2f K); "
               "measure at two or more temperatures or fit a model without a shift",
               name.c_str(), st.levels.front()));
    if (static_cast<int>(st.levels.size()) < t_params)
      throw InputError(
          strf("%s: %d temperature parameters need data at %d or more temperatures, the data hold %zu; "
               "hold one with --fix (e.g. --fix D2_K=<glass transition in K>)",
               name.c_str(), t_params, t_params, st.levels.size()));
  }
  const int k = free_count(specs);
  if (static_cast<int>(points) <= k)
    throw InputError(
        strf("%s: %zu data points for %d free parameters; need more points than parameters", name.c_str(), points, k));
}

// What the data determine even when the temperature parameters are not separately
// identifiable: derived viscosities with delta-method intervals (FitResult::derived).
void add_derived_viscosities(FitResult& fit, const RheologyData& data, const ViscosityFitOptions& o,
                             const ViscosityProblem& vp) {
  const auto& specs = vp.specs;
  const auto& st = vp.stats;
  const std::size_t n = data.size();
  // At each measured temperature the zero-shear viscosity (not for the power law, which has
  // none) and the viscosity at the median measured shear rate: smooth functions of the
  // parameters, so their linearised (delta-method) intervals on ln hold.
  if (st.levels.size() < 2 || fit.covariance.size() != specs.size() * specs.size()) return;
  const Evaluator ev{o.model, o.shift};
  std::vector<bool> is_log;
  for (const auto& s : specs) is_log.push_back(s.log);
  const std::size_t np = specs.size();
  std::vector<double> x(np);
  for (std::size_t j = 0; j < np; ++j) x[j] = fit.params[j].value;
  double p_mean = 0;
  for (double v : data.pressure_Pa) p_mean += v / static_cast<double>(data.pressure_Pa.size());
  auto ln_eta = [&](const std::vector<double>& q, double g, double T) {
    double v[12];
    for (std::size_t j = 0; j < np; ++j) v[j] = is_log[j] ? std::exp(q[j]) : q[j];
    return std::log(ev(v, g, T, p_mean));
  };
  const int dof = fit.diagnostics.num_observations - fit.diagnostics.num_parameters;
  const double tq = t_multiplier(0.95, dof);
  auto add = [&](const std::string& qname, double g, double T) {
    std::vector<double> grad(np, 0.0);
    for (std::size_t j = 0; j < np; ++j) {
      if (fit.params[j].fixed) continue;
      const double h = 1e-6 * std::max(1.0, std::abs(x[j]));
      auto xp = x, xm = x;
      xp[j] += h;
      xm[j] -= h;
      grad[j] = (ln_eta(xp, g, T) - ln_eta(xm, g, T)) / (2 * h);
    }
    double var = 0;
    for (std::size_t a = 0; a < np; ++a)
      for (std::size_t b = 0; b < np; ++b) var += grad[a] * fit.covariance[a * np + b] * grad[b];
    const double l = ln_eta(x, g, T), se = std::sqrt(std::max(var, 0.0));
    Param q;
    q.name = qname;
    q.unit = "Pa.s";
    q.value = std::exp(l);
    q.std_error = q.value * se;
    q.ci95_lo = std::exp(l - tq * se);
    q.ci95_hi = std::exp(l + tq * se);
    q.ci95_method = "wald";
    if (std::isfinite(q.value) && std::isfinite(q.std_error) && std::isfinite(q.ci95_lo) && std::isfinite(q.ci95_hi))
      fit.derived.push_back(q);
  };
  for (double T : st.levels) {
    std::vector<double> gs;
    for (std::size_t i = 0; i < n; ++i)
      if (std::abs(data.temperature_K[i] - T) <= 0.05 + 1e-9) gs.push_back(data.shear_rate_1_s[i]);
    std::sort(gs.begin(), gs.end());
    const double g_med = gs[(gs.size() - 1) / 2];
    if (o.model != ViscosityModel::power_law) add(strf("eta0_Pa_s_at_%.2fK", T), 1e-30, T);
    add(strf("eta_Pa_s_at_%.2fK_%.4g_per_s", T, g_med), g_med, T);
  }
}

// The WLF ridge warning of Cross-WLF (D1, D2, A1 trade off with few temperatures).
void add_ridge_warning(FitResult& fit, const std::vector<PSpec>& specs, const DataStats& st) {
  std::vector<std::size_t> t_idx;
  for (std::size_t j = 0; j < specs.size(); ++j)
    if (!specs[j].fixed &&
        (specs[j].name == "D1_Pa_s" || specs[j].name == "D2_K" || specs[j].name == "A1" || specs[j].name == "A2_K"))
      t_idx.push_back(j);
  double max_r = 0;
  for (std::size_t a = 0; a < t_idx.size(); ++a)
    for (std::size_t b = a + 1; b < t_idx.size(); ++b)
      max_r = std::max(max_r, std::abs(correlation(fit, t_idx[a], t_idx[b])));
  const bool d2_free = std::any_of(t_idx.begin(), t_idx.end(), [&](std::size_t j) { return specs[j].name == "D2_K"; });
  if (d2_free && t_idx.size() >= 2 && max_r > kRidgeCorrelation) {
    std::string names;
    for (auto j : t_idx) names += (names.empty() ? "" : ", ") + specs[j].name;
    fit.warnings.push_back(
        strf("%s are not separately identifiable from %zu temperatures (correlation up to %.4f); fix "
             "D2_K at the polymer's glass transition (--fix D2_K=...), or measure more temperatures. "
             "What the data determine: n, tau_star_Pa and the viscosity at each measured temperature "
             "(derived; the zero-shear viscosity where the data reach the plateau)",
             names.c_str(), st.levels.size(), max_r));
  }
}

// `base` with the residuals of the points idx through the public viscosity functions
// (viscosity.hpp), for the start search: it needs no derivatives, and the least squares after it
// uses the same function in logarithms with its analytic Jacobian (LnViscosity). Cross-WLF's
// search uses that ln form too.
LsqProblem search_problem(LsqProblem base, const RheologyData& data, const ViscosityRows& rows,
                          std::vector<std::size_t> idx, const ViscosityFitOptions& o, const std::vector<PSpec>& specs) {
  if (o.model == ViscosityModel::cross_wlf)
    return viscosity_problem(std::move(base), rows, std::move(idx), LnViscosity(o.model, o.shift));
  base.num_residuals = static_cast<int>(idx.size());
  base.observed.clear();
  for (auto i : idx) base.observed.push_back(rows.ln_obs[i]);
  std::vector<bool> is_log;
  for (const auto& s : specs) is_log.push_back(s.log);
  base.residuals_and_jacobian = nullptr;
  base.residuals = [&data, &rows, ev = Evaluator{o.model, o.shift}, is_log, idx](const double* p, double* r) {
    double v[12];
    for (std::size_t j = 0; j < is_log.size(); ++j) v[j] = is_log[j] ? std::exp(p[j]) : p[j];
    for (std::size_t k = 0; k < idx.size(); ++k) {
      const auto i = idx[k];
      const double e = ev(v, data.shear_rate_1_s[i], data.temperature_K[i], rows.pressure[i]);
      if (!(e > 0) || !std::isfinite(e)) return false;
      r[k] = rows.sw[i] * (std::log(e) - rows.ln_obs[i]);
    }
    return true;
  };
  return base;
}

}  // namespace

namespace rheology_detail {

std::unique_ptr<ViscosityProblem> viscosity_problem_for(const RheologyData& data, const ViscosityFitOptions& o) {
  validate_data(data);
  auto vp = std::make_unique<ViscosityProblem>();
  vp->stats = stats_of(data);
  const auto& st = vp->stats;
  vp->name = ViscositySpec{o.model, o.shift, {}}.name();
  const double T_ref = std::isfinite(o.T_ref_K) ? o.T_ref_K : default_T_ref(st.levels);
  vp->specs = default_specs(o, st, T_ref);
  check_temperatures(o, st, vp->specs, vp->name, data.size());
  LsqProblem prob;
  for (const auto& s : vp->specs) {
    ParamSpec ps{s.name,
                 s.unit,
                 s.log ? std::log(s.start) : s.start,
                 s.log ? std::log(s.lo) : s.lo,
                 s.log ? std::log(s.hi) : s.hi,
                 s.fixed};
    if (s.fixed) ps.lower = -kInf, ps.upper = kInf;
    prob.params.push_back(ps);
  }
  prob.residuals_are_time_ordered = false;
  vp->rows = viscosity_rows(data);
  const LnViscosity ln_eta(o.model, o.shift);
  const std::size_t n = data.size();
  std::vector<std::size_t> all(n), sub;
  for (std::size_t i = 0; i < n; ++i) all[i] = i;
  const std::size_t max_search = 120;  // the search only has to find the basin
  if (n > max_search) {
    for (std::size_t k = 0; k < max_search; ++k) sub.push_back(k * n / max_search);
  } else {
    sub = all;
  }
  vp->search = search_problem(prob, data, vp->rows, sub, o, vp->specs);
  vp->all = viscosity_problem(std::move(prob), vp->rows, std::move(all), ln_eta);
  return vp;
}

FitResult finish_viscosity_fit(const RheologyData& data, const ViscosityFitOptions& o, const ViscosityProblem& vp,
                               FitResult fit) {
  if (o.profile_intervals) apply_profile_intervals(vp.all, fit, o.profile);
  add_derived_viscosities(fit, data, o, vp);
  if (o.model == ViscosityModel::cross_wlf) add_ridge_warning(fit, vp.specs, vp.stats);
  finish_params(fit, vp.specs);
  return fit;
}

FitResult solve_viscosity(const ViscosityProblem& vp, const ViscosityFitOptions& o) {
  return solve_with_global_start(vp.name, vp.all, o.global, o.lsq, &vp.search);
}

}  // namespace rheology_detail

FitResult fit_viscosity(const RheologyData& data, const ViscosityFitOptions& o) {
  const auto vp = rheology_detail::viscosity_problem_for(data, o);
  return rheology_detail::finish_viscosity_fit(data, o, *vp, rheology_detail::solve_viscosity(*vp, o));
}

ViscositySpec spec_from_fit(const FitResult& fit) {
  ViscositySpec s = parse_viscosity_spec_name(fit.model);
  for (const auto& p : fit.params) s.values[p.name] = p.value;
  return s;
}

FitResult fit_power_law_window(const ViscositySpec& v, double T, double lo, double hi, int points, double pressure) {
  if (!(lo > 0) || !(hi > lo)) throw InputError(strf("power-law window: need 0 < low < high (got %g..%g 1/s)", lo, hi));
  if (points < 3) throw InputError("power-law window: need at least 3 points");
  std::vector<double> lg, lt;
  for (int i = 0; i < points; ++i) {
    const double g = std::pow(10.0, std::log10(lo) + i * (std::log10(hi) - std::log10(lo)) / (points - 1));
    lg.push_back(std::log(g));
    lt.push_back(std::log(v.viscosity(g, T, pressure) * g));
  }
  // Start from the closed-form regression, refine (and get the covariance) with the core.
  const double N = points;
  double mx = 0, my = 0;
  for (int i = 0; i < points; ++i) mx += lg[i] / N, my += lt[i] / N;
  double sxy = 0, sxx = 0;
  for (int i = 0; i < points; ++i) sxy += (lg[i] - mx) * (lt[i] - my), sxx += (lg[i] - mx) * (lg[i] - mx);
  const double slope = sxy / sxx, icpt = my - slope * mx;
  LsqProblem prob;
  prob.params = {{"K_Pa_s_n", "Pa.s^n", icpt}, {"n", "1", slope}};
  prob.num_residuals = points;
  prob.observed = lt;
  prob.residuals_are_time_ordered = false;
  prob.residuals_and_jacobian = [&](const double* p, double* r, double* J) {
    for (int i = 0; i < points; ++i) {
      r[i] = p[0] + p[1] * lg[i] - lt[i];
      if (J) J[2 * i] = 1, J[2 * i + 1] = lg[i];
    }
    return true;
  };
  auto fit = solve_least_squares("power-law", prob);
  finish_params(fit, {{"K_Pa_s_n", "Pa.s^n", true, 0, kInf, 0, false}, {"n", "1", false, -kInf, kInf, 0, false}});
  fit.warnings.clear();
  return fit;
}

}  // namespace tunekit::fitting
