#include "tunekit/ident/input_shaper.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>

#include <fmt/format.h>

#include "tunekit/fitting/error.hpp"
#include "tunekit/ident/csv.hpp"

namespace tunekit::ident {
namespace {

constexpr double kPi = std::numbers::pi;

void normalize(Shaper& s) {
  double sum = 0;
  for (double a : s.amplitudes) sum += a;
  for (double& a : s.amplitudes) a /= sum;
}

const std::vector<ShaperInfo>& infos() {
  // Minimum frequencies as Klipper chose them (projected max_accel about 1500 mm/s^2); ZVDD,
  // which Klipper does not define, gets the 2-hump EI value (same duration, 1.5 periods).
  static const std::vector<ShaperInfo> v = {
      {ShaperType::zv, 21.0, 0.99},          {ShaperType::mzv, 23.0, 0.99},
      {ShaperType::zvd, 29.0, 0.99},         {ShaperType::zvdd, 39.0, 0.99},
      {ShaperType::ei, 29.0, 0.4},           {ShaperType::two_hump_ei, 39.0, 0.3},
      {ShaperType::three_hump_ei, 48.0, 0.2}};
  return v;
}

bool uniform_grid(std::span<const double> f) {
  if (f.size() < 3) return false;
  const double step = (f.back() - f.front()) / static_cast<double>(f.size() - 1);
  if (!(step > 0)) return false;
  for (std::size_t i = 0; i < f.size(); ++i)
    if (std::abs(f[i] - (f.front() + step * static_cast<double>(i))) > 1e-9 * std::max(1.0, std::abs(f.back())))
      return false;
  return true;
}

}  // namespace

std::string to_string(ShaperType t) {
  switch (t) {
    case ShaperType::zv: return "zv";
    case ShaperType::mzv: return "mzv";
    case ShaperType::zvd: return "zvd";
    case ShaperType::zvdd: return "zvdd";
    case ShaperType::ei: return "ei";
    case ShaperType::two_hump_ei: return "2hump_ei";
    case ShaperType::three_hump_ei: return "3hump_ei";
  }
  return "?";
}

ShaperType parse_shaper_type(const std::string& name) {
  for (const auto& i : infos())
    if (iequals(name, to_string(i.type))) return i.type;
  throw InputError("unknown shaper '" + name + "' (zv, mzv, zvd, zvdd, ei, 2hump_ei, 3hump_ei)");
}

const std::vector<ShaperType>& all_shaper_types() {
  static const std::vector<ShaperType> v = {ShaperType::zv,   ShaperType::mzv, ShaperType::zvd,
                                            ShaperType::zvdd, ShaperType::ei,  ShaperType::two_hump_ei,
                                            ShaperType::three_hump_ei};
  return v;
}

const ShaperInfo& shaper_info(ShaperType t) {
  for (const auto& i : infos())
    if (i.type == t) return i;
  return infos().front();
}

Shaper design_shaper(ShaperType type, double f, double z, double V) {
  if (!(f > 0) || !std::isfinite(f)) throw InputError(fmt::format("shaper frequency {} Hz must be positive", f));
  if (!(z >= 0 && z < 1)) throw InputError(fmt::format("damping ratio {} must be in [0, 1)", z));
  Shaper s;
  s.type = type;
  s.freq_hz = f;
  s.damping_ratio = z;
  const double df = std::sqrt(1 - z * z);
  const double K = std::exp(-z * kPi / df);  // decay over half a damped period
  const double td = 1.0 / (f * df);          // damped period
  switch (type) {
    case ShaperType::zv:  // Singer & Seering: zero vibration at (f, z)
      s.amplitudes = {1, K};
      s.times_s = {0, 0.5 * td};
      break;
    case ShaperType::zvd:  // plus zero derivative in frequency
      s.amplitudes = {1, 2 * K, K * K};
      s.times_s = {0, 0.5 * td, td};
      break;
    case ShaperType::zvdd:  // plus zero second derivative
      s.amplitudes = {1, 3 * K, 3 * K * K, K * K * K};
      s.times_s = {0, 0.5 * td, td, 1.5 * td};
      break;
    case ShaperType::mzv: {  // Klipper's modified ZV: impulses 3/8 of a period apart
      const double k = std::exp(-0.75 * z * kPi / df);
      const double a1 = 1 - 1 / std::numbers::sqrt2;
      s.amplitudes = {a1, (std::numbers::sqrt2 - 1) * k, a1 * k * k};
      s.times_s = {0, 0.375 * td, 0.75 * td};
      break;
    }
    case ShaperType::ei: {  // Singhose: V(f) = V_tol with zero slope at f; damped by the K factors
      const double a1 = 0.25 * (1 + V);
      s.amplitudes = {a1, 0.5 * (1 - V) * K, a1 * K * K};
      s.times_s = {0, 0.5 * td, td};
      break;
    }
    case ShaperType::two_hump_ei: {  // Singhose's two-hump EI closed form
      const double V2 = V * V;
      const double X = std::cbrt(V2 * (std::sqrt(1 - V2) + 1));
      const double a1 = (3 * X * X + 2 * X + 3 * V2) / (16 * X);
      const double a2 = 0.5 - a1;
      s.amplitudes = {a1, a2 * K, a2 * K * K, a1 * K * K * K};
      s.times_s = {0, 0.5 * td, td, 1.5 * td};
      break;
    }
    case ShaperType::three_hump_ei: {  // Singhose's three-hump EI closed form
      const double a1 = (1 + 3 * V + 2 * std::sqrt(2 * (V + 1) * V)) / 16;
      const double a2 = 0.25 * (1 - V);
      const double a3 = 0.5 * (1 + V) - 2 * a1;
      const double K2 = K * K;
      s.amplitudes = {a1, a2 * K, a3 * K2, a2 * K2 * K, a1 * K2 * K2};
      s.times_s = {0, 0.5 * td, td, 1.5 * td, 2 * td};
      break;
    }
  }
  normalize(s);
  return s;
}

double residual_vibration(const Shaper& s, double f, double z) {
  const double w = 2 * kPi * f;
  const double wd = w * std::sqrt(std::max(0.0, 1 - z * z));
  const double tn = s.duration_s();
  double c = 0, sn = 0, sum = 0;
  for (std::size_t i = 0; i < s.amplitudes.size(); ++i) {
    const double a = s.amplitudes[i] * std::exp(-z * w * (tn - s.times_s[i]));
    c += a * std::cos(wd * s.times_s[i]);
    sn += a * std::sin(wd * s.times_s[i]);
    sum += s.amplitudes[i];
  }
  return std::hypot(c, sn) / sum;
}

std::vector<double> residual_vibration_curve(const Shaper& s, std::span<const double> f, double z) {
  std::vector<double> v(f.size());
  if (!uniform_grid(f)) {
    for (std::size_t b = 0; b < f.size(); ++b) v[b] = residual_vibration(s, f[b], z);
    return v;
  }
  // On a uniform grid f_b = f_0 + b df every impulse's factor exp((-z w (T_n - T_i)) + j w_d T_i)
  // is a geometric sequence in b: one complex multiplication per bin and impulse.
  const double step = (f.back() - f.front()) / static_cast<double>(f.size() - 1);
  const double dz = std::sqrt(std::max(0.0, 1 - z * z));
  const double tn = s.duration_s();
  double sum = 0;
  for (double a : s.amplitudes) sum += a;
  std::vector<std::complex<double>> acc(f.size(), {0, 0});
  for (std::size_t i = 0; i < s.amplitudes.size(); ++i) {
    const double decay = -z * 2 * kPi * (tn - s.times_s[i]);
    const double phase = 2 * kPi * dz * s.times_s[i];
    const std::complex<double> ratio = std::exp(std::complex<double>(decay * step, phase * step));
    std::complex<double> cur = s.amplitudes[i] * std::exp(std::complex<double>(decay * f.front(), phase * f.front()));
    for (std::size_t b = 0; b < f.size(); ++b) {
      acc[b] += cur;
      cur *= ratio;
    }
  }
  for (std::size_t b = 0; b < f.size(); ++b) v[b] = std::sqrt(std::norm(acc[b])) / sum;
  return v;
}

namespace {
struct SmoothingTerms {
  double s1 = 0;   // sum_{T_i >= ts} A_i (T_i - ts)
  double s2p = 0;  // sum_{T_i >= ts} A_i (T_i - ts)^2
  double s2 = 0;   // sum_i A_i (T_i - ts)^2
};
SmoothingTerms smoothing_terms(const Shaper& s) {
  double sum = 0, ts = 0;
  for (std::size_t i = 0; i < s.amplitudes.size(); ++i) {
    sum += s.amplitudes[i];
    ts += s.amplitudes[i] * s.times_s[i];
  }
  ts /= sum;
  SmoothingTerms t;
  for (std::size_t i = 0; i < s.amplitudes.size(); ++i) {
    const double a = s.amplitudes[i] / sum, d = s.times_s[i] - ts;
    if (d >= 0) {
      t.s1 += a * d;
      t.s2p += a * d * d;
    }
    t.s2 += a * d * d;
  }
  return t;
}
}  // namespace

double shaper_smoothing(const Shaper& s, double accel, double scv) {
  const auto t = smoothing_terms(s);
  const double s90 = std::numbers::sqrt2 * (scv * t.s1 + 0.5 * accel * t.s2p);
  const double s180 = 0.5 * accel * t.s2;
  return std::max(s90, s180);
}

double shaper_max_accel(const Shaper& s, double scv, double target) {
  const auto t = smoothing_terms(s);
  // s90(a) <= target  <=>  a <= 2 (target / sqrt2 - scv s1) / s2p ; s180(a) <= target <=> a <= 2 target / s2
  const double free90 = target / std::numbers::sqrt2 - scv * t.s1;
  if (free90 < 0) return 0;
  double a = std::numeric_limits<double>::infinity();
  if (t.s2p > 0) a = std::min(a, 2 * free90 / t.s2p);
  if (t.s2 > 0) a = std::min(a, 2 * target / t.s2);
  return a;
}

double remaining_vibrations(const Shaper& s, std::span<const double> f, std::span<const double> psd, double z,
                            double reduction) {
  const auto vals = residual_vibration_curve(s, f, z);
  const double threshold = *std::max_element(psd.begin(), psd.end()) / reduction;
  double remaining = 0, all = 0;
  for (std::size_t b = 0; b < psd.size(); ++b) {
    remaining += std::max(vals[b] * psd[b] - threshold, 0.0);
    all += std::max(psd[b] - threshold, 0.0);
  }
  return all > 0 ? remaining / all : 0.0;
}

ShaperSelection select_shaper(std::span<const double> freq, std::span<const double> psd_in,
                              const ShaperSelectionOptions& o) {
  if (freq.size() != psd_in.size()) throw InputError("frequency and PSD arrays differ in length");
  if (o.types.empty()) throw InputError("no shaper types to choose from");
  if (o.test_damping_ratios.empty()) throw InputError("no test damping ratios");
  for (double z : o.test_damping_ratios)
    if (!(z >= 0 && z < 1)) throw InputError(fmt::format("test damping ratio {} must be in [0, 1)", z));
  if (!(o.freq_step_hz > 0)) throw InputError("shaper frequency step must be positive");
  std::vector<double> f, psd;
  for (std::size_t b = 0; b < freq.size(); ++b)
    if (freq[b] <= o.max_freq_hz) {
      f.push_back(freq[b]);
      psd.push_back(psd_in[b]);
    }
  if (f.size() < 3 || !(*std::max_element(psd.begin(), psd.end()) > 0))
    throw InputError(fmt::format("the vibration spectrum below {} Hz is empty or zero; nothing to shape",
                                 o.max_freq_hz));

  // Only bins above the threshold contribute to the remaining vibrations: evaluate the shaper
  // there only, with the geometric recurrence when the grid is uniform.
  const double thr = *std::max_element(psd.begin(), psd.end()) / o.vibration_reduction;
  double all = 0;
  std::size_t b_lo = psd.size(), b_hi = 0;
  for (std::size_t b = 0; b < psd.size(); ++b)
    if (psd[b] > thr) {
      all += psd[b] - thr;
      b_lo = std::min(b_lo, b);
      b_hi = std::max(b_hi, b);
    }
  const bool uniform = uniform_grid(f);
  const double step = uniform ? (f.back() - f.front()) / static_cast<double>(f.size() - 1) : 0.0;
  std::vector<std::complex<double>> acc;
  auto vibrations = [&](const Shaper& sh, double z) {
    if (!(all > 0)) return 0.0;
    double remaining = 0;
    if (!uniform) {
      for (std::size_t b = b_lo; b <= b_hi; ++b)
        remaining += std::max(residual_vibration(sh, f[b], z) * psd[b] - thr, 0.0);
      return remaining / all;
    }
    const std::size_t nb = b_hi - b_lo + 1;
    acc.assign(nb, {0, 0});
    const double dz = std::sqrt(std::max(0.0, 1 - z * z));
    const double tn = sh.duration_s();
    for (std::size_t i = 0; i < sh.amplitudes.size(); ++i) {
      const double decay = -z * 2 * kPi * (tn - sh.times_s[i]);
      const double phase = 2 * kPi * dz * sh.times_s[i];
      const std::complex<double> ratio = std::exp(std::complex<double>(decay * step, phase * step));
      std::complex<double> cur = sh.amplitudes[i] * std::exp(std::complex<double>(decay * f[b_lo], phase * f[b_lo]));
      for (std::size_t b = 0; b < nb; ++b) {
        acc[b] += cur;
        cur *= ratio;
      }
    }
    for (std::size_t b = 0; b < nb; ++b) remaining += std::max(std::sqrt(std::norm(acc[b])) * psd[b_lo + b] - thr, 0.0);  // |acc|, without hypot's cost
    return remaining / all;
  };

  ShaperSelection sel;
  bool have_best = false;
  ShaperCandidate best;
  for (ShaperType type : o.types) {
    const auto& info = shaper_info(type);
    const double design_z = std::min(o.design_damping_ratio, info.max_damping_ratio);
    const double f_end = o.max_shaper_freq_hz;
    const double f_start = std::min(info.min_freq_hz, f_end - 1e-7);
    std::vector<double> test_freqs;
    for (std::size_t i = 0;; ++i) {
      const double tf = f_start + o.freq_step_hz * static_cast<double>(i);
      if (tf >= f_end) break;
      test_freqs.push_back(tf);
    }
    // Evaluate from the highest frequency down, as Klipper does (ties keep the higher one).
    std::vector<ShaperCandidate> results;
    results.reserve(test_freqs.size());
    std::size_t best_res = 0;
    for (auto it = test_freqs.rbegin(); it != test_freqs.rend(); ++it) {
      const Shaper sh = design_shaper(type, *it, design_z);
      ShaperCandidate c;
      c.type = type;
      c.freq_hz = *it;
      c.damping_ratio = design_z;
      c.smoothing_mm = shaper_smoothing(sh, 5000.0, o.scv_mm_s);
      if (o.max_smoothing_mm > 0 && c.smoothing_mm > o.max_smoothing_mm && !results.empty()) break;
      c.max_accel_mm_s2 = shaper_max_accel(sh, o.scv_mm_s, o.target_smoothing_mm);
      for (double z : o.test_damping_ratios)
        c.vibrations = std::max(c.vibrations, vibrations(sh, z));
      c.score = c.smoothing_mm * (std::pow(c.vibrations, 1.5) + 0.2 * c.vibrations + 0.01);
      results.push_back(c);
      if (results.size() == 1 || results[best_res].vibrations > c.vibrations) best_res = results.size() - 1;
    }
    if (results.empty()) continue;
    // The frequency with fewest vibrations, or a lower-scoring one (less smoothing) that is
    // not much worse (within 10 % + 0.05 percentage points), scanning from low frequencies.
    ShaperCandidate chosen = results[best_res];
    const double vibr_limit = results[best_res].vibrations * 1.1 + 0.0005;
    for (auto it = results.rbegin(); it != results.rend(); ++it)
      if (it->vibrations < vibr_limit && it->score < chosen.score) chosen = *it;
    // Across types: a new type wins by a 20 % better score, or a 5 % better score with 10 %
    // less smoothing.
    if (!have_best || chosen.score * 1.2 < best.score ||
        (chosen.score * 1.05 < best.score && chosen.smoothing_mm * 1.1 < best.smoothing_mm)) {
      best = chosen;
      have_best = true;
    }
    // Any frequency of this type with both fewer vibrations and less smoothing than the
    // current best replaces it (and becomes this type's reported candidate).
    for (auto it = results.rbegin(); it != results.rend(); ++it)
      if (it->vibrations < best.vibrations && it->smoothing_mm < best.smoothing_mm) {
        best = *it;
        chosen = *it;
      }
    sel.candidates.push_back(chosen);
  }
  if (!have_best) throw InputError("no shaper could be evaluated in the allowed frequency range");
  // ZV is only kept when no other type leaves clearly (10 %) fewer vibrations.
  if (best.type == ShaperType::zv)
    for (const auto& c : sel.candidates)
      if (c.type != ShaperType::zv && c.vibrations * 1.1 < best.vibrations) {
        best = c;
        break;
      }
  sel.recommended = best;
  return sel;
}

}  // namespace tunekit::ident
