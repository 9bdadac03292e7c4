#include "tunekit/design/input_shaper.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <complex>
#include <exception>
#include <future>
#include <limits>
#include <numbers>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::design {
namespace {

constexpr double kPi = std::numbers::pi;

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

namespace {

// One dataset cut to the PSD frequency limit, with the bins that can count (above the
// threshold max/vibration_reduction: the shaper's |V| <= 1 cannot lift the others over it).
struct ScoredDataset {
  std::vector<double> f, psd;
  double thr = 0, all = 0;
  std::size_t lo = 0, hi = 0;
  bool uniform = false;
  double step = 0;
};

// Scratch of dataset_vibrations: the shaper's response summed over impulses, per bin.
struct ResponseSums {
  std::vector<double> re, im;
};

// Remaining vibration fraction of one shaper against one dataset at one test damping ratio.
// Built for AVX2 as well as the baseline: the four sequences then advance in one instruction.
[[gnu::target_clones("avx2", "default")]] double dataset_vibrations(const ScoredDataset& d, const Shaper& sh, double z,
                                                                    ResponseSums& acc) {
  if (!(d.all > 0)) return 0.0;
  double remaining = 0;
  if (!d.uniform) {
    for (std::size_t b = d.lo; b <= d.hi; ++b)
      remaining += std::max(residual_vibration(sh, d.f[b], z) * d.psd[b] - d.thr, 0.0);
    return remaining / d.all;
  }
  // Uniform bins: every impulse's factor exp((-z w (T_n - T_i)) + j w_d T_i) is a geometric
  // sequence in the bin index. It is run as four interleaved sequences (bins b, b+1, b+2, b+3,
  // each stepped by the ratio's fourth power), which the processor works on side by side: one
  // sequence alone waits on each multiplication's result.
  const std::size_t nb = d.hi - d.lo + 1;
  acc.re.assign(nb + 3, 0.0);
  acc.im.assign(nb + 3, 0.0);
  const double dz = std::sqrt(std::max(0.0, 1 - z * z));
  const double tn = sh.duration_s();
  for (std::size_t i = 0; i < sh.amplitudes.size(); ++i) {
    const double decay = -z * 2 * kPi * (tn - sh.times_s[i]);
    const double phase = 2 * kPi * dz * sh.times_s[i];
    const std::complex<double> ratio = std::exp(std::complex<double>(decay * d.step, phase * d.step));
    const std::complex<double> ratio2 = ratio * ratio, ratio4 = ratio2 * ratio2;
    double cr[4], ci[4];
    std::complex<double> c = sh.amplitudes[i] * std::exp(std::complex<double>(decay * d.f[d.lo], phase * d.f[d.lo]));
    for (int j = 0; j < 4; ++j, c *= ratio) {
      cr[j] = c.real();
      ci[j] = c.imag();
    }
    const double rr = ratio4.real(), ri = ratio4.imag();
    double* re = acc.re.data();
    double* im = acc.im.data();
    for (std::size_t b = 0; b < nb; b += 4)
      for (int j = 0; j < 4; ++j) {
        re[b + j] += cr[j];
        im[b + j] += ci[j];
        const double r = cr[j] * rr - ci[j] * ri;
        ci[j] = cr[j] * ri + ci[j] * rr;
        cr[j] = r;
      }
  }
  for (std::size_t b = 0; b < nb; ++b)
    remaining += std::max(std::sqrt(acc.re[b] * acc.re[b] + acc.im[b] * acc.im[b]) * d.psd[d.lo + b] - d.thr, 0.0);
  return remaining / d.all;
}

// The datasets cut at a PSD frequency limit (max_freq_hz, but never below the type's highest
// shaper frequency: Klipper's rule, per type), with the bins that can count.
std::vector<ScoredDataset> scored_datasets(std::span<const PsdDataset> datasets, double psd_limit,
                                           const ShaperSelectionOptions& o) {
  std::vector<ScoredDataset> sets;
  for (const auto& ds : datasets) {
    ScoredDataset d;
    for (std::size_t b = 0; b < ds.freq_hz.size(); ++b)
      if (ds.freq_hz[b] <= psd_limit) {
        d.f.push_back(ds.freq_hz[b]);
        d.psd.push_back(ds.psd[b]);
      }
    if (d.f.size() < 3 || !(*std::max_element(d.psd.begin(), d.psd.end()) > 0))
      throw InputError(fmt::format("the vibration spectrum below {} Hz is empty or zero; nothing to shape", psd_limit));
    d.thr = *std::max_element(d.psd.begin(), d.psd.end()) / o.vibration_reduction;
    d.lo = d.psd.size();
    for (std::size_t b = 0; b < d.psd.size(); ++b)
      if (d.psd[b] > d.thr) {
        d.all += d.psd[b] - d.thr;
        d.lo = std::min(d.lo, b);
        d.hi = std::max(d.hi, b);
      }
    d.uniform = uniform_grid(d.f);
    d.step = d.uniform ? (d.f.back() - d.f.front()) / static_cast<double>(d.f.size() - 1) : 0.0;
    sets.push_back(std::move(d));
  }
  return sets;
}

// One type's candidates, scored from its highest frequency down as Klipper does (ties keep the
// higher one), and which of them leaves the fewest vibrations.
struct TypeScan {
  std::vector<ShaperCandidate> results;
  std::size_t best = 0;
  bool smoothing_limited = false;  // the smoothing limit cut the scan short
};

TypeScan scan_type(ShaperType type, const std::vector<double>& test_freqs, std::span<const PsdDataset> datasets,
                   const ShaperSelectionOptions& o) {
  TypeScan scan;
  if (test_freqs.empty()) return scan;
  const auto sets = scored_datasets(datasets, std::max(o.max_freq_hz, test_freqs.back()), o);
  const double design_z = std::min(o.design_damping_ratio, shaper_info(type).max_damping_ratio);
  ResponseSums acc;
  auto& results = scan.results;
  results.reserve(test_freqs.size());
  for (auto it = test_freqs.rbegin(); it != test_freqs.rend(); ++it) {
    const Shaper sh = design_shaper(type, *it, design_z, kDefaultVibrationTolerance, o.ei_design);
    ShaperCandidate c;
    c.type = type;
    c.freq_hz = *it;
    c.damping_ratio = design_z;
    c.smoothing_mm = shaper_smoothing(sh, 5000.0, o.scv_mm_s);
    if (o.max_smoothing_mm > 0 && c.smoothing_mm > o.max_smoothing_mm && !results.empty()) {
      scan.smoothing_limited = true;
      break;
    }
    c.max_accel_mm_s2 = shaper_max_accel(sh, o.scv_mm_s, o.target_smoothing_mm);
    for (const auto& d : sets)
      for (double z : o.test_damping_ratios) c.vibrations = std::max(c.vibrations, dataset_vibrations(d, sh, z, acc));
    c.score = c.smoothing_mm * (std::pow(c.vibrations, 1.5) + 0.2 * c.vibrations + 0.01);
    results.push_back(c);
    if (results.size() == 1 || results[scan.best].vibrations > c.vibrations) scan.best = results.size() - 1;
  }
  return scan;
}

// InputError for no spectrum, no types, a test damping ratio outside [0, 1) or a frequency step
// or highest frequency that is not positive.
void check_selection_options(std::span<const PsdDataset> datasets, const ShaperSelectionOptions& o) {
  if (datasets.empty()) throw InputError("no vibration spectrum to choose a shaper for");
  if (o.types.empty()) throw InputError("no shaper types to choose from");
  if (o.test_damping_ratios.empty()) throw InputError("no test damping ratios");
  for (double z : o.test_damping_ratios)
    if (!(z >= 0 && z < 1)) throw InputError(fmt::format("test damping ratio {} must be in [0, 1)", z));
  if (!(o.freq_step_hz > 0)) throw InputError("shaper frequency step must be positive");
  if (!(o.max_shaper_freq_hz > 0)) throw InputError("the highest shaper frequency must be positive");
}

// Shaper frequencies per type: from the type's minimum up to (not including) the maximum.
std::vector<std::vector<double>> type_frequencies(const ShaperSelectionOptions& o) {
  std::vector<std::vector<double>> type_freqs;
  for (ShaperType type : o.types) {
    const double f_end = o.max_shaper_freq_hz;
    const double f_start = std::min(shaper_info(type).min_freq_hz, f_end - 1e-7);
    std::vector<double> tf;
    for (std::size_t i = 0;; ++i) {
      const double x = f_start + o.freq_step_hz * static_cast<double>(i);
      if (x >= f_end) break;
      tf.push_back(x);
    }
    type_freqs.push_back(std::move(tf));
  }
  return type_freqs;
}

// Each type's frequencies are scored on their own, on two threads that take the types in
// order of their work (impulses x frequencies, the largest first) as each finishes one. A type's
// error is raised after both threads are done, the first type's first, so the message is the
// one a single pass gives.
std::vector<TypeScan> scan_types_in_parallel(const std::vector<std::vector<double>>& type_freqs,
                                             std::span<const PsdDataset> datasets, const ShaperSelectionOptions& o) {
  std::vector<TypeScan> scans(o.types.size());
  std::vector<std::exception_ptr> errors(o.types.size());
  std::vector<std::size_t> order(o.types.size());
  std::vector<double> work(o.types.size());
  for (std::size_t ti = 0; ti < o.types.size(); ++ti) {
    order[ti] = ti;
    const auto impulses =
        design_shaper(o.types[ti], 50.0, 0.1, kDefaultVibrationTolerance, o.ei_design).amplitudes.size();
    work[ti] = static_cast<double>(impulses * type_freqs[ti].size());
  }
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return work[a] > work[b]; });
  std::atomic<std::size_t> next{0};
  auto scan_types = [&] {
    for (std::size_t k; (k = next.fetch_add(1)) < order.size();) {
      const std::size_t ti = order[k];
      try {
        scans[ti] = scan_type(o.types[ti], type_freqs[ti], datasets, o);
      } catch (...) {
        errors[ti] = std::current_exception();
      }
    }
  };
  {
    auto other = std::async(o.types.size() > 1 ? std::launch::async : std::launch::deferred, scan_types);
    scan_types();
    other.get();
  }
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
  return scans;
}

// A type's candidate: the frequency with fewest vibrations, or a lower-scoring one (less
// smoothing) that is not much worse (within 10 % + 0.05 percentage points), scanning from low
// frequencies. When the smoothing limit cut the scan short, Klipper keeps the fewest-vibrations
// one. Above a vibrations limit the lowest such frequency is taken whatever its score.
ShaperCandidate type_candidate(const TypeScan& scan, const ShaperSelectionOptions& o) {
  const auto& results = scan.results;
  const std::size_t best_res = scan.best;
  ShaperCandidate chosen = results[best_res];
  if (!scan.smoothing_limited) {
    const double vibr_limit = results[best_res].vibrations * 1.1 + 0.0005;
    const bool over = o.max_vibrations.has_value() && results[best_res].vibrations > o.max_vibrations.value_or(0.0);
    for (auto it = results.rbegin(); it != results.rend(); ++it)
      if (it->vibrations < vibr_limit && (it->score < chosen.score || over)) chosen = *it;
  }
  return chosen;
}

}  // namespace

ShaperSelection select_shaper(std::span<const double> freq, std::span<const double> psd,
                              const ShaperSelectionOptions& o) {
  if (freq.size() != psd.size()) throw InputError("frequency and PSD arrays differ in length");
  const PsdDataset one{freq, psd};
  return select_shaper(std::span<const PsdDataset>(&one, 1), o);
}

ShaperSelection select_shaper(std::span<const PsdDataset> datasets, const ShaperSelectionOptions& o) {
  check_selection_options(datasets, o);
  const std::vector<std::vector<double>> type_freqs = type_frequencies(o);
  for (const auto& ds : datasets)
    if (ds.freq_hz.size() != ds.psd.size()) throw InputError("frequency and PSD arrays differ in length");
  const std::vector<TypeScan> scans = scan_types_in_parallel(type_freqs, datasets, o);

  // The choice among the types is Klipper's, in the types' order.
  ShaperSelection sel;
  bool have_best = false;
  ShaperCandidate best;
  const bool limit = o.max_vibrations.has_value();
  const double max_vibrations = o.max_vibrations.value_or(0.0);
  for (std::size_t ti = 0; ti < o.types.size(); ++ti) {
    const auto& results = scans[ti].results;
    if (results.empty()) continue;
    ShaperCandidate chosen = type_candidate(scans[ti], o);
    // Across types: a new type wins by a 20 % better score, or a 5 % better score with 10 %
    // less smoothing, or fewer vibrations while the best is above the limit.
    if (!have_best || chosen.score * 1.2 < best.score ||
        (chosen.score * 1.05 < best.score && chosen.smoothing_mm * 1.1 < best.smoothing_mm) ||
        (limit && best.vibrations > max_vibrations && chosen.vibrations < best.vibrations)) {
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

std::vector<double> shaper_response(const Shaper& s, std::span<const double> f, std::span<const double> zs) {
  std::vector<double> out(f.size(), 0.0);
  for (double z : zs) {
    const auto v = residual_vibration_curve(s, f, z);
    for (std::size_t b = 0; b < f.size(); ++b) out[b] = std::max(out[b], v[b]);
  }
  return out;
}

}  // namespace tunekit::design
