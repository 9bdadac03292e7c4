#include "tunekit/fitting/greybox.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "tunekit/core/error.hpp"

namespace tunekit::fitting {

TransferFunction greybox_tf(const GreyBoxParams& p, double K) {
  TransferFunction tf;
  tf.num = {K * p.D_t, K * p.C_t};
  tf.den = {p.D_n * p.D_t / p.C_f, p.D_t + p.D_n + p.D_n * p.C_t / p.C_f, p.C_t};
  return tf;
}

GreyBoxCombinations greybox_combinations(const GreyBoxParams& p) {
  return {p.D_t / p.C_t, p.D_n / p.C_f, p.D_n / p.C_t};
}

FitResult fit_greybox_output_error(std::span<const double> u, std::span<const double> y, double dt,
                                   const GreyBoxFitOptions& o) {
  if (u.size() != y.size()) throw InputError("grey-box fit: input and output lengths differ");
  if (y.size() < 30) throw InputError("grey-box fit: too few samples (" + std::to_string(y.size()) + ")");
  if (!(dt > 0)) throw InputError("grey-box fit: the sample interval must be positive");
  if (!(o.C_f > 0)) throw InputError("grey-box fit: C_f must be positive");
  std::vector<double> du(u.size());
  for (std::size_t i = 0; i < u.size(); ++i) du[i] = u[i] - u[0];
  const std::vector<double> yv(y.begin(), y.end());
  const double T = dt * static_cast<double>(y.size());
  LsqProblem prob;
  prob.num_residuals = static_cast<int>(yv.size());
  prob.observed = yv;
  prob.residuals = [du, yv, dt](const double* p, double* r) {
    GreyBoxParams gp{p[0], p[1], p[2], p[3]};
    if (!(gp.C_f > 0 && gp.C_t > 0 && gp.D_t > 0 && gp.D_n > 0)) return false;
    std::vector<double> sim;
    try {
      sim = greybox_tf(gp, p[4]).simulate_zoh(du, dt);
    } catch (const InputError&) {
      return false;
    }
    for (std::size_t i = 0; i < yv.size(); ++i) {
      r[i] = sim[i] + p[5] - yv[i];
      if (!std::isfinite(r[i])) return false;
    }
    return true;
  };
  auto specs = [&](double tt, double tf, double tn) {
    // From the combinations with C_f given: D_n = tau_f C_f, C_t = D_n / tau_n, D_t = tau_t C_t.
    const double Dn = tf * o.C_f, Ct = Dn / tn, Dt = tt * Ct;
    const double tiny = std::numeric_limits<double>::min();
    return std::vector<ParamSpec>{{"C_f", "N/m", o.C_f, tiny, std::numeric_limits<double>::infinity(), o.fix_C_f},
                                  {"C_t", "N/m", Ct, tiny},
                                  {"D_t", "N.s/m", Dt, tiny},
                                  {"D_n", "N.s/m", Dn, tiny},
                                  {"K", o.gain_unit, 1.0, -std::numeric_limits<double>::infinity(),
                                   std::numeric_limits<double>::infinity(), !o.fit_gain},
                                  {"y0", "1", yv.front()}};
  };
  LsqOptions scan;
  scan.compute_covariance = false;
  scan.require_convergence = false;
  scan.max_iterations = 60;
  double best = std::numeric_limits<double>::infinity();
  std::vector<double> best_p;
  std::string last;
  const double grid[] = {T / 100, T / 10};
  for (double tt : grid)
    for (double tf : grid)
      for (double tn : grid) {
        prob.params = specs(tt, tf, tn);
        try {
          const auto r = solve_least_squares("greybox_appendix_c", prob, scan);
          if (r.diagnostics.rss < best) {
            best = r.diagnostics.rss;
            best_p.clear();
            for (const auto& q : r.params) best_p.push_back(q.value);
          }
        } catch (const FitError& e) {
          last = e.message();
        }
      }
  if (best_p.empty()) throw FitError("greybox_appendix_c: no start value led to a fit (" + last + ")");
  prob.params = specs(1, 1, 1);
  for (std::size_t i = 0; i < best_p.size(); ++i) prob.params[i].start = best_p[i];
  auto r = solve_least_squares("greybox_appendix_c", prob);
  const auto c = greybox_combinations({r.value("C_f"), r.value("C_t"), r.value("D_t"), r.value("D_n")});
  char buf[200];
  std::snprintf(buf, sizeof buf,
                "identifiable combinations: tau_t = D_t/C_t = %.4g s, tau_f = D_n/C_f = %.4g s, tau_n = D_n/C_t = "
                "%.4g s; C_t, D_t, D_n are relative to the fixed C_f",
                c.tau_t_s, c.tau_f_s, c.tau_n_s);
  r.warnings.push_back(buf);
  return r;
}

}  // namespace tunekit::fitting
