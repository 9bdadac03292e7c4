#include "tunekit/ident/excitation.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "tunekit/core/error.hpp"

namespace tunekit::ident {
namespace {

// A logged set-point repeats its level exactly, to the digits it is written with; a thousandth
// of the input's range is far above that rounding and far below any step an experiment makes.
constexpr double kHoldTolerance = 1e-3;

// A steady hold before an excitation is long against the excitation's own holds: the liquefier
// chirp settles for at least 2 s before staircase steps of at most 50 ms (Holtrup, Tuning
// liquefier dynamics, MSc thesis, University of Twente, 2019, ch. 4.3.3: steady state first).
constexpr double kSteadyHoldFactor = 10;

// The band keeps every bin within 30 dB of the strongest: a logarithmic chirp over a decade and
// a half spans 15 dB, a linear one is flat, and the walk from the peak stops in the gap before
// a staircase's images (about 20 dB down at ten levels per period, but not contiguous).
constexpr double kBandFloor = 1e-3;

double hold_duration(std::span<const double> t, const InputHold& h) {
  // A hold lasts until the next level starts: one sample period past its last sample.
  const double dt = (t.back() - t.front()) / static_cast<double>(t.size() - 1);
  return t[h.last] - t[h.first] + dt;
}

}  // namespace

std::vector<InputHold> input_holds(std::span<const double> u) {
  std::vector<InputHold> holds;
  if (u.empty()) return holds;
  const auto [lo, hi] = std::minmax_element(u.begin(), u.end());
  const double tol = kHoldTolerance * (*hi - *lo);
  InputHold cur;
  for (std::size_t i = 1; i < u.size(); ++i) {
    if (std::abs(u[i] - u[cur.first]) <= tol) continue;
    cur.last = i - 1;
    holds.push_back(cur);
    cur.first = i;
  }
  cur.last = u.size() - 1;
  holds.push_back(cur);
  return holds;
}

double typical_hold_s(std::span<const double> t, std::span<const InputHold> holds) {
  if (t.size() < 2 || holds.empty()) throw InputError("a record of at least two samples is needed for its holds");
  std::vector<double> d;
  for (const auto& h : holds) d.push_back(hold_duration(t, h));
  std::sort(d.begin(), d.end());
  double total = 0;
  for (double v : d) total += v;
  double below = 0;
  for (double v : d) {
    below += v;
    if (below >= 0.5 * total) return v;
  }
  return d.back();
}

std::size_t excitation_onset(std::span<const double> t, std::span<const double> u) {
  if (t.size() < 2 || t.size() != u.size()) return 0;
  const auto holds = input_holds(u);
  const double middle = 0.5 * (t.front() + t.back());
  const InputHold* steady = nullptr;
  for (const auto& h : holds)
    if (t[h.last] <= middle && (steady == nullptr || hold_duration(t, h) > hold_duration(t, *steady))) steady = &h;
  if (steady == nullptr || steady->last + 1 >= t.size()) return 0;
  if (hold_duration(t, *steady) < kSteadyHoldFactor * typical_hold_s(t, holds)) return 0;
  return steady->last;
}

ExcitedBand excited_band(const Spectrum& psd) {
  const auto& p = psd.psd;
  if (p.size() < 3) throw InputError("the input's spectrum has too few bins for its excited band");
  const auto peak = static_cast<std::size_t>(std::max_element(p.begin() + 1, p.end()) - p.begin());
  const double floor = kBandFloor * p[peak];
  std::size_t lo = peak, hi = peak;
  while (lo > 1 && p[lo - 1] >= floor) --lo;
  while (hi + 1 < p.size() && p[hi + 1] >= floor) ++hi;
  return {psd.freq_hz[lo], psd.freq_hz[hi]};
}

}  // namespace tunekit::ident
