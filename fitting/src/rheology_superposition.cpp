// Time-temperature superposition of viscosity curves (a master curve with one shift factor per
// temperature level) and the test of whether the data superpose at all.
#include "tunekit/fitting/rheology_fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <boost/math/distributions/fisher_f.hpp>

#include <cstdarg>
#include <cstdio>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/profile_likelihood.hpp"
#include "tunekit/fitting/stats.hpp"
#include "rheology_fit_detail.hpp"

namespace tunekit::fitting {
namespace {

using rheology_detail::default_T_ref;
using rheology_detail::finish_params;
using rheology_detail::free_count;
using rheology_detail::kInf;
using rheology_detail::ln_cross_viscosity;
using rheology_detail::PSpec;
using rheology_detail::stats_of;
using rheology_detail::strf;
using rheology_detail::validate_data;

// What the master curve's residuals read: each point's temperature level, the index of each
// level's ln a_T parameter (-1 at the reference), ln viscosity and ln shear rate.
struct TtsRows {
  const RheologyData& data;
  std::vector<std::size_t> level_of;
  std::vector<int> shift_index;
  std::vector<double> ln_obs, ln_g;
};

// Residuals ln eta - ln eta_observed of the points idx on the master curve (Cross at T_ref with
// eta0 a_T at each other level; parameters ln eta0, ln tau*, n, ln a_T...) and their Jacobian.
ResidualJacobianFunction tts_residuals(const TtsRows& rows, std::vector<std::size_t> idx, std::size_t np) {
  return [&rows, idx = std::move(idx), np](const double* p, double* r, double* J) {
    for (std::size_t k = 0; k < idx.size(); ++k) {
      const std::size_t i = idx[k];
      const int si = rows.shift_index[rows.level_of[i]];
      double d[3];
      r[k] = ln_cross_viscosity(p[0] + (si < 0 ? 0.0 : p[si]), rows.ln_g[i], p[1], p[2], J != nullptr ? d : nullptr) -
             rows.ln_obs[i];
      if (!std::isfinite(r[k])) return false;
      if (J == nullptr) continue;
      double* row = J + np * k;
      std::fill(row, row + np, 0.0);
      std::copy(d, d + 3, row);
      if (si >= 0) row[si] = d[0];  // ln a_T enters as ln eta0 does
    }
    return true;
  };
}

// The same residuals through cross_viscosity, for the start search (which needs no derivatives).
ResidualFunction tts_search_residuals(const TtsRows& rows, std::vector<std::size_t> idx) {
  return [&rows, idx = std::move(idx)](const double* p, double* r) {
    const double eta0 = std::exp(p[0]), ts = std::exp(p[1]), nn = p[2];
    for (std::size_t k = 0; k < idx.size(); ++k) {
      const std::size_t i = idx[k];
      const int si = rows.shift_index[rows.level_of[i]];
      const double a = si < 0 ? 1.0 : std::exp(p[si]);
      const double e = cross_viscosity(eta0 * a, ts, nn, rows.data.shear_rate_1_s[i]);
      if (!(e > 0) || !std::isfinite(e)) return false;
      r[k] = std::log(e) - rows.ln_obs[i];
    }
    return true;
  };
}

}  // namespace

TtsResult time_temperature_superposition(const RheologyData& data, double T_ref_K) {
  validate_data(data);
  const auto st = stats_of(data);
  if (st.levels.size() < 2)
    throw InputError(
        strf("time-temperature superposition needs data at two or more temperatures (the data hold one, %.2f K)",
             st.levels.front()));
  TtsResult t;
  t.T_ref_K = std::isfinite(T_ref_K) ? T_ref_K : default_T_ref(st.levels);
  // Reference level index: the level nearest T_ref.
  std::size_t ref = 0;
  for (std::size_t k = 0; k < st.levels.size(); ++k)
    if (std::abs(st.levels[k] - t.T_ref_K) < std::abs(st.levels[ref] - t.T_ref_K)) ref = k;
  if (std::abs(st.levels[ref] - t.T_ref_K) > 0.05)
    throw InputError(strf("the TTS reference temperature %.2f K is not one of the data's temperatures", t.T_ref_K));
  const std::size_t n = data.size(), L = st.levels.size();
  std::vector<std::size_t> level_of(n);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t k = 0; k < L; ++k)
      if (std::abs(data.temperature_K[i] - st.levels[k]) <= 0.05 + 1e-9) {
        level_of[i] = k;
        break;
      }
  std::vector<PSpec> specs{{"eta0_Pa_s", "Pa.s", true, st.eta_min / 10, st.eta_max * 1e4, st.eta_max},
                           {"tau_star_Pa", "Pa", true, 1, 1e8, 1e5},
                           {"n", "1", false, 0.01, 1.0, 0.4}};
  std::vector<int> shift_index(L, -1);
  for (std::size_t k = 0; k < L; ++k) {
    if (k == ref) continue;
    shift_index[k] = static_cast<int>(specs.size());
    specs.push_back({strf("ln_aT_%.2fK", st.levels[k]), "1", false, -30, 30, 0});
  }
  if (static_cast<int>(n) <= free_count(specs))
    throw InputError(strf("TTS: %zu data points for %d parameters", n, free_count(specs)));
  LsqProblem prob;
  for (const auto& s : specs)
    prob.params.push_back({s.name, s.unit, s.log ? std::log(s.start) : s.start, s.log ? std::log(s.lo) : s.lo,
                           s.log ? std::log(s.hi) : s.hi});
  prob.num_residuals = static_cast<int>(n);
  prob.residuals_are_time_ordered = false;
  TtsRows rows{data, level_of, shift_index, {}, {}};
  for (std::size_t i = 0; i < n; ++i) {
    rows.ln_obs.push_back(std::log(data.viscosity_Pa_s[i]));
    rows.ln_g.push_back(std::log(data.shear_rate_1_s[i]));
  }
  prob.observed = rows.ln_obs;
  std::vector<std::size_t> all(n);
  for (std::size_t i = 0; i < n; ++i) all[i] = i;
  prob.residuals_and_jacobian = tts_residuals(rows, std::move(all), prob.params.size());
  prob.same_residuals_with_jacobian = true;
  constexpr std::size_t kSearchPerLevel = 60;
  std::vector<std::vector<std::size_t>> rows_of(L);
  for (std::size_t i = 0; i < n; ++i) rows_of[level_of[i]].push_back(i);
  std::vector<std::size_t> sub;
  for (const auto& level_rows : rows_of) {
    const std::size_t m = std::min(level_rows.size(), kSearchPerLevel);
    for (std::size_t j = 0; j < m; ++j) sub.push_back(level_rows[j * level_rows.size() / m]);
  }
  std::sort(sub.begin(), sub.end());
  LsqProblem search = prob;
  search.num_residuals = static_cast<int>(sub.size());
  search.observed.clear();
  for (std::size_t i : sub) search.observed.push_back(rows.ln_obs[i]);
  search.residuals_and_jacobian = nullptr;
  search.residuals = tts_search_residuals(rows, sub);
  t.reference_fit = solve_with_global_start("cross+tts", prob, {}, {}, &search);
  finish_params(t.reference_fit, specs);
  t.reference_fit.params.push_back({"T_ref_K", t.T_ref_K, kNaN, kNaN, kNaN, "K", true});
  std::vector<double> lnA(L, 0.0), lnA_se(L, 0.0);
  for (std::size_t k = 0; k < L; ++k) {
    t.temperatures_K.push_back(st.levels[k]);
    if (shift_index[k] < 0) {
      t.shift_factor.push_back(1.0);
      t.shift_factor_lo.push_back(1.0);
      t.shift_factor_hi.push_back(1.0);
      continue;
    }
    const auto& p = t.reference_fit.params[static_cast<std::size_t>(shift_index[k])];
    lnA[k] = p.value;
    lnA_se[k] = p.std_error;
    t.shift_factor.push_back(std::exp(p.value));
    t.shift_factor_lo.push_back(std::exp(p.ci95_lo));
    t.shift_factor_hi.push_back(std::exp(p.ci95_hi));
  }
  for (std::size_t i = 0; i < n; ++i) {
    const double a = t.shift_factor[level_of[i]];
    t.reduced_shear_rate_1_s.push_back(a * data.shear_rate_1_s[i]);
    t.reduced_viscosity_Pa_s.push_back(data.viscosity_Pa_s[i] / a);
  }
  if (L >= 3) {
    // ln a_T = (Ea / R) (1/T - 1/T_ref), weighted by the shift factors' standard errors.
    std::vector<std::size_t> ks;
    for (std::size_t k = 0; k < L; ++k)
      if (k != ref) ks.push_back(k);
    LsqProblem ap;
    ap.params = {{"Ea_J_per_mol", "J/mol", 1e5, 0, 1e7}};
    ap.num_residuals = static_cast<int>(ks.size());
    ap.residuals_are_time_ordered = false;
    ap.residuals = [&](const double* p, double* r) {
      for (std::size_t q = 0; q < ks.size(); ++q) {
        const double T = st.levels[ks[q]];
        const double w = lnA_se[ks[q]] > 0 ? 1.0 / lnA_se[ks[q]] : 1.0;
        r[q] = w * (p[0] / kGasConstant * (1.0 / T - 1.0 / t.T_ref_K) - lnA[ks[q]]);
      }
      return true;
    };
    try {
      t.arrhenius = solve_least_squares("arrhenius-shift", ap);
      t.arrhenius.params.push_back({"T_ref_K", t.T_ref_K, kNaN, kNaN, kNaN, "K", true});
      t.has_arrhenius = true;
    } catch (const Error&) {
      t.has_arrhenius = false;
    }
  }
  return t;
}

nlohmann::json to_json(const TtsResult& t) {
  nlohmann::json j;
  j["reference_temperature_K"] = t.T_ref_K;
  nlohmann::json sf = nlohmann::json::array();
  for (std::size_t k = 0; k < t.temperatures_K.size(); ++k)
    sf.push_back({{"temperature_K", t.temperatures_K[k]},
                  {"a_T", t.shift_factor[k]},
                  {"ci95", {t.shift_factor_lo[k], t.shift_factor_hi[k]}}});
  j["shift_factors"] = sf;
  j["reference_fit"] = to_json(t.reference_fit);
  if (t.has_arrhenius) j["arrhenius"] = to_json(t.arrhenius);
  j["master_curve"] = {{"reduced_shear_rate_1_s", t.reduced_shear_rate_1_s},
                       {"reduced_viscosity_Pa_s", t.reduced_viscosity_Pa_s}};
  return j;
}

bool SuperpositionCheck::superposes() const {
  return reversals.empty() &&
         std::all_of(levels.begin(), levels.end(), [](const auto& l) { return l.on_master_curve; });
}

SuperpositionCheck check_superposition(const RheologyData& data, double T_ref_K, double alpha) {
  SuperpositionCheck c;
  c.alpha = alpha;
  c.tts = time_temperature_superposition(data, T_ref_K);
  const auto& t = c.tts;
  const std::size_t L = t.temperatures_K.size(), n = data.size();
  auto level_index = [&](double T) {
    std::size_t best = 0;
    for (std::size_t k = 0; k < L; ++k)
      if (std::abs(t.temperatures_K[k] - T) < std::abs(t.temperatures_K[best] - T)) best = k;
    return best;
  };
  // Residuals of every point on the master curve (Cross at T_ref, shifted).
  const double eta0 = t.reference_fit.value("eta0_Pa_s"), ts = t.reference_fit.value("tau_star_Pa"),
               nn = t.reference_fit.value("n");
  std::vector<double> rss_master(L, 0.0);
  std::vector<int> count(L, 0);
  std::vector<RheologyData> per(L);
  for (std::size_t i = 0; i < n; ++i) {
    const auto k = level_index(data.temperature_K[i]);
    const double a = t.shift_factor[k];
    const double r =
        std::log(cross_viscosity(eta0 * a, ts, nn, data.shear_rate_1_s[i])) - std::log(data.viscosity_Pa_s[i]);
    rss_master[k] += r * r;
    ++count[k];
    per[k].shear_rate_1_s.push_back(data.shear_rate_1_s[i]);
    per[k].viscosity_Pa_s.push_back(data.viscosity_Pa_s[i]);
    per[k].temperature_K.push_back(data.temperature_K[i]);
  }
  // Each temperature's own Cross fit (the alternative of the F test).
  constexpr int kOwnParams = 3, kMinOwnPoints = kOwnParams + 2;
  std::vector<double> rss_own(L, kNaN);
  double pooled = 0;
  int pooled_dof = 0;
  for (std::size_t k = 0; k < L; ++k) {
    if (count[k] < kMinOwnPoints) continue;
    ViscosityFitOptions o;
    o.model = ViscosityModel::cross;
    o.shift = TemperatureShift::none;
    o.profile_intervals = false;
    o.lsq.compute_covariance = false;
    try {
      const auto f = fit_viscosity(per[k], o);
      rss_own[k] = std::min(f.diagnostics.rss, rss_master[k]);
      pooled += rss_own[k];
      pooled_dof += count[k] - kOwnParams;
    } catch (const Error&) {
      rss_own[k] = kNaN;
    }
  }
  const double s2 = pooled_dof > 0
                        ? std::max(pooled / pooled_dof, residual_variance_floor({std::log(data.viscosity_Pa_s[0])}))
                        : kNaN;
  for (std::size_t k = 0; k < L; ++k) {
    SuperpositionLevel l;
    l.temperature_K = t.temperatures_K[k];
    l.points = count[k];
    l.shift_factor = t.shift_factor[k];
    l.shift_lo = t.shift_factor_lo[k];
    l.shift_hi = t.shift_factor_hi[k];
    l.rms_master_ln = count[k] > 0 ? std::sqrt(rss_master[k] / count[k]) : kNaN;
    if (std::isfinite(rss_own[k]) && std::isfinite(s2)) {
      l.rms_own_ln = std::sqrt(rss_own[k] / count[k]);
      const double df1 = kOwnParams - 1;
      l.f_statistic = std::max(0.0, (rss_master[k] - rss_own[k]) / df1 / s2);
      const boost::math::fisher_f_distribution<> fd(df1, pooled_dof);
      l.p_value = boost::math::cdf(boost::math::complement(fd, l.f_statistic));
      // Off the curve: a significant misfit that is also material (precise, digitized curves
      // make percent-level shape differences significant).
      l.on_master_curve = !(l.p_value < alpha && l.rms_master_ln > kSuperpositionTolerance);
    }
    c.levels.push_back(l);
  }
  for (std::size_t k = 0; k + 1 < L; ++k) {
    const auto& a = c.levels[k];
    const auto& b = c.levels[k + 1];
    if (b.shift_lo > a.shift_hi)
      c.reversals.push_back({a.temperature_K, b.temperature_K, b.shift_factor / a.shift_factor});
  }
  if (!c.reversals.empty()) {
    // A master curve across a transition fits neither side, so every temperature would look
    // off the curve: test each side of the transitions on its own instead.
    std::size_t first = 0;
    int seg = 0;
    for (std::size_t k = 0; k <= L; ++k) {
      const bool cut = k == L || std::any_of(c.reversals.begin(), c.reversals.end(), [&](const auto& r) {
                         return std::abs(r.upper_K - t.temperatures_K[k]) < 1e-9;
                       });
      if (!cut) continue;
      for (std::size_t q = first; q < k; ++q) {
        auto& l = c.levels[q];
        l.segment = seg;
        l.on_master_curve = true;  // a side with one temperature has nothing to superpose on
        l.f_statistic = l.p_value = l.rms_own_ln = kNaN;
      }
      if (k - first >= 2) {
        RheologyData side;
        for (std::size_t i = 0; i < n; ++i) {
          const auto lk = level_index(data.temperature_K[i]);
          if (lk < first || lk >= k) continue;
          side.shear_rate_1_s.push_back(data.shear_rate_1_s[i]);
          side.viscosity_Pa_s.push_back(data.viscosity_Pa_s[i]);
          side.temperature_K.push_back(data.temperature_K[i]);
        }
        try {
          const auto sc = check_superposition(side, kNaN, alpha);
          for (std::size_t q = first; q < k; ++q) {
            const auto& from = sc.levels[q - first];
            auto& l = c.levels[q];
            l.on_master_curve = from.on_master_curve;
            l.f_statistic = from.f_statistic;
            l.p_value = from.p_value;
            l.rms_own_ln = from.rms_own_ln;
            l.rms_master_ln = from.rms_master_ln;
          }
        } catch (const Error&) {
          // The side cannot be tested on its own; its temperatures keep "not tested".
        }
      }
      first = k;
      ++seg;
    }
  }
  return c;
}

nlohmann::json to_json(const SuperpositionCheck& c) {
  nlohmann::json levels = nlohmann::json::array();
  for (const auto& l : c.levels) {
    nlohmann::json j{{"temperature_K", l.temperature_K},
                     {"points", l.points},
                     {"segment", l.segment},
                     {"a_T", l.shift_factor},
                     {"a_T_ci95", {l.shift_lo, l.shift_hi}},
                     {"rms_master_ln", l.rms_master_ln},
                     {"tested", std::isfinite(l.p_value)},
                     {"on_master_curve", l.on_master_curve}};
    if (std::isfinite(l.p_value)) {  // untested levels (too few points) carry no statistic
      j["rms_own_ln"] = l.rms_own_ln;
      j["f_statistic"] = l.f_statistic;
      j["p_value"] = l.p_value;
    }
    levels.push_back(j);
  }
  nlohmann::json rev = nlohmann::json::array();
  for (const auto& r : c.reversals)
    rev.push_back({{"lower_K", r.lower_K}, {"upper_K", r.upper_K}, {"a_T_ratio", r.ratio}});
  return {
      {"test", "F test of each temperature's own Cross fit against the master curve (Cross at T_ref with a shift a_T)"},
      {"alpha", c.alpha},
      {"reference_temperature_K", c.tts.T_ref_K},
      {"superposes", c.superposes()},
      {"levels", levels},
      {"reversals", rev}};
}

}  // namespace tunekit::fitting
