#include "tunekit/fitting/least_squares.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>

#include <ceres/ceres.h>
#include <glog/logging.h>

#include "solver_logging.hpp"
#include "solver_text.hpp"
#include "svd_covariance.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/fitting/stats.hpp"
#include "whiteness_detail.hpp"

namespace tunekit::fitting {
namespace {

// The last evaluations, served again bit for bit instead of recomputed (the residual functions
// are pure). Ceres evaluates the same point more than once per iteration: with bounds, its
// projected line search evaluates the trial point with the gradient (so with the Jacobian), then
// the trial point's cost, and an accepted trial point with its Jacobian again; after a rejected
// last trial the solution's residuals and its Jacobian (for the covariance) are asked for once
// more. Two evaluations with a Jacobian are kept (two more copies of the Jacobian than Ceres
// holds) and two without.
class EvaluationMemo {
 public:
  EvaluationMemo(int num_params, int num_residuals) : n_(num_params), m_(num_residuals) {}

  // Copies a stored evaluation at x into r (and jac when not null). A Jacobian request needs
  // the entry with a Jacobian; a residual request takes it only when `any_kind` (the residuals
  // are computed the same way with and without the Jacobian).
  bool find(const double* x, double* r, double* jac, bool any_kind) const {
    for (const auto& e : with_jacobian_)
      if (same_point(e, x) && (jac != nullptr || any_kind)) {
        copy_out(e, r, jac);
        return true;
      }
    if (jac != nullptr) return false;
    for (const auto& e : residuals_only_)
      if (same_point(e, x)) {
        copy_out(e, r, nullptr);
        return true;
      }
    return false;
  }

  void store(const double* x, const double* r, const double* jac) {
    Entry& e = jac != nullptr ? with_jacobian_[next_jac_] : residuals_only_[next_];
    if (jac == nullptr) next_ = 1 - next_;
    else next_jac_ = 1 - next_jac_;
    e.x.assign(x, x + n_);
    e.r.assign(r, r + m_);
    if (jac != nullptr) e.jac.assign(jac, jac + static_cast<std::size_t>(m_) * static_cast<std::size_t>(n_));
  }

 private:
  struct Entry {
    std::vector<double> x, r, jac;
  };
  bool same_point(const Entry& e, const double* x) const {
    return !e.x.empty() && std::memcmp(e.x.data(), x, sizeof(double) * static_cast<std::size_t>(n_)) == 0;
  }
  static void copy_out(const Entry& e, double* r, double* jac) {
    std::copy(e.r.begin(), e.r.end(), r);
    if (jac != nullptr) std::copy(e.jac.begin(), e.jac.end(), jac);
  }
  int n_, m_;
  std::array<Entry, 2> with_jacobian_;
  std::array<Entry, 2> residuals_only_;
  std::size_t next_ = 0, next_jac_ = 0;
};

// One residual block holding every residual, one parameter block holding the free parameters
// (the indices `free` of the problem's parameters; the others keep their values in `x`).
// Jacobians come from the model when it provides them, otherwise from central differences
// (one-sided where a central step leaves the model's domain), and hold the free parameters'
// columns only: the solver and the covariance never see a fixed parameter. (A SubsetManifold on
// the whole vector takes the same steps, its parameter tolerance counting the fixed values too,
// but multiplies every Jacobian by its selection matrix: a fifth of a ring-down fit's CPU time.)
class WholeProblemCost final : public ceres::CostFunction {
 public:
  WholeProblemCost(const LsqProblem& p, std::vector<int> free, std::vector<double> x)
      : prob_(p),
        n_(static_cast<int>(p.params.size())),
        free_(std::move(free)),
        x_(std::move(x)),
        memo_(static_cast<int>(free_.size()), p.num_residuals) {
    set_num_residuals(p.num_residuals);
    mutable_parameter_block_sizes()->push_back(static_cast<int>(free_.size()));
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const double* xf = parameters[0];
    double* jac = (jacobians != nullptr) ? jacobians[0] : nullptr;
    const bool reusable = !prob_.residuals_and_jacobian || prob_.same_residuals_with_jacobian;
    if (memo_.find(xf, residuals, jac, reusable)) return true;
    for (std::size_t k = 0; k < free_.size(); ++k) x_[static_cast<std::size_t>(free_[k])] = xf[k];
    if (!compute(residuals, jac)) return false;
    memo_.store(xf, residuals, jac);
    return true;
  }

 private:
  bool all_free() const { return static_cast<int>(free_.size()) == n_; }

  bool compute(double* residuals, double* jac) const {
    if (!prob_.residuals_and_jacobian) return numeric(residuals, jac);
    if (jac == nullptr || all_free()) return prob_.residuals_and_jacobian(x_.data(), residuals, jac);
    const int m = num_residuals(), nf = static_cast<int>(free_.size());
    full_jac_.resize(static_cast<std::size_t>(m) * static_cast<std::size_t>(n_));
    if (!prob_.residuals_and_jacobian(x_.data(), residuals, full_jac_.data())) return false;
    for (int i = 0; i < m; ++i)
      for (int k = 0; k < nf; ++k) jac[i * nf + k] = full_jac_[static_cast<std::size_t>(i * n_ + free_[k])];
    return true;
  }

  bool numeric(double* residuals, double* jac) const {
    if (!prob_.residuals(x_.data(), residuals)) return false;
    if (jac == nullptr) return true;
    const int m = num_residuals(), nf = static_cast<int>(free_.size());
    std::vector<double> xp(x_), rp(static_cast<std::size_t>(m)), rm(static_cast<std::size_t>(m));
    for (int k = 0; k < nf; ++k) {
      const int j = free_[static_cast<std::size_t>(k)];
      const double h = 1e-6 * std::max(std::abs(x_[j]), 1e-6);
      xp[j] = x_[j] + h;
      const bool okp = prob_.residuals(xp.data(), rp.data());
      xp[j] = x_[j] - h;
      const bool okm = prob_.residuals(xp.data(), rm.data());
      xp[j] = x_[j];
      if (okp && okm) {
        for (int i = 0; i < m; ++i) jac[i * nf + k] = (rp[i] - rm[i]) / (2 * h);
      } else if (okp) {
        for (int i = 0; i < m; ++i) jac[i * nf + k] = (rp[i] - residuals[i]) / h;
      } else if (okm) {
        for (int i = 0; i < m; ++i) jac[i * nf + k] = (residuals[i] - rm[i]) / h;
      } else {
        return false;
      }
    }
    return true;
  }

  const LsqProblem& prob_;
  int n_;
  std::vector<int> free_;
  mutable std::vector<double> x_;         // every parameter; the free ones from the last point asked
  mutable std::vector<double> full_jac_;  // the model's Jacobian of every parameter, before selection
  mutable EvaluationMemo memo_;
};

// Ceres reports through glog, which (never initialised by the program) writes ERROR and WARNING
// lines to stderr before our own one-line FitError. The solver's outcome is read from its
// summary and return values instead, so glog is kept quiet: nothing below FATAL, and nothing to
// stderr.
void quiet_glog() {
  static std::once_flag once;
  std::call_once(once, [] {
    FLAGS_minloglevel = google::GLOG_FATAL;
    FLAGS_stderrthreshold = google::GLOG_FATAL;
    FLAGS_logtostderr = false;
    FLAGS_alsologtostderr = false;
  });
}

std::string free_names(const LsqProblem& p) {
  std::string s;
  for (const auto& ps : p.params) {
    if (ps.fixed) continue;
    if (!s.empty()) s += ", ";
    s += ps.name;
  }
  return s;
}

}  // namespace

void quiet_solver_logging() { quiet_glog(); }

namespace {

// The largest finite |v| of observed, at least 1 (residual_variance_floor's scale).
double observed_scale(std::span<const double> observed) {
  double scale = 1.0;
  for (double v : observed)
    if (std::isfinite(v)) scale = std::max(scale, std::abs(v));
  return scale;
}

double floor_of_scale(double scale) {
  const double sigma = kRelativeResidualFloor * scale;
  return sigma * sigma;
}

// The sums fill_residual_diagnostics is made of, each summed in the order of the samples.
struct ResidualSums {
  double rss = 0, res_sum = 0;  // of the residuals' squares and of the residuals
  double obs_sum = 0, tss = 0;  // of the observations and of their squared deviations from their mean
  double scale = 1;             // observed_scale
  double res_c0 = 0;            // of the residuals' squared deviations from their mean (with_c0)
};

// All of them in two passes over the samples, several independent sums per pass (one sum at a
// time is bound by the latency of its additions). Each is the sum it was one at a time, to the bit.
ResidualSums residual_sums(std::span<const double> res, std::span<const double> obs, bool with_c0) {
  ResidualSums s;
  const std::size_t n = res.size();
  if (obs.size() != n) {  // no R^2: the residuals' sums and the scale alone
    for (double v : res) s.rss += v * v, s.res_sum += v;
    s.scale = observed_scale(obs);
  } else {
    double scale = 1.0;
    for (std::size_t i = 0; i < n; ++i) {
      const double v = res[i], o = obs[i], a = std::abs(o);
      s.rss += v * v;
      s.res_sum += v;
      s.obs_sum += o;
      if (a > scale && std::isfinite(a)) scale = a;
    }
    s.scale = scale;
  }
  const double res_mean = s.res_sum / static_cast<double>(n), obs_mean = s.obs_sum / static_cast<double>(n);
  if (obs.size() == n && with_c0) {
    for (std::size_t i = 0; i < n; ++i) {
      s.tss += (obs[i] - obs_mean) * (obs[i] - obs_mean);
      s.res_c0 += (res[i] - res_mean) * (res[i] - res_mean);
    }
  } else if (obs.size() == n) {
    for (double o : obs) s.tss += (o - obs_mean) * (o - obs_mean);
  } else if (with_c0) {
    for (double v : res) s.res_c0 += (v - res_mean) * (v - res_mean);
  }
  return s;
}

// Every statistic of fill_residual_diagnostics but the whiteness test, from those sums.
void fill_fit_statistics(FitResult& r, const ResidualSums& s, std::size_t num_res, std::size_t num_obs) {
  auto& d = r.diagnostics;
  const double n = static_cast<double>(num_res);
  const double rss = s.rss;
  d.num_observations = static_cast<int>(num_res);
  d.rss = rss;
  d.rms = num_res == 0 ? kNaN : std::sqrt(rss / n);
  const double k = d.num_parameters;
  // An exact fit (rss = 0) has no finite log-likelihood; the residual variance is floored at
  // what the arithmetic can resolve, so exact fits get finite criteria and the simpler model
  // wins a tie (the 2k term decides).
  const double floor = floor_of_scale(s.scale);
  if (num_res > 0 && std::isfinite(rss)) {
    const double var = std::max(rss / n, floor);
    d.aic = n * std::log(var) + 2 * k;
    d.bic = n * std::log(var) + k * std::log(n);
  }
  if (num_obs == num_res && num_obs > 0) {
    // Data that do not vary leave nothing to explain: R^2 is 1 for a fit to within the floor
    // and 0 otherwise (the fit explains nothing the mean does not), with a warning.
    if (s.tss > floor * n) {
      d.r2 = 1.0 - rss / s.tss;
    } else {
      d.r2 = rss <= floor * n ? 1.0 : 0.0;
      r.warnings.push_back("the observed values do not vary; R^2 says nothing about this fit");
    }
  }
}

void set_whiteness(FitResult& r, const WhitenessTest& wt) {
  r.diagnostics.whiteness_p = wt.p_value;
  r.diagnostics.whiteness_lags = wt.lags;
}

}  // namespace

double residual_variance_floor(const std::vector<double>& observed) { return floor_of_scale(observed_scale(observed)); }

void fill_residual_diagnostics(FitResult& r, const std::vector<double>& res, const std::vector<double>& observed,
                               bool time_ordered) {
  fill_fit_statistics(r, residual_sums(res, observed, false), res.size(), observed.size());
  if (time_ordered) set_whiteness(r, ljung_box(res, default_whiteness_lags(res.size())));
}

void fill_residual_diagnostics_in_place(FitResult& r, std::span<double> res, std::span<const double> observed,
                                        bool time_ordered) {
  const bool whiteness = time_ordered && res.size() >= 3;
  const ResidualSums s = residual_sums(res, observed, whiteness);
  fill_fit_statistics(r, s, res.size(), observed.size());
  if (!time_ordered) return;
  const int lags = default_whiteness_lags(res.size());
  set_whiteness(r, whiteness ? whiteness_detail::ljung_box_in_place(res, s.res_sum / static_cast<double>(res.size()),
                                                                    s.res_c0, lags)
                             : WhitenessTest{});
}

namespace {

// The number of free parameters; InputError when the data points are fewer.
int free_parameter_count(const std::string& model, const LsqProblem& prob) {
  int n_free = 0;
  for (const auto& ps : prob.params)
    if (!ps.fixed) ++n_free;
  if (prob.num_residuals < n_free)
    throw InputError(model + ": " + std::to_string(prob.num_residuals) + " data points for " + std::to_string(n_free) +
                     " free parameters (" + free_names(prob) + ")");
  return n_free;
}

// The parameters' start values, each within its bounds.
std::vector<double> clamped_start(const LsqProblem& prob) {
  std::vector<double> x(prob.params.size());
  for (std::size_t j = 0; j < x.size(); ++j) {
    const auto& ps = prob.params[j];
    x[j] = std::clamp(ps.start, ps.lower, ps.upper);
  }
  return x;
}

// The indices of the parameters not marked in `fixed`.
std::vector<int> free_indices(const std::vector<bool>& fixed) {
  std::vector<int> free;
  for (std::size_t j = 0; j < fixed.size(); ++j)
    if (!fixed[j]) free.push_back(static_cast<int>(j));
  return free;
}

// x's values at the indices `free`.
std::vector<double> gathered(const std::vector<double>& x, const std::vector<int>& free) {
  std::vector<double> xf(free.size());
  for (std::size_t k = 0; k < free.size(); ++k) xf[k] = x[static_cast<std::size_t>(free[k])];
  return xf;
}

// The whole problem as one residual block on xf, the free parameters (indices `free`) of x, with
// their bounds. Needs at least one free parameter.
void build_ceres_problem(ceres::Problem& problem, const LsqProblem& prob, const std::vector<int>& free,
                         const std::vector<double>& x, std::vector<double>& xf) {
  problem.AddResidualBlock(new WholeProblemCost(prob, free, x), nullptr, xf.data());
  for (std::size_t k = 0; k < free.size(); ++k) {
    const auto& ps = prob.params[static_cast<std::size_t>(free[k])];
    const int i = static_cast<int>(k);
    if (std::isfinite(ps.lower)) problem.SetParameterLowerBound(xf.data(), i, ps.lower);
    if (std::isfinite(ps.upper)) problem.SetParameterUpperBound(xf.data(), i, ps.upper);
  }
}

ceres::Solver::Options solver_options(const LsqOptions& opt) {
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = opt.max_iterations;
  so.function_tolerance = opt.function_tolerance;
  so.gradient_tolerance = opt.gradient_tolerance;
  so.parameter_tolerance = opt.parameter_tolerance;
  so.logging_type = ceres::SILENT;
  so.minimizer_progress_to_stdout = false;
  so.num_threads = 1;
  return so;
}

// FitError when the solve failed, did not converge where convergence is required, or ended on a
// point that is not finite.
void check_solution(const std::string& model, const ceres::Solver::Summary& summary, const LsqOptions& opt, int n_free,
                    const std::vector<double>& x, const std::string& solver) {
  if (n_free > 0) {
    if (summary.termination_type == ceres::FAILURE || summary.termination_type == ceres::USER_FAILURE ||
        !summary.IsSolutionUsable())
      throw FitError(model + ": " + detail::plain_solver_failure(summary));
    if (summary.termination_type == ceres::NO_CONVERGENCE && opt.require_convergence)
      throw FitError(model + ": did not converge in " + std::to_string(opt.max_iterations) + " iterations");
  }
  for (double v : x)
    if (!std::isfinite(v)) throw FitError(model + ": the solution is not finite (" + solver + ")");
}

// Parameters the caller holds on a bound (hold_before_covariance): fixed from here on
// (statistics and covariance). `fixed` starts as the problem's fixed parameters; n_free drops by
// the ones held. True when any was held.
bool hold_at_callers_request(const LsqOptions& opt, std::vector<double>& x, std::vector<bool>& fixed, int& n_free) {
  bool any_held = false;
  if (!opt.hold_before_covariance || n_free == 0) return false;
  const std::size_t n = fixed.size();
  std::vector<bool> hold(n, false);
  opt.hold_before_covariance(x, hold);
  for (std::size_t j = 0; j < n; ++j) {
    if (!hold[j] || fixed[j]) continue;
    fixed[j] = true;
    any_held = true;
    --n_free;
  }
  return any_held;
}

// The cost the solution's residuals and covariance are evaluated with, at `point`: the Ceres
// problem's own at its block xf, whose memo holds the solve's last evaluations there; with held
// parameters, a cost over the parameters still free; with every parameter fixed, one over all of
// them at x.
struct SolutionCost {
  std::unique_ptr<WholeProblemCost> own;
  const ceres::CostFunction* cost = nullptr;
  std::vector<double> point;
};

SolutionCost solution_cost(const LsqProblem& prob, ceres::Problem& problem, const std::vector<double>& x,
                           const std::vector<double>& xf, const std::vector<bool>& fixed, int n_free, bool any_held) {
  SolutionCost c;
  if (n_free > 0 && !any_held) {
    std::vector<ceres::ResidualBlockId> blocks;
    problem.GetResidualBlocks(&blocks);
    c.cost = problem.GetCostFunctionForResidualBlock(blocks.front());
    c.point = xf;
    return c;
  }
  std::vector<int> free = free_indices(fixed);
  if (n_free == 0) {
    free.resize(prob.params.size());
    for (std::size_t j = 0; j < free.size(); ++j) free[j] = static_cast<int>(j);
  }
  c.point = gathered(x, free);
  c.own = std::make_unique<WholeProblemCost>(prob, std::move(free), x);
  c.cost = c.own.get();
  return c;
}

// The residuals at the solution, with the Jacobian of the cost's parameters into `jacobian` when
// it is not empty.
std::vector<double> evaluate_at_solution(const std::string& model, const LsqProblem& prob, const SolutionCost& c,
                                         std::vector<double>& jacobian) {
  std::vector<double> res(static_cast<std::size_t>(prob.num_residuals));
  const double* parameters[] = {c.point.data()};
  double* jacobians[] = {jacobian.data()};
  if (!c.cost->Evaluate(parameters, res.data(), jacobian.empty() ? nullptr : jacobians))
    throw FitError(model + ": the model cannot be evaluated at the solution");
  return res;
}

// The n x n covariance of the parameters (before the residual variance s^2), NaN where a
// parameter is fixed: (J'J)^-1 of the free parameters from the Jacobian J of the solution's cost.
// FitError when the free parameters are not identifiable.
std::vector<double> free_covariance(const std::string& model, const LsqProblem& prob, const SolutionCost& c,
                                    const std::vector<bool>& fixed, double min_reciprocal_condition) {
  const int n = static_cast<int>(prob.params.size());
  const std::vector<int> free = free_indices(fixed);
  const int nf = static_cast<int>(free.size()), m = prob.num_residuals;
  std::vector<double> jac(static_cast<std::size_t>(m) * static_cast<std::size_t>(nf));
  evaluate_at_solution(model, prob, c, jac);
  const std::optional<std::vector<double>> cov_free = svd_covariance(jac, m, nf, min_reciprocal_condition);
  if (!cov_free)
    throw FitError(model + ": parameters not identifiable from these data (the Jacobian of " + free_names(prob) +
                   " is rank deficient); record a longer or richer response, or fix a parameter");
  std::vector<double> cov(static_cast<std::size_t>(n * n), kNaN);
  const auto unf = static_cast<std::size_t>(nf);
  for (std::size_t a = 0; a < unf; ++a)
    for (std::size_t b = 0; b < unf; ++b)
      cov[static_cast<std::size_t>(free[a] * n + free[b])] = (*cov_free)[a * unf + b];
  return cov;
}

// The result's parameters (value, Wald interval from cov s^2 with the t multiplier tq), the
// warnings for those that ended on a bound, and the covariance of the free ones.
void fill_parameters(FitResult& r, const std::string& model, const LsqProblem& prob, const LsqOptions& opt,
                     const std::vector<double>& x, const std::vector<bool>& fixed, const std::vector<double>& cov,
                     double s2, double tq, int n_free) {
  const int n = static_cast<int>(prob.params.size());
  for (int j = 0; j < n; ++j) {
    const auto& ps = prob.params[j];
    Param p;
    p.name = ps.name;
    p.unit = ps.unit;
    p.value = x[j];
    p.fixed = fixed[j];
    if (!p.fixed && opt.compute_covariance) {
      p.ci95_method = "wald";
      const double var = cov[j * n + j] * s2;
      p.std_error = var >= 0 ? std::sqrt(var) : kNaN;
      p.ci95_lo = p.value - tq * p.std_error;
      p.ci95_hi = p.value + tq * p.std_error;
      if (!std::isfinite(p.std_error))
        throw FitError(model + ": the uncertainty of " + ps.name + " is not finite; it is not identifiable");
    }
    if (!p.fixed && (x[j] <= ps.lower || x[j] >= ps.upper))
      r.warnings.push_back(ps.name + " ended on its bound (" + std::to_string(x[j]) + ")");
    r.params.push_back(p);
  }
  if (opt.compute_covariance && n_free > 0) {
    r.covariance.assign(static_cast<std::size_t>(n * n), 0.0);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        if (!fixed[i] && !fixed[j]) r.covariance[i * n + j] = cov[i * n + j] * s2;
  }
}

}  // namespace

FitResult solve_least_squares(const std::string& model, const LsqProblem& prob, const LsqOptions& opt) {
  quiet_glog();
  const int n = static_cast<int>(prob.params.size());
  if (n == 0) throw FitError(model + ": no parameters to fit");
  if (!prob.residuals && !prob.residuals_and_jacobian) throw FitError(model + ": no residual function");
  int n_free = free_parameter_count(model, prob);
  std::vector<double> x = clamped_start(prob);
  std::vector<bool> fixed(static_cast<std::size_t>(n));
  for (int j = 0; j < n; ++j) fixed[j] = prob.params[j].fixed;
  const std::vector<int> free = free_indices(fixed);
  std::vector<double> xf = gathered(x, free);

  ceres::Problem::Options popt;
  popt.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(popt);
  ceres::Solver::Summary summary;
  if (n_free > 0) {
    build_ceres_problem(problem, prob, free, x, xf);
    ceres::Solve(solver_options(opt), &problem, &summary);
    for (std::size_t k = 0; k < free.size(); ++k) x[static_cast<std::size_t>(free[k])] = xf[k];
  }

  FitResult r;
  r.model = model;
  r.diagnostics.iterations = static_cast<int>(summary.iterations.size());
  r.diagnostics.solver = n_free > 0 ? summary.BriefReport() : "all parameters fixed";
  check_solution(model, summary, opt, n_free, x, r.diagnostics.solver);
  r.diagnostics.converged = n_free == 0 || summary.termination_type == ceres::CONVERGENCE;

  const bool any_held = hold_at_callers_request(opt, x, fixed, n_free);
  r.diagnostics.num_parameters = n_free;
  // In place: xf's storage is the Ceres problem's parameter block.
  for (std::size_t k = 0; k < free.size(); ++k) xf[k] = x[static_cast<std::size_t>(free[k])];

  const SolutionCost at_solution = solution_cost(prob, problem, x, xf, fixed, n_free, any_held);
  std::vector<double> no_jacobian;
  const std::vector<double> res = evaluate_at_solution(model, prob, at_solution, no_jacobian);
  fill_residual_diagnostics(r, res, prob.observed, prob.residuals_are_time_ordered);

  const int dof = prob.num_residuals - n_free;
  const double s2 = (opt.absolute_sigma || dof <= 0) ? 1.0 : r.diagnostics.rss / dof;
  const double tq = t_multiplier(opt.confidence, dof);

  std::vector<double> cov(static_cast<std::size_t>(n * n), kNaN);
  if (opt.compute_covariance && n_free > 0) {
    if (dof <= 0) throw FitError(model + ": as many parameters as data points; no uncertainty can be estimated");
    cov = free_covariance(model, prob, at_solution, fixed, opt.min_reciprocal_condition);
  }
  fill_parameters(r, model, prob, opt, x, fixed, cov, s2, tq, n_free);
  return r;
}

}  // namespace tunekit::fitting
