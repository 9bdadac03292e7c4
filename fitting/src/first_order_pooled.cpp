// The pooled fit of first-order step responses: one K, tau_s and theta_s shared by several steps,
// each with its own offset y0 (Holtrup, Tuning liquefier dynamics, MSc thesis, University of
// Twente, 2019, ch. 4.4.2). The single-step fit and the model are in first_order.cpp.
#include <algorithm>
#include <cmath>
#include <numeric>

#include <array>
#include <memory>

#include <Eigen/Dense>
#include <ceres/ceres.h>

#include "tunekit/fitting/first_order.hpp"
#include "tunekit/fitting/stats.hpp"

#include "tunekit/core/error.hpp"
#include "first_order_detail.hpp"
#include "tunekit/fitting/levenberg_marquardt.hpp"
#include "number_text.hpp"
#include "solver_logging.hpp"
#include "solver_text.hpp"

namespace tunekit::fitting {
using namespace first_order_detail;
namespace {

// One residual block of the pooled fit: the samples of one step, with the parameter blocks
// {K, tau_s, theta_s} (shared by every step) and {y0 of this step}. Handing Ceres one block per
// step (instead of one dense Jacobian over all samples and parameters) lets it eliminate the
// per-step offsets (Schur complement) and work on a 3x3 reduced system: the Jacobian of a
// 6-level sweep has ~165k rows but only 4 non-zeros in each.
class PooledStepCost final : public ceres::CostFunction {
 public:
  explicit PooledStepCost(const StepRecord& r) : r_(r) {
    set_num_residuals(static_cast<int>(r.t.size()));
    mutable_parameter_block_sizes()->push_back(3);
    mutable_parameter_block_sizes()->push_back(1);
  }

  bool Evaluate(double const* const* p, double* res, double** jac) const override {
    double* j_shared = jac != nullptr ? jac[0] : nullptr;
    double* j_y0 = jac != nullptr ? jac[1] : nullptr;
    const std::size_t n = r_.t.size();
    const double K = p[0][0], tau = p[0][1], theta = p[0][2], y0 = p[1][0];
    std::vector<StepModelPoint> pts;  // a driven record's model, computed over the whole record
    const bool driven = follows_input(r_);
    if (driven) step_model_points(r_, K, tau, theta, y0, pts);
    for (std::size_t i = 0; i < n; ++i) {
      const StepModelPoint m = driven ? pts[i] : step_model_at(r_, i, K, tau, theta, y0);
      res[i] = m.m - r_.y[i];
      if (j_shared != nullptr) {
        j_shared[3 * i] = m.dK;
        j_shared[3 * i + 1] = m.dtau;
        j_shared[3 * i + 2] = m.dtheta;
      }
      if (j_y0 != nullptr) j_y0[i] = 1.0;
    }
    return true;
  }

 private:
  const StepRecord& r_;
};

// The pooled fit's normal equations: each step's 4x4 block (normal_equations) added into the
// (3 + steps)-square matrix; p = {K, tau_s, theta_s, y0_0, y0_1, ...}. Returns the residual
// sum of squares.
double pooled_normal_equations(const std::vector<StepRecord>& recs, std::span<const double> p, Eigen::MatrixXd& N,
                               Eigen::VectorXd& g) {
  const auto n = static_cast<Eigen::Index>(p.size());
  N.setZero(n, n);
  g.setZero(n);
  double rss = 0;
  for (std::size_t j = 0; j < recs.size(); ++j) {
    const double q[4] = {p[0], p[1], p[2], p[3 + j]};
    Eigen::Matrix4d JtJ;
    Eigen::Vector4d Jtr;
    rss += normal_equations(recs[j], q, JtJ, Jtr);
    const Eigen::Index idx[4] = {0, 1, 2, 3 + static_cast<Eigen::Index>(j)};
    for (int a = 0; a < 4; ++a) {
      g(idx[a]) += Jtr(a);
      for (int b = 0; b < 4; ++b) N(idx[a], idx[b]) += JtJ(a, b);
    }
  }
  return rss;
}

// The pooled fit's start polish: Levenberg-Marquardt on the small normal equations (one pass
// over the samples per trial, no Jacobian stored), so that Ceres starts next to the optimum.
void polish_pooled_start(const std::vector<StepRecord>& recs, std::vector<double>& p, const std::vector<double>& lo,
                         const std::vector<double>& hi, const std::vector<bool>& fixed) {
  auto equations = [&recs](std::span<const double> q, Eigen::MatrixXd& N, Eigen::VectorXd& g) {
    return pooled_normal_equations(recs, q, N, g);
  };
  lm_detail::polish<Eigen::MatrixXd, Eigen::VectorXd>(p, lo, hi, fixed, equations);
}

// Step j's normal equations at the pooled estimates p (K, tau_s, theta_s, then each step's
// y0), and a 4-vector of that step's parameters (K, tau_s, theta_s, its y0) placed on the free
// parameters (free_idx; fixed ones and other steps' offsets are 0).
struct StepNormal {
  Eigen::Matrix4d JtJ;
  Eigen::Vector4d Jtr;
};

StepNormal step_normal(const std::vector<StepRecord>& recs, const std::vector<double>& p, std::size_t j) {
  const double q[4] = {p[0], p[1], p[2], p[3 + j]};
  StepNormal out;
  normal_equations(recs[j], q, out.JtJ, out.Jtr);
  return out;
}

Eigen::VectorXd on_free_params(const Eigen::Vector4d& v, std::size_t j, const std::vector<int>& free_idx) {
  const int k = static_cast<int>(free_idx.size());
  Eigen::VectorXd out = Eigen::VectorXd::Zero(k);
  const int idx[4] = {0, 1, 2, 3 + static_cast<int>(j)};
  for (int a = 0; a < k; ++a)
    for (int c = 0; c < 4; ++c)
      if (free_idx[static_cast<std::size_t>(a)] == idx[c]) out(a) = v(c);
  return out;
}

// The step instants are known to one sample: a rectangular uncertainty r = dt / sqrt(12) in
// each (JCGM 100:2008, "Guide to the expression of uncertainty in measurement", 4.3.7). An error
// e_j in step j's instant shifts that step's response alone, which moves the estimates by
// a_j e_j, a_j = (J^T J)^-1 J_j^T J_j,theta (J_j,theta: the model's derivative in the dead time
// over step j's samples); the instants of different steps fall at unrelated phases of the sample
// clock, so their errors are independent and add r^2 sum_j a_j a_j^T to the covariance (law of
// propagation, ibid. 5.1.2). Shifting every step alike moves the dead time by the same amount
// (sum_j a_j = 1 in theta): r^2 would be the one common clock offset, which the pooled steps
// do not share. C is (J^T J)^-1 over the free parameters (free_idx), p the estimates.
Eigen::MatrixXd instant_resolution_variance(const std::vector<StepRecord>& recs, const std::vector<double>& p,
                                            const std::vector<int>& free_idx, const Eigen::MatrixXd& C) {
  const int k = static_cast<int>(free_idx.size());
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(k, k);
  if (std::find(free_idx.begin(), free_idx.end(), 2) == free_idx.end()) return W;  // theta fixed
  for (std::size_t j = 0; j < recs.size(); ++j) {
    const double r = step_instant_resolution(recs[j]);
    if (!(r > 0)) continue;
    const Eigen::Vector4d by_theta = step_normal(recs, p, j).JtJ.col(2);
    const Eigen::VectorXd aj = C * on_free_params(by_theta, j, free_idx);
    W += r * r * aj * aj.transpose();
  }
  return W;
}

// The cluster-robust sandwich C B C, one cluster per step: B the sum over steps of each step's
// score g_j g_j^T (g_j = J_j^T r_j over the free parameters) times G/(G-1).
Eigen::MatrixXd cluster_robust_variance(const std::vector<StepRecord>& recs, const std::vector<double>& p,
                                        const std::vector<int>& free_idx, const Eigen::MatrixXd& C) {
  const int k = static_cast<int>(free_idx.size());
  const std::size_t G = recs.size();
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(k, k);
  for (std::size_t j = 0; j < G; ++j) {
    const Eigen::VectorXd gj = on_free_params(step_normal(recs, p, j).Jtr, j, free_idx);
    B += gj * gj.transpose();
  }
  B *= static_cast<double>(G) / static_cast<double>(G - 1);
  return C * B * C;
}

// Covariance of the pooled fit from its (3 + steps)-square normal matrix J^T J
// (pooled_normal_equations): s^2 (J^T J)^-1, what ceres::Covariance computes
// from the tall Jacobian with a dense SVD, at a cost independent of the number of samples.
// Rank checks: the one ceres::Covariance applies (DENSE_SVD: ratio of the extreme singular values
// of J below sqrt(min_reciprocal_condition)), and the one fill_covariance applies to single steps
// (the same ratio after scaling the columns to unit length, below min_reciprocal_condition).
void fill_pooled_covariance(FitResult& f, const std::vector<StepRecord>& recs, const LsqOptions& o) {
  const int n = static_cast<int>(f.params.size());
  std::vector<double> p;
  for (const auto& prm : f.params) p.push_back(prm.value);
  Eigen::MatrixXd N;
  Eigen::VectorXd g;
  pooled_normal_equations(recs, p, N, g);
  std::vector<int> free_idx;
  for (int j = 0; j < n; ++j)
    if (!f.params[static_cast<std::size_t>(j)].fixed) free_idx.push_back(j);
  const int k = static_cast<int>(free_idx.size());
  Eigen::MatrixXd A(k, k);
  for (int a = 0; a < k; ++a)
    for (int b = 0; b < k; ++b)
      A(a, b) = N(free_idx[static_cast<std::size_t>(a)], free_idx[static_cast<std::size_t>(b)]);
  Eigen::VectorXd d(k);
  for (int a = 0; a < k; ++a) d(a) = 1.0 / std::sqrt(std::max(A(a, a), 1e-300));
  const Eigen::MatrixXd S = d.asDiagonal() * A * d.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> raw(A, Eigen::EigenvaluesOnly);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(S);
  const double rmin = raw.eigenvalues().minCoeff(), rmax = raw.eigenvalues().maxCoeff();
  const double lmin = es.eigenvalues().minCoeff(), lmax = es.eigenvalues().maxCoeff();
  std::string names;
  for (int j : free_idx) names += (names.empty() ? "" : ", ") + f.params[static_cast<std::size_t>(j)].name;
  const bool raw_ok = rmax > 0 && rmin > 0 && rmin / rmax >= o.min_reciprocal_condition;
  const bool scaled_ok = lmax > 0 && lmin > 0 && std::sqrt(lmin / lmax) >= std::max(o.min_reciprocal_condition, 1e-10);
  if (!raw_ok || !scaled_ok)
    throw FitError(f.model + ": parameters not identifiable from these data (the Jacobian of " + names +
                   " is rank deficient); record a longer or richer response, or fix a parameter");
  const int dof = f.diagnostics.num_observations - k;
  if (dof <= 0) throw FitError(f.model + ": as many parameters as data points; no uncertainty can be estimated");
  // (J^T J)^-1 = D S^-1 D, S^-1 from its eigen-decomposition (the SVD of a symmetric positive
  // definite matrix).
  const Eigen::MatrixXd Sinv =
      es.eigenvectors() * es.eigenvalues().cwiseInverse().asDiagonal() * es.eigenvectors().transpose();
  const Eigen::MatrixXd C = d.asDiagonal() * Sinv * d.asDiagonal();
  const double s2 = o.absolute_sigma ? 1.0 : f.diagnostics.rss / dof;
  Eigen::MatrixXd V = C * s2;
  double tq = t_multiplier(o.confidence, dof);
  std::string method = "wald";
  // Residuals that are not white say the model does not describe the data exactly (a ramped
  // feed, a sampled dead time, a plant that is not quite first order): their errors are
  // correlated within each step, and s^2 (J^T J)^-1 is too sure. The cluster-robust sandwich
  // C B C with one cluster per step (Liang and Zeger, "Longitudinal data analysis using
  // generalized linear models", 1986; small-sample factor G/(G-1), t with G-1 degrees of
  // freedom: Cameron and Miller, "A practitioner's guide to cluster-robust inference", 2015)
  // takes whatever correlation there is within a step; an interval is never made narrower
  // than the noise-only one.
  const std::size_t G = recs.size();
  const bool not_white = !o.absolute_sigma && f.diagnostics.whiteness_p < kWhitenessRobustP;
  if (not_white && G >= 4) {
    Eigen::MatrixXd R = cluster_robust_variance(recs, p, free_idx, C);
    bool wider = false;
    for (int a = 0; a < k; ++a) {
      if (free_idx[static_cast<std::size_t>(a)] < 3 && R(a, a) > V(a, a)) wider = true;
      R(a, a) = std::max(R(a, a), V(a, a));  // never narrower than the noise-only variance
    }
    if (wider) {
      V = R;
      method = "cluster-robust over steps";
      tq = t_multiplier(o.confidence, static_cast<int>(G) - 1);
    }
  }
  const Eigen::MatrixXd W = instant_resolution_variance(recs, p, free_idx, C);
  if (W.trace() > 0) {
    V += W;
    method += ", with the step instants' sampling resolution";
  }
  f.covariance.assign(static_cast<std::size_t>(n * n), 0.0);
  for (int a = 0; a < k; ++a)
    for (int b = 0; b < k; ++b)
      f.covariance[static_cast<std::size_t>(free_idx[static_cast<std::size_t>(a)] * n +
                                            free_idx[static_cast<std::size_t>(b)])] = V(a, b);
  for (int a = 0; a < k; ++a) {
    const int j = free_idx[static_cast<std::size_t>(a)];
    auto& prm = f.params[static_cast<std::size_t>(j)];
    prm.ci95_method = method;
    const double var = V(a, a);
    prm.std_error = var >= 0 ? std::sqrt(var) : kNaN;
    prm.ci95_lo = prm.value - tq * prm.std_error;
    prm.ci95_hi = prm.value + tq * prm.std_error;
    if (!std::isfinite(prm.std_error))
      throw FitError(f.model + ": the uncertainty of " + prm.name + " is not finite; it is not identifiable");
  }
}

// The pooled fit's parameters: K, tau_s and theta_s shared by the steps (from `start` or the
// first step's log-incomplete start; theta fixed at 0 for the first-order model), then one
// offset y0_j per step (the mean before its step).
std::vector<ParamSpec> pooled_params(const std::vector<StepRecord>& recs, StepModel model, const FitResult* start,
                                     double min_duration, double max_duration) {
  double K0, tau0, theta0;
  if (start != nullptr) {
    K0 = start->value("K");
    tau0 = start->value("tau_s");
    theta0 = start->value("theta_s");
  } else {
    const auto st = log_incomplete_start(recs.front());
    K0 = st.K;
    tau0 = st.tau_s;
    theta0 = st.theta_s;
  }
  if (model == StepModel::fo) theta0 = 0;
  std::vector<ParamSpec> params = {{"K", recs.front().gain_unit, K0},
                                   {"tau_s", "s", tau0, 1e-9, kTauMaxFactor * max_duration},
                                   {"theta_s", "s", theta0, 0.0, 0.9 * min_duration, model == StepModel::fo}};
  for (std::size_t j = 0; j < recs.size(); ++j) {
    const auto& r = recs[j];
    double y0 = r.y.front();
    std::size_t before = 0;
    for (double t : r.t)
      if (t < r.t_step) ++before;
    if (before > 0) y0 = mean_of(r.y, 0, before);
    params.push_back({"y0_" + std::to_string(j), r.output_unit, y0});
  }
  return params;
}

// The start of the pooled solve: the shared parameters within their bounds and the offsets,
// polished on the normal equations (polish_pooled_start).
void polished_pooled_start(const std::vector<StepRecord>& recs, const std::vector<ParamSpec>& params, double shared[3],
                           std::vector<double>& y0) {
  const std::size_t k = params.size();
  for (int j = 0; j < 3; ++j) {
    const auto& ps = params[static_cast<std::size_t>(j)];
    shared[j] = std::clamp(ps.start, ps.lower, ps.upper);
  }
  y0.resize(recs.size());
  for (std::size_t j = 0; j < recs.size(); ++j) y0[j] = params[3 + j].start;
  std::vector<double> p(k), lo(k), hi(k);
  std::vector<bool> fixed(k);
  for (std::size_t j = 0; j < k; ++j) {
    p[j] = j < 3 ? shared[j] : y0[j - 3];
    lo[j] = params[j].lower;
    hi[j] = params[j].upper;
    fixed[j] = params[j].fixed;
  }
  polish_pooled_start(recs, p, lo, hi, fixed);
  for (std::size_t j = 0; j < k; ++j) (j < 3 ? shared[j] : y0[j - 3]) = p[j];
}

// One residual block per step (PooledStepCost): Ceres eliminates the offsets y0_j and solves
// a dense system in K, tau_s, theta_s only (DENSE_SCHUR), with the same Levenberg-Marquardt
// iteration and bounds as solve_least_squares. FitError when the solve fails or does not
// converge where convergence is required.
ceres::Solver::Summary solve_pooled(const std::vector<StepRecord>& recs, StepModel model,
                                    const std::vector<ParamSpec>& params, double shared[3], std::vector<double>& y0,
                                    const LsqOptions& options, const std::string& name) {
  ceres::Problem::Options popt;
  popt.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(popt);
  for (std::size_t j = 0; j < recs.size(); ++j)
    problem.AddResidualBlock(new PooledStepCost(recs[j]), nullptr, shared, &y0[j]);
  for (int j = 1; j < 3; ++j) {
    problem.SetParameterLowerBound(shared, j, params[static_cast<std::size_t>(j)].lower);
    problem.SetParameterUpperBound(shared, j, params[static_cast<std::size_t>(j)].upper);
  }
  if (model == StepModel::fo) problem.SetManifold(shared, new ceres::SubsetManifold(3, {2}));
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_SCHUR;
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (double& v : y0) ordering->AddElementToGroup(&v, 0);  // eliminated first
  ordering->AddElementToGroup(shared, 1);
  so.linear_solver_ordering = ordering;
  so.max_num_iterations = options.max_iterations;
  // As in fit_step: the polished start is at the optimum to about 1e-8 in cost, Ceres confirms
  // it; its default tolerances (1e-15) would have it shrink rejected steps for several
  // iterations before giving up on the last digits.
  so.function_tolerance = std::max(options.function_tolerance, 1e-12);
  so.gradient_tolerance = options.gradient_tolerance;
  so.parameter_tolerance = std::max(options.parameter_tolerance, 1e-12);
  so.logging_type = ceres::SILENT;
  so.minimizer_progress_to_stdout = false;
  so.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  if (summary.termination_type == ceres::FAILURE || summary.termination_type == ceres::USER_FAILURE ||
      !summary.IsSolutionUsable())
    throw FitError(name + ": " + detail::plain_solver_failure(summary));
  if (summary.termination_type == ceres::NO_CONVERGENCE && options.require_convergence)
    throw FitError(name + ": did not converge in " + std::to_string(options.max_iterations) + " iterations");
  return summary;
}

// The solved parameters into the result, with a warning for each that ended on a bound;
// FitError when one is not finite.
void collect_pooled_params(FitResult& f, const std::vector<ParamSpec>& params, const double shared[3],
                           const std::vector<double>& y0) {
  for (std::size_t j = 0; j < params.size(); ++j) {
    const auto& ps = params[j];
    const double v = j < 3 ? shared[j] : y0[j - 3];
    if (!std::isfinite(v)) throw FitError(f.model + ": the solution is not finite (" + f.diagnostics.solver + ")");
    Param p;
    p.name = ps.name;
    p.unit = ps.unit;
    p.value = v;
    p.fixed = ps.fixed;
    if (!ps.fixed && (v <= ps.lower || v >= ps.upper))
      f.warnings.push_back(ps.name + " ended on its bound (" + std::to_string(v) + ")");
    f.params.push_back(std::move(p));
  }
}

// Residual diagnostics at the solution, the residuals in time order step after step (m of them).
void pooled_residual_diagnostics(FitResult& f, const std::vector<StepRecord>& recs, const double shared[3],
                                 const std::vector<double>& y0, std::size_t m) {
  std::vector<double> res(m), observed;
  observed.reserve(m);
  std::size_t off = 0;
  for (std::size_t j = 0; j < recs.size(); ++j) {
    const auto& r = recs[j];
    const std::size_t cols[4] = {0, 1, 2, 3};
    step_residuals(r, shared[0], shared[1], shared[2], y0[j], res.data() + off, nullptr, 4, cols);
    observed.insert(observed.end(), r.y.begin(), r.y.end());
    off += r.t.size();
  }
  fill_residual_diagnostics(f, res, observed, true);
}

}  // namespace

FitResult fit_steps_pooled(const std::vector<StepRecord>& recs, StepModel model, const FitResult* start,
                           const LsqOptions& options) {
  if (recs.empty()) throw InputError("pooled step fit: no steps");
  if (recs.size() == 1) return fit_step(recs.front(), model, options);
  std::size_t m = 0;
  double min_duration = 1e300, max_duration = 0;
  for (const auto& r : recs) {
    check_record(r, model_name(model) + " (pooled)");
    m += r.t.size();
    min_duration = std::min(min_duration, response_duration(r));
    max_duration = std::max(max_duration, response_duration(r));
  }
  const std::size_t k = 3 + recs.size();
  const std::vector<ParamSpec> params = pooled_params(recs, model, start, min_duration, max_duration);
  quiet_solver_logging();
  const std::string name = model_name(model) + "_pooled";
  double shared[3];
  std::vector<double> y0;
  polished_pooled_start(recs, params, shared, y0);
  const ceres::Solver::Summary summary = solve_pooled(recs, model, params, shared, y0, options, name);
  FitResult f;
  f.model = name;
  f.diagnostics.iterations = static_cast<int>(summary.iterations.size());
  f.diagnostics.solver = summary.BriefReport();
  f.diagnostics.num_parameters = static_cast<int>(k) - (model == StepModel::fo ? 1 : 0);
  f.diagnostics.converged = summary.termination_type == ceres::CONVERGENCE;
  collect_pooled_params(f, params, shared, y0);
  pooled_residual_diagnostics(f, recs, shared, y0, m);
  if (options.compute_covariance) fill_pooled_covariance(f, recs, options);
  check_identifiable(f, nullptr, max_duration, options.compute_covariance);
  return f;
}

}  // namespace tunekit::fitting
