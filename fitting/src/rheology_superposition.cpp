// Time-temperature superposition of viscosity curves (a master curve with one shift factor per
// temperature level) and the test of whether the data superpose at all.
#include "tunekit/fitting/rheology_fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

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

// The index of the temperature level nearest T_ref; InputError when none is within 0.05 K.
std::size_t reference_level(const std::vector<double>& levels, double T_ref_K) {
  std::size_t ref = 0;
  for (std::size_t k = 0; k < levels.size(); ++k)
    if (std::abs(levels[k] - T_ref_K) < std::abs(levels[ref] - T_ref_K)) ref = k;
  if (std::abs(levels[ref] - T_ref_K) > 0.05)
    throw InputError(strf("the TTS reference temperature %.2f K is not one of the data's temperatures", T_ref_K));
  return ref;
}

// Each point's temperature level (the first within 0.05 K of its temperature).
std::vector<std::size_t> level_of_points(const RheologyData& data, const std::vector<double>& levels) {
  std::vector<std::size_t> level_of(data.size());
  for (std::size_t i = 0; i < data.size(); ++i)
    for (std::size_t k = 0; k < levels.size(); ++k)
      if (std::abs(data.temperature_K[i] - levels[k]) <= 0.05 + 1e-9) {
        level_of[i] = k;
        break;
      }
  return level_of;
}

// The start search reads at most kSearchPerLevel points of each level, spread over its rows, in
// the data's order.
std::vector<std::size_t> search_subset(const std::vector<std::size_t>& level_of, std::size_t L) {
  constexpr std::size_t kSearchPerLevel = 60;
  std::vector<std::vector<std::size_t>> rows_of(L);
  for (std::size_t i = 0; i < level_of.size(); ++i) rows_of[level_of[i]].push_back(i);
  std::vector<std::size_t> sub;
  for (const auto& level_rows : rows_of) {
    const std::size_t m = std::min(level_rows.size(), kSearchPerLevel);
    for (std::size_t j = 0; j < m; ++j) sub.push_back(level_rows[j * level_rows.size() / m]);
  }
  std::sort(sub.begin(), sub.end());
  return sub;
}

// The master curve's problem: ln eta0, ln tau*, n and ln a_T of every level but the reference
// (specs), over all points.
LsqProblem master_curve_problem(const std::vector<PSpec>& specs, const TtsRows& rows) {
  const std::size_t n = rows.ln_obs.size();
  LsqProblem prob;
  for (const auto& s : specs)
    prob.params.push_back({s.name, s.unit, s.log ? std::log(s.start) : s.start, s.log ? std::log(s.lo) : s.lo,
                           s.log ? std::log(s.hi) : s.hi});
  prob.num_residuals = static_cast<int>(n);
  prob.residuals_are_time_ordered = false;
  prob.observed = rows.ln_obs;
  std::vector<std::size_t> all(n);
  for (std::size_t i = 0; i < n; ++i) all[i] = i;
  prob.residuals_and_jacobian = tts_residuals(rows, std::move(all), prob.params.size());
  prob.same_residuals_with_jacobian = true;
  return prob;
}

// The shift factors and their intervals per level from the master curve's ln a_T (1 at the
// reference); ln a_T and its standard error per level into lnA, lnA_se (0 at the reference).
void collect_shift_factors(TtsResult& t, const std::vector<double>& levels, const std::vector<int>& shift_index,
                           std::vector<double>& lnA, std::vector<double>& lnA_se) {
  for (std::size_t k = 0; k < levels.size(); ++k) {
    t.temperatures_K.push_back(levels[k]);
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
}

// ln a_T = (Ea / R) (1/T - 1/T_ref), weighted by the shift factors' standard errors, over the
// levels other than the reference; has_arrhenius false when it cannot be fitted.
void fit_arrhenius_shift(TtsResult& t, const std::vector<double>& levels, std::size_t ref,
                         const std::vector<double>& lnA, const std::vector<double>& lnA_se) {
  std::vector<std::size_t> ks;
  for (std::size_t k = 0; k < levels.size(); ++k)
    if (k != ref) ks.push_back(k);
  LsqProblem ap;
  ap.params = {{"Ea_J_per_mol", "J/mol", 1e5, 0, 1e7}};
  ap.num_residuals = static_cast<int>(ks.size());
  ap.residuals_are_time_ordered = false;
  ap.residuals = [&](const double* p, double* r) {
    for (std::size_t q = 0; q < ks.size(); ++q) {
      const double T = levels[ks[q]];
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
  const std::size_t ref = reference_level(st.levels, t.T_ref_K);
  const std::size_t n = data.size(), L = st.levels.size();
  const std::vector<std::size_t> level_of = level_of_points(data, st.levels);
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
  TtsRows rows{data, level_of, shift_index, {}, {}};
  for (std::size_t i = 0; i < n; ++i) {
    rows.ln_obs.push_back(std::log(data.viscosity_Pa_s[i]));
    rows.ln_g.push_back(std::log(data.shear_rate_1_s[i]));
  }
  const LsqProblem prob = master_curve_problem(specs, rows);
  const std::vector<std::size_t> sub = search_subset(level_of, L);
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
  collect_shift_factors(t, st.levels, shift_index, lnA, lnA_se);
  for (std::size_t i = 0; i < n; ++i) {
    const double a = t.shift_factor[level_of[i]];
    t.reduced_shear_rate_1_s.push_back(a * data.shear_rate_1_s[i]);
    t.reduced_viscosity_Pa_s.push_back(data.viscosity_Pa_s[i] / a);
  }
  if (L >= 3) fit_arrhenius_shift(t, st.levels, ref, lnA, lnA_se);
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

namespace {

// The index of the temperature nearest T (the first of equally near ones).
std::size_t nearest_level(const std::vector<double>& temperatures_K, double T) {
  std::size_t best = 0;
  for (std::size_t k = 0; k < temperatures_K.size(); ++k)
    if (std::abs(temperatures_K[k] - T) < std::abs(temperatures_K[best] - T)) best = k;
  return best;
}

// Per temperature level: the residual sum of squares of its points on the master curve (Cross at
// T_ref, shifted), their count and the points themselves.
struct MasterResiduals {
  std::vector<double> rss;
  std::vector<int> count;
  std::vector<RheologyData> per;
};

MasterResiduals master_residuals(const RheologyData& data, const TtsResult& t) {
  const std::size_t L = t.temperatures_K.size();
  const double eta0 = t.reference_fit.value("eta0_Pa_s"), ts = t.reference_fit.value("tau_star_Pa"),
               nn = t.reference_fit.value("n");
  MasterResiduals m{std::vector<double>(L, 0.0), std::vector<int>(L, 0), std::vector<RheologyData>(L)};
  for (std::size_t i = 0; i < data.size(); ++i) {
    const auto k = nearest_level(t.temperatures_K, data.temperature_K[i]);
    const double a = t.shift_factor[k];
    const double r =
        std::log(cross_viscosity(eta0 * a, ts, nn, data.shear_rate_1_s[i])) - std::log(data.viscosity_Pa_s[i]);
    m.rss[k] += r * r;
    ++m.count[k];
    m.per[k].shear_rate_1_s.push_back(data.shear_rate_1_s[i]);
    m.per[k].viscosity_Pa_s.push_back(data.viscosity_Pa_s[i]);
    m.per[k].temperature_K.push_back(data.temperature_K[i]);
  }
  return m;
}

constexpr int kOwnParams = 3, kMinOwnPoints = kOwnParams + 2;

// Each temperature's own Cross fit (the alternative of the F test): its residual sum of squares
// (at most the master curve's; NaN with too few points or no fit), and the pooled sum and
// degrees of freedom over the levels fitted.
struct OwnFits {
  std::vector<double> rss;
  double pooled = 0;
  int pooled_dof = 0;
};

OwnFits own_fits(const MasterResiduals& m) {
  const std::size_t L = m.rss.size();
  OwnFits own{std::vector<double>(L, kNaN), 0, 0};
  for (std::size_t k = 0; k < L; ++k) {
    if (m.count[k] < kMinOwnPoints) continue;
    ViscosityFitOptions o;
    o.model = ViscosityModel::cross;
    o.shift = TemperatureShift::none;
    o.profile_intervals = false;
    o.lsq.compute_covariance = false;
    try {
      const auto f = fit_viscosity(m.per[k], o);
      own.rss[k] = std::min(f.diagnostics.rss, m.rss[k]);
      own.pooled += own.rss[k];
      own.pooled_dof += m.count[k] - kOwnParams;
    } catch (const Error&) {
      own.rss[k] = kNaN;
    }
  }
  return own;
}

// Level k's test: the F statistic of the master curve against the level's own fit, with the
// pooled residual variance s2 of the own fits.
SuperpositionLevel level_test(const TtsResult& t, std::size_t k, const MasterResiduals& m, const OwnFits& own,
                              double s2, double alpha) {
  SuperpositionLevel l;
  l.temperature_K = t.temperatures_K[k];
  l.points = m.count[k];
  l.shift_factor = t.shift_factor[k];
  l.shift_lo = t.shift_factor_lo[k];
  l.shift_hi = t.shift_factor_hi[k];
  l.rms_master_ln = m.count[k] > 0 ? std::sqrt(m.rss[k] / m.count[k]) : kNaN;
  if (std::isfinite(own.rss[k]) && std::isfinite(s2)) {
    l.rms_own_ln = std::sqrt(own.rss[k] / m.count[k]);
    const double df1 = kOwnParams - 1;
    l.f_statistic = std::max(0.0, (m.rss[k] - own.rss[k]) / df1 / s2);
    l.p_value = f_test_p_value(l.f_statistic, df1, own.pooled_dof);
    // Off the curve: a significant misfit that is also material (precise, digitized curves
    // make percent-level shape differences significant).
    l.on_master_curve = !(l.p_value < alpha && l.rms_master_ln > kSuperpositionTolerance);
  }
  return l;
}

// Neighbouring temperatures whose shift factors' intervals are reversed (the upper one's above).
void find_reversals(SuperpositionCheck& c) {
  for (std::size_t k = 0; k + 1 < c.levels.size(); ++k) {
    const auto& a = c.levels[k];
    const auto& b = c.levels[k + 1];
    if (b.shift_lo > a.shift_hi)
      c.reversals.push_back({a.temperature_K, b.temperature_K, b.shift_factor / a.shift_factor});
  }
}

// Levels [first, k) of a side of the reversals, tested against their own master curve.
void test_side(SuperpositionCheck& c, const RheologyData& data, std::size_t first, std::size_t k, double alpha) {
  RheologyData side;
  for (std::size_t i = 0; i < data.size(); ++i) {
    const auto lk = nearest_level(c.tts.temperatures_K, data.temperature_K[i]);
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

// A master curve across a transition fits neither side, so every temperature would look off the
// curve: each side of the transitions is tested on its own instead.
void test_sides_of_reversals(SuperpositionCheck& c, const RheologyData& data, double alpha) {
  const auto& temps = c.tts.temperatures_K;
  const std::size_t L = temps.size();
  std::size_t first = 0;
  int seg = 0;
  for (std::size_t k = 0; k <= L; ++k) {
    const bool cut = k == L || std::any_of(c.reversals.begin(), c.reversals.end(),
                                           [&](const auto& r) { return std::abs(r.upper_K - temps[k]) < 1e-9; });
    if (!cut) continue;
    for (std::size_t q = first; q < k; ++q) {
      auto& l = c.levels[q];
      l.segment = seg;
      l.on_master_curve = true;  // a side with one temperature has nothing to superpose on
      l.f_statistic = l.p_value = l.rms_own_ln = kNaN;
    }
    if (k - first >= 2) test_side(c, data, first, k, alpha);
    first = k;
    ++seg;
  }
}

}  // namespace

SuperpositionCheck check_superposition(const RheologyData& data, double T_ref_K, double alpha) {
  SuperpositionCheck c;
  c.alpha = alpha;
  c.tts = time_temperature_superposition(data, T_ref_K);
  const auto& t = c.tts;
  const std::size_t L = t.temperatures_K.size();
  const MasterResiduals m = master_residuals(data, t);
  const OwnFits own = own_fits(m);
  const double s2 = own.pooled_dof > 0 ? std::max(own.pooled / own.pooled_dof,
                                                  residual_variance_floor({std::log(data.viscosity_Pa_s[0])}))
                                       : kNaN;
  for (std::size_t k = 0; k < L; ++k) c.levels.push_back(level_test(t, k, m, own, s2, alpha));
  find_reversals(c);
  if (!c.reversals.empty()) test_sides_of_reversals(c, data, alpha);
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
