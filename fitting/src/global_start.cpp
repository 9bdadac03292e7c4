#include "tunekit/fitting/global_start.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <nlopt.hpp>

#include "tunekit/core/error.hpp"

namespace tunekit::fitting {
namespace {

struct SearchContext {
  const LsqProblem* prob = nullptr;
  std::vector<int> free_idx;
  std::vector<bool> log_scale;
  std::vector<double> base;  // full parameter vector (fixed values)
  std::vector<double> r;
  int evaluations = 0;

  std::vector<double> full(const std::vector<double>& z) const {
    std::vector<double> x = base;
    for (std::size_t k = 0; k < free_idx.size(); ++k) x[free_idx[k]] = log_scale[k] ? std::exp(z[k]) : z[k];
    return x;
  }

  double cost(const std::vector<double>& z) {
    ++evaluations;
    const auto x = full(z);
    bool ok = false;
    if (prob->residuals) ok = prob->residuals(x.data(), r.data());
    else ok = prob->residuals_and_jacobian(x.data(), r.data(), nullptr);
    if (!ok) return std::numeric_limits<double>::max();
    double s = 0;
    for (double v : r) s += v * v;
    return std::isfinite(s) ? 0.5 * s : std::numeric_limits<double>::max();
  }
};

double objective(unsigned /*n*/, const double* z, double* grad, void* data) {
  auto* ctx = static_cast<SearchContext*>(data);
  if (grad != nullptr) return std::numeric_limits<double>::max();  // derivative-free algorithms only
  return ctx->cost(std::vector<double>(z, z + ctx->free_idx.size()));
}

}  // namespace

GlobalStartResult global_start(const LsqProblem& prob, const GlobalStartOptions& opt) {
  SearchContext ctx;
  ctx.prob = &prob;
  const int n = static_cast<int>(prob.params.size());
  std::vector<double> lo, hi, z0;
  for (int j = 0; j < n; ++j) {
    const auto& ps = prob.params[j];
    ctx.base.push_back(std::clamp(ps.start, ps.lower, ps.upper));
    if (ps.fixed) continue;
    if (!std::isfinite(ps.lower) || !std::isfinite(ps.upper) || !(ps.lower < ps.upper))
      throw InputError("global start: parameter " + ps.name + " needs finite lower < upper bounds");
    const bool lg = ps.lower > 0 && ps.upper / ps.lower > 100.0;
    ctx.free_idx.push_back(j);
    ctx.log_scale.push_back(lg);
    lo.push_back(lg ? std::log(ps.lower) : ps.lower);
    hi.push_back(lg ? std::log(ps.upper) : ps.upper);
    const double s = ctx.base.back();
    z0.push_back(lg ? std::log(s) : s);
  }
  ctx.r.resize(static_cast<std::size_t>(prob.num_residuals));
  GlobalStartResult res;
  res.start = ctx.base;
  const auto nf = static_cast<unsigned>(ctx.free_idx.size());
  if (nf == 0) return res;

  // The "auto" bounds of a log-scaled parameter must stay inside the box in z.
  auto clamp_z = [&](std::vector<double> z) {
    for (unsigned k = 0; k < nf; ++k) z[k] = std::clamp(z[k], lo[k], hi[k]);
    return z;
  };

  nlopt::srand(opt.seed);
  std::vector<double> best = clamp_z(z0);
  double best_cost = ctx.cost(best);
  {
    nlopt::opt g(nlopt::GN_CRS2_LM, nf);
    g.set_lower_bounds(lo);
    g.set_upper_bounds(hi);
    g.set_min_objective(objective, &ctx);
    g.set_maxeval(opt.max_evaluations);
    g.set_ftol_rel(1e-10);
    std::vector<double> z = best;
    double f = best_cost;
    try {
      g.optimize(z, f);
    } catch (const std::exception&) {
      // NLopt reports roundoff-limited or forced stops as exceptions; keep what it found.
      f = ctx.cost(z);
    }
    if (f < best_cost) best = z, best_cost = f;
  }
  auto polish = [&](std::vector<double> z) {
    nlopt::opt l(nlopt::LN_BOBYQA, nf);
    l.set_lower_bounds(lo);
    l.set_upper_bounds(hi);
    l.set_min_objective(objective, &ctx);
    l.set_maxeval(opt.local_evaluations);
    l.set_xtol_rel(1e-10);
    double f = ctx.cost(z);
    try {
      l.optimize(z, f);
    } catch (const std::exception&) {
      f = ctx.cost(z);
    }
    if (f < best_cost) best = z, best_cost = f;
  };
  polish(best);
  for (const auto& s : opt.extra_starts) {
    if (s.size() != prob.params.size()) continue;
    std::vector<double> z;
    for (unsigned k = 0; k < nf; ++k) {
      const double v = s[ctx.free_idx[k]];
      z.push_back(ctx.log_scale[k] ? std::log(std::max(v, 1e-300)) : v);
    }
    polish(clamp_z(z));
  }
  res.start = ctx.full(best);
  res.cost = best_cost;
  res.evaluations = ctx.evaluations;
  return res;
}

FitResult solve_with_global_start(const std::string& model, LsqProblem prob, const GlobalStartOptions& global,
                                  const LsqOptions& options, const LsqProblem* search) {
  const auto gs = global_start(search != nullptr ? *search : prob, global);
  for (std::size_t j = 0; j < prob.params.size(); ++j) prob.params[j].start = gs.start[j];
  auto fit = solve_least_squares(model, prob, options);
  fit.diagnostics.solver = "global start: CRS2-LM + BOBYQA, " + std::to_string(gs.evaluations) + " evaluations; then " +
                           fit.diagnostics.solver;
  return fit;
}

}  // namespace tunekit::fitting
