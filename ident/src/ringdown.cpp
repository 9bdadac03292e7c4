#include "tunekit/ident/ringdown.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <span>

#include <fmt/format.h>

#include "ringdown_series.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/fitting/damped_sinusoids.hpp"
#include "tunekit/fitting/stats.hpp"
#include "tunekit/core/text.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/ident/spectrum.hpp"

namespace tunekit::ident {

using core::iequals;
namespace {

namespace rd = ringdown_detail;

double ringdown_rms(std::span<const double> x) {
  if (x.empty()) return 0;
  double mean = 0;
  for (double v : x) mean += v;
  mean /= static_cast<double>(x.size());
  double s = 0;
  for (double v : x) s += (v - mean) * (v - mean);
  return std::sqrt(s / static_cast<double>(x.size()));
}

// The impact: the largest excursion of all channels together (each about its median).
std::size_t find_impact(const AccelRecord& rec) {
  const std::size_t n = rec.channels.front().size();
  std::vector<double> med;
  for (const auto& c : rec.channels) med.push_back(fitting::median(c));
  std::size_t impact = 0;
  double best = -1;
  for (std::size_t i = 0; i < n; ++i) {
    double s = 0;
    for (std::size_t c = 0; c < rec.channels.size(); ++c) {
      const double d = rec.channels[c][i] - med[c];
      s += d * d;
    }
    if (s > best) {
      best = s;
      impact = i;
    }
  }
  return impact;
}

// Where the noise floor of a record is measured: before the impact (less a guard), else the
// record's last fifth when it lies after the strength window.
struct NoiseSpans {
  std::size_t pre_end = 0;     ///< [0, pre_end) when > 0
  std::size_t tail_begin = 0;  ///< [tail_begin, n) when > 0
};

double noise_rms(std::span<const double> x, const NoiseSpans& s) {
  double noise = std::numeric_limits<double>::infinity();
  if (s.pre_end > 0) noise = ringdown_rms(x.subspan(0, s.pre_end));
  if (s.tail_begin > 0) noise = std::min(noise, ringdown_rms(x.subspan(s.tail_begin)));
  return noise;
}

std::vector<double> weighted_sum(const AccelRecord& rec, const std::vector<double>& w) {
  std::vector<double> y(rec.channels.front().size(), 0.0);
  for (std::size_t c = 0; c < rec.channels.size(); ++c)
    if (w[c] != 0)
      for (std::size_t i = 0; i < y.size(); ++i) y[i] += w[c] * rec.channels[c][i];
  return y;
}

std::string projection_text(const AccelRecord& rec, const std::vector<double>& w) {
  std::string s;
  for (std::size_t c = 0; c < w.size(); ++c) {
    if (std::abs(w[c]) < 0.005) continue;
    if (s.empty()) s += fmt::format("{:.2f} {}", w[c], rec.channel_names[c]);
    else s += fmt::format(" {} {:.2f} {}", w[c] < 0 ? '-' : '+', std::abs(w[c]), rec.channel_names[c]);
  }
  return s;
}

// The spectral lines of the decay window, each line's power divided by the median of the
// spectrum it was found in over [lo, hi]: every channel's own spectrum and the channels' summed
// spectrum (the named channel's alone when one is named), pooled and strongest first. A line
// is measured where it stands highest: a line that stands clearly over one channel's floor is
// not drowned by another channel's larger floor (as it is in the sum), and a line spread over
// the channels adds up in the sum.
std::vector<rd::Line> pooled_lines(const std::vector<std::span<const double>>& windows, int named, std::size_t nfft,
                                   double df, double lo, double hi) {
  std::vector<rd::Line> pool;
  auto add = [&](const std::vector<double>& p) {
    const double floor = rd::spectral_floor(p, df, lo, hi);
    if (!(floor > 0)) return;
    for (auto l : rd::spectral_lines(p, df, lo, hi)) {
      l.power /= floor;
      pool.push_back(l);
    }
  };
  std::vector<double> sum;
  for (std::size_t c = 0; c < windows.size(); ++c) {
    if (named >= 0 && static_cast<int>(c) != named) continue;
    auto p = padded_amplitude_spectrum(windows[c], nfft);
    for (double& v : p) v *= v;
    add(p);
    if (sum.empty()) sum.assign(p.size(), 0.0);
    for (std::size_t k = 0; k < p.size() && k < sum.size(); ++k) sum[k] += p[k];
  }
  if (named < 0 && windows.size() > 1) add(sum);
  std::sort(pool.begin(), pool.end(), [](const rd::Line& x, const rd::Line& y) { return x.power > y.power; });
  return pool;
}

// The largest damping ratio a line of the series may take in the fit. A ring-down's modes are
// lightly damped; left free, the fundamental's component can instead take the impact's
// broadband transient as one heavily damped "line" (a damping ratio of 0.3-0.7 on real plucks
// whose fundamental is weak), which is no mode at all. With a tap limit (max_zeta) the bound is
// twice that limit, so that a tap still fits above the limit and is refused by it.
double series_max_zeta(const RingdownOptions& o) { return o.max_zeta > 0 ? 2 * o.max_zeta : 0.25; }

// The matrix pencils of a decay window, by order (empty where the window is too short for the
// order, and for order 0: the spectral start values then serve). Computed once per window: the
// fit starts from several and the other motion's lines come from the highest.
struct DecayPencils {
  std::vector<std::pair<int, std::vector<fitting::PencilComponent>>> by_order;

  const std::vector<fitting::PencilComponent>& of(int order) const {
    static const std::vector<fitting::PencilComponent> none;
    for (const auto& [k, c] : by_order)
      if (k == order) return c;
    return none;
  }
};

constexpr int kOtherMotionOrder = 40;  ///< exponentials of the pencil the other motion's lines come from

// The orders of the matrix pencils the fit starts from (0: the spectral lines alone): the usual
// one first (it also centres the frequency bounds), then lower and higher ones.
std::vector<int> start_orders(const RingdownOptions& o) {
  const int base = 2 * o.max_components + 4;
  return {base, base - 4, base + 8, base + 20, 0};
}

DecayPencils decay_pencils(const std::vector<double>& win, double fs, const RingdownOptions& o) {
  DecayPencils p;
  auto orders = start_orders(o);
  orders.push_back(kOtherMotionOrder);
  for (int order : orders) {
    std::vector<fitting::PencilComponent> c;
    try {
      if (order > 0) c = fitting::matrix_pencil(win, fs, order);
    } catch (const Error&) {
      c.clear();  // the spectral start values serve
    }
    p.by_order.emplace_back(order, std::move(c));
  }
  return p;
}

// Start values of the components `comps` (harmonic number or 0, spectral line in Hz): the line of
// the matrix pencil `pencil` where it finds one near, else the spectral line with a damping
// ratio of 0.01.
std::vector<fitting::PencilComponent> component_starts(const std::vector<fitting::PencilComponent>& pencil,
                                                       const std::vector<std::pair<int, double>>& comps,
                                                       const RingdownOptions& o) {
  std::vector<fitting::PencilComponent> starts;
  for (const auto& c : comps) {
    fitting::PencilComponent s;
    s.freq_hz = c.second;
    s.zeta = 0.01;
    s.harmonic = starts.empty() ? 0 : std::max(0, c.first);  // the series' harmonics share f0
    if (c.first >= 1) s.max_zeta = series_max_zeta(o);
    for (const auto& p : pencil)
      if (std::abs(p.freq_hz - c.second) <= o.harmonic_tolerance * c.second && p.zeta > 0 && p.zeta < 0.5) {
        s.freq_hz = p.freq_hz;
        s.zeta = p.zeta;
        break;
      }
    s.freq_hz *= 1 + o.start_perturbation;
    s.zeta *= 1 - o.start_perturbation;
    starts.push_back(s);
  }
  return starts;
}

// Least squares from several starts, the least residual kept (fitting::fit_damped_sinusoids_best_of):
// the matrix pencils of `orders` (start_orders); the fundamental (component 0) into r.
void fit_components(RingdownResult& r, const std::vector<double>& win, double fs,
                    const std::vector<std::pair<int, double>>& comps, const DecayPencils& pencils,
                    const std::vector<int>& orders, const RingdownOptions& o) {
  std::vector<std::vector<fitting::PencilComponent>> start_sets;
  for (int order : orders) start_sets.push_back(component_starts(pencils.of(order), comps, o));
  const auto& starts = start_sets.front();
  try {
    r.fit = fitting::fit_damped_sinusoids_best_of(win, fs, start_sets, o.max_line_shift);
  } catch (const Error& e) {
    throw FitError(fmt::format("the damped-sinusoid fit of the decay in {} failed: {}", r.channel, e.message()),
                   r.path);
  }
  const auto& pf = r.fit.param("f0_hz");
  const auto& pz = r.fit.param("zeta0");
  const double f_start = comps.front().second;
  if (std::abs(pf.value - f_start) >= 0.999 * o.max_line_shift * f_start)
    throw FitError(fmt::format("the fit moved the fundamental from {:.2f} Hz (spectrum) to {:.2f} Hz; the decay is "
                               "not a sum of damped sinusoids",
                               f_start, pf.value),
                   r.path);
  r.freq_hz = pf.value;
  r.freq_stderr_hz = pf.std_error;
  r.freq_ci95_lo = pf.ci95_lo;
  r.freq_ci95_hi = pf.ci95_hi;
  r.zeta = pz.value;
  r.zeta_stderr = pz.std_error;
  r.zeta_ci95_lo = pz.ci95_lo;
  r.zeta_ci95_hi = pz.ci95_hi;
  r.zeta_identified = pz.value < 0.999 * series_max_zeta(o);
  r.series_zeta = r.zeta_identified ? r.zeta : std::numeric_limits<double>::infinity();
  for (std::size_t i = 1; i < starts.size(); ++i) {
    r.other_lines_hz.push_back(r.fit.value(fmt::format("f{}_hz", i)));
    if (comps[i].first >= 2) r.series_zeta = std::min(r.series_zeta, r.fit.value(fmt::format("zeta{}", i)));
  }
  if (!std::isfinite(r.series_zeta)) r.series_zeta = r.zeta;
  // What a tuner reads: the series' lines ring at their damped frequencies.
  r.damped_freq_hz = r.freq_hz * std::sqrt(std::max(0.0, 1 - r.series_zeta * r.series_zeta));
  if (!r.zeta_identified)
    r.warnings.push_back(fmt::format(
        "the fundamental's damping is not identified: its fitted line reached the bound {:g} (the impact's transient "
        "at {:.2f} Hz); the frequency is the harmonic series', and the series' damping is {:.4f}",
        series_max_zeta(o), r.freq_hz, r.series_zeta));
}

// Lines of other motion than the fitted ones (the toolhead's own modes, the impact's transient):
// the strongest lines of a matrix pencil of high order in the band [min_hz / 2, max_hz] that
// decay (a damping ratio below 0.5) and lie more than twice the series' tolerance from every
// component, at most four.
std::vector<std::pair<int, double>> other_motion_lines(const DecayPencils& pencils,
                                                       const std::vector<std::pair<int, double>>& comps,
                                                       const RingdownOptions& o, double max_hz) {
  constexpr std::size_t kLines = 4;
  std::vector<std::pair<int, double>> out;
  for (const auto& p : pencils.of(kOtherMotionOrder)) {  // strongest first
    if (out.size() >= kLines) break;
    if (p.freq_hz < 0.5 * o.min_hz || p.freq_hz > max_hz || !(p.zeta > 0 && p.zeta < 0.5)) continue;
    auto near = [&](const auto& c) { return std::abs(c.second - p.freq_hz) <= 2 * o.harmonic_tolerance * c.second; };
    if (std::any_of(comps.begin(), comps.end(), near) || std::any_of(out.begin(), out.end(), near)) continue;
    out.emplace_back(0, p.freq_hz);
  }
  return out;
}

// Where the fit's residuals are not white, the record holds more than the fitted lines: the
// model is extended by the other motion's lines (other_motion_lines), each with its own
// frequency and damping, and the extended fit kept when its BIC is lower. Left out, that motion
// is taken up by the fundamental's damping or by another component pinned on its bounds, and the
// fit's end moves with its start values' last digits. `before` is r as it was before the fit.
void extend_for_other_motion(RingdownResult& r, const RingdownResult& before, const std::vector<double>& win, double fs,
                             std::vector<std::pair<int, double>>& comps, const DecayPencils& pencils,
                             const RingdownOptions& o, double max_hz) {
  if (!(r.fit.diagnostics.whiteness_p < 0.01)) return;
  const auto extra = other_motion_lines(pencils, comps, o, max_hz);
  if (extra.empty()) return;
  auto extended = comps;
  extended.insert(extended.end(), extra.begin(), extra.end());
  RingdownResult alt = before;
  try {
    fit_components(alt, win, fs, extended, pencils, start_orders(o), o);
  } catch (const FitError&) {
    return;
  }
  if (!(alt.fit.diagnostics.bic < r.fit.diagnostics.bic)) return;
  r = std::move(alt);
  comps = std::move(extended);
}

// The decay window of a record and what the fundamental's choice and the fit share.
struct DecayWindow {
  const AccelRecord& rec;
  std::vector<std::span<const double>> windows;  ///< every channel's decay window
  std::vector<double> noises;                    ///< every channel's noise RMS
  NoiseSpans spans;
  std::size_t start = 0, len = 0, head = 0;  ///< window start and length, strength head, samples
  std::size_t nfft = 1;                      ///< zero-padded FFT length
  double df = 0;                             ///< its bin spacing, Hz
  double max_hz = 0;                         ///< the band's top, Hz
  int named = -1;                            ///< the named channel, or -1
};

rd::SeriesChoice choose(const std::vector<rd::Line>& lines, const std::vector<double>& excluded, double max_hz,
                        const RingdownOptions& o) {
  auto sq = [](double v) { return v * v; };
  return rd::choose_fundamental(
      lines, sq(o.min_line_ratio), sq(o.min_subharmonic_ratio), o.min_hz, max_hz, o.harmonic_tolerance, 5.0,
      {sq(o.min_fundamental_line_ratio), sq(o.min_fundamental_to_harmonic), sq(o.min_pair_line_ratio)}, excluded);
}

// The fundamental is in the record when its fitted amplitude (a0, b0) differs from zero: the
// Wald statistic with their covariance above the chi-square(2) 99 % point (9.21). A candidate
// fundamental chosen for a noise line at f/2 of a real line fits with no amplitude.
bool fundamental_present(const fitting::FitResult& fit) {
  const std::size_t n = fit.params.size();
  std::size_t ia = n, ib = n;
  for (std::size_t i = 0; i < n; ++i) {
    if (fit.params[i].name == "a0") ia = i;
    if (fit.params[i].name == "b0") ib = i;
  }
  if (ia == n || ib == n || fit.covariance.size() != n * n) return true;  // nothing to test: keep it
  const double a = fit.params[ia].value, b = fit.params[ib].value;
  const double caa = fit.covariance[ia * n + ia], cbb = fit.covariance[ib * n + ib], cab = fit.covariance[ia * n + ib];
  const double det = caa * cbb - cab * cab;
  if (!(det > 0)) return true;
  const double w = (cbb * a * a - 2 * cab * a * b + caa * b * b) / det;
  return w > 9.21;
}

// Intervals where the residuals are not white (other motion than the fitted lines: the
// toolhead's own modes, the other belt): the Cramer-Rao bound of a sinusoid's frequency in
// coloured noise is the white-noise bound with the noise's spectral density at the line in
// place of its mean (Stoica and Moses, Spectral Analysis of Signals, 2005, section 4.3). Each
// line's factor rho_k is the residuals' periodogram around k f0 (+-2 resolution bins) over its
// mean; f0, informed by every line of the series in proportion to k^2 A_k^2 / rho_k, is
// widened by sum(k^2 A_k^2) / sum(k^2 A_k^2 / rho_k), the fundamental's damping by rho_1;
// never narrowed. White residuals keep the Wald intervals.
void widen_for_coloured_residuals(RingdownResult& r, const std::vector<double>& win, double fs, std::size_t nfft,
                                  const std::vector<std::pair<int, double>>& comps) {
  if (!(r.fit.diagnostics.whiteness_p < 0.01)) return;
  std::vector<double> res(win.size());
  for (std::size_t i = 0; i < win.size(); ++i)
    res[i] = win[i] - fitting::damped_sinusoids_value(r.fit, static_cast<double>(i) / fs);
  auto p = padded_amplitude_spectrum(res, nfft);
  double mean = 0;
  for (double& v : p) mean += (v *= v);
  mean /= static_cast<double>(p.size());
  if (!(mean > 0)) return;
  const double df = fs / static_cast<double>(nfft);
  const double half = 2.0 * fs / static_cast<double>(win.size());  // two resolution bins, Hz
  auto rho = [&](double f) {
    const auto k0 = static_cast<std::size_t>(std::max(0.0, (f - half) / df));
    const auto k1 = std::min(p.size() - 1, static_cast<std::size_t>((f + half) / df));
    double s = 0;
    for (std::size_t k = k0; k <= k1; ++k) s += p[k];
    return std::max(1.0, s / static_cast<double>(k1 - k0 + 1) / mean);
  };
  double w_sum = 0, w_over_rho = 0, rho1 = 1;
  for (std::size_t i = 0; i < comps.size(); ++i) {
    const int k = comps[i].first;
    if (k < 1) continue;
    const double a = r.fit.value(fmt::format("a{}", i)), b = r.fit.value(fmt::format("b{}", i));
    const double rk = rho(r.fit.value(fmt::format("f{}_hz", i)));
    const double w = k * k * (a * a + b * b);
    w_sum += w;
    w_over_rho += w / rk;
    if (k == 1) rho1 = rk;
  }
  const double f_factor = w_over_rho > 0 ? std::max(1.0, w_sum / w_over_rho) : rho1;
  auto widen = [](double value, double& se, double& lo, double& hi, double factor) {
    const double g = std::sqrt(factor);
    se *= g;
    lo = value - g * (value - lo);
    hi = value + g * (hi - value);
  };
  widen(r.freq_hz, r.freq_stderr_hz, r.freq_ci95_lo, r.freq_ci95_hi, f_factor);
  widen(r.zeta, r.zeta_stderr, r.zeta_ci95_lo, r.zeta_ci95_hi, rho1);
  r.interval_factor = std::sqrt(f_factor);
}

// 4-5. The projection in which the fundamental stands highest over the noise; the fundamental,
// its harmonics present in the projection, then the other strong lines of the projection,
// fitted; the series found reported. Whether the fundamental is in the record (its fitted
// amplitude, fundamental_present) is judged in the fit of these lines, before the other motion's
// are added (extend_for_other_motion): those are heavily damped, their broad lines overlap the
// fundamental's and share its amplitude, which leaves a weak fundamental's amplitude uncertain
// there without making it absent.
bool fit_series(RingdownResult& r, const DecayWindow& dw, const rd::SeriesChoice& choice, const RingdownOptions& o) {
  const auto& rec = dw.rec;
  const double fs = r.sample_rate_hz;
  const auto& series = choice.best;
  const double f_spec = series.fundamental.freq_hz;
  std::vector<double> w(rec.channels.size(), 0.0);
  if (dw.named >= 0) w[static_cast<std::size_t>(dw.named)] = 1.0;
  else w = rd::best_projection(dw.windows, dw.noises, f_spec, fs);
  for (std::size_t c = 0; c < w.size(); ++c) r.channels[c].weight = w[c];
  const auto y = weighted_sum(rec, w);
  r.channel = dw.named >= 0 ? rec.channel_names[static_cast<std::size_t>(dw.named)] : std::string("projection");
  r.projection = projection_text(rec, w);
  const std::span<const double> ys(y);
  const double y_noise = noise_rms(ys, dw.spans);
  r.strength =
      y_noise > 0 ? ringdown_rms(ys.subspan(dw.start, dw.head)) / y_noise : std::numeric_limits<double>::infinity();
  const std::vector<double> win(y.begin() + static_cast<std::ptrdiff_t>(dw.start),
                                y.begin() + static_cast<std::ptrdiff_t>(dw.start + dw.len));

  std::vector<double> pp = padded_amplitude_spectrum(win, dw.nfft);
  for (double& v : pp) v *= v;
  const auto plines = rd::spectral_lines(pp, dw.df, 0.5 * o.min_hz, dw.max_hz);
  const double pfloor = rd::spectral_floor(pp, dw.df, o.min_hz, dw.max_hz);
  const double ratio2 = o.min_line_ratio * o.min_line_ratio;
  std::vector<std::pair<int, double>> comps{{1, f_spec}};  // (harmonic number or 0, start Hz)
  const auto* fund_line = rd::line_near(plines, f_spec, o.harmonic_tolerance);
  if (fund_line) comps.front().second = fund_line->freq_hz;
  auto distinct = [&](double f) {
    return std::none_of(comps.begin(), comps.end(),
                        [&](const auto& c) { return std::abs(c.second - f) <= o.harmonic_tolerance * c.second; });
  };
  // A harmonic of the series counts down to the series' own threshold (min_pair_line_ratio, as in
  // the series' choice): left out of the fit, its line would be taken up by the fundamental's
  // damping or by another line's.
  const double harmonic_ratio2 = std::min(ratio2, o.min_pair_line_ratio * o.min_pair_line_ratio);
  for (const auto& [k, hl] : series.harmonics) {
    if (static_cast<int>(comps.size()) >= o.max_components) break;
    const auto* l = rd::line_near(plines, hl.freq_hz, o.harmonic_tolerance);
    if (l && l->power >= harmonic_ratio2 * pfloor && distinct(l->freq_hz)) comps.emplace_back(k, l->freq_hz);
  }
  // The series' f0 to start from: each line's f_k / k weighted by k^2 times its power (a line's
  // frequency error falls with its amplitude, and f_k / k divides it by k), so that a strong
  // harmonic places f0 where a weak fundamental alone would not.
  if (comps.size() > 1) {
    double sw = 0, swf = 0;
    for (const auto& [k, f] : comps) {
      const auto* l = k == 1 ? fund_line : rd::line_near(plines, f, 1e-9);
      if (l == nullptr) continue;
      sw += k * k * l->power;
      swf += k * k * l->power * (f / k);
    }
    if (sw > 0) comps.front().second = swf / sw;
  }
  const double ptop = plines.empty() ? 0.0 : plines.front().power;
  for (const auto& l : plines) {
    if (static_cast<int>(comps.size()) >= o.max_components) break;
    if (l.freq_hz >= o.min_hz && l.power >= 0.09 * ptop && l.power >= ratio2 * pfloor && distinct(l.freq_hz))
      comps.emplace_back(0, l.freq_hz);
  }
  const RingdownResult before = r;
  const DecayPencils pencils = decay_pencils(win, fs, o);
  fit_components(r, win, fs, comps, pencils, start_orders(o), o);
  const bool present = fundamental_present(r.fit);
  extend_for_other_motion(r, before, win, fs, comps, pencils, o, dw.max_hz);
  widen_for_coloured_residuals(r, win, fs, dw.nfft, comps);

  // The harmonic series found, and where the strongest line stands in it.
  r.spectral_freq_hz = comps.front().second;
  r.strongest_peak_hz = choice.strongest.freq_hz;
  r.harmonics.push_back({1, r.freq_hz, 1.0, true, r.zeta});
  for (const auto& [k, hl] : series.harmonics) {
    RingdownHarmonic h{k, hl.freq_hz, std::sqrt(hl.power / series.fundamental.power), false, 0.0};
    for (std::size_t i = 1; i < comps.size(); ++i)
      if (comps[i].first == k) {
        h.fitted = true;
        h.freq_hz = r.fit.value(fmt::format("f{}_hz", i));
        h.zeta = r.fit.value(fmt::format("zeta{}", i));
      }
    if (std::abs(hl.freq_hz - choice.strongest.freq_hz) < 1e-9) r.harmonic_number = k;
    r.harmonics.push_back(h);
  }
  r.strongest_is_harmonic = r.harmonic_number > 1;
  if (r.strongest_is_harmonic)
    r.warnings.push_back(fmt::format("the strongest line, {:.2f} Hz, is harmonic {} of the fundamental {:.2f} Hz",
                                     r.strongest_peak_hz, r.harmonic_number, r.freq_hz));
  return present;
}

// 6. A ring-down decays, and a belt's decays slowly.
void check_ringdown(RingdownResult& r, const RingdownOptions& o) {
  r.decay_ratio = std::exp(-r.zeta * 2 * std::numbers::pi * r.freq_hz * r.window_s);
  if (r.decay_ratio > o.max_decay_ratio)
    throw FitError(fmt::format("the {:.2f} Hz line does not decay: its envelope keeps {:.0f} % of its amplitude over "
                               "the {:.2f} s window (more than {:.0f} %); a steady tone (a fan, a motor), not a "
                               "ring-down",
                               r.freq_hz, 100 * r.decay_ratio, r.window_s, 100 * o.max_decay_ratio),
                   r.path);
  if (o.max_zeta > 0 && r.series_zeta > o.max_zeta)
    throw FitError(fmt::format("the {:.2f} Hz line decays too fast for a plucked belt: damping ratio {:.3f}, above "
                               "{:g}; a tap or a bump of the frame, not a pluck",
                               r.freq_hz, r.series_zeta, o.max_zeta),
                   r.path);
  // Residuals that are not white but leave the interval within a quarter of white-noise theory's
  // change nothing the user reads (the p-value is reported with the fit); a wider interval says
  // the record holds other motion than the belt's (a second pluck, the frame, a fan).
  constexpr double kWideningWorthWarning = 1.25;
  if (r.fit.diagnostics.whiteness_p < 0.01 && r.interval_factor >= kWideningWorthWarning)
    r.warnings.push_back(
        fmt::format("{}: the fit's residuals are not white (p = {:.2g}): other motion than the fitted "
                    "lines; the frequency's interval is widened {:.1f}x for the residuals' level at the lines",
                    r.channel, r.fit.diagnostics.whiteness_p, r.interval_factor));
}

// 2. Strength of every channel: decay RMS (over `head` samples from `start`) over the noise
// floor, each channel into r.channels. Returns the named channel (-1: none named) and every
// channel's noise RMS. InputError when the named channel is missing, FitError when the channel
// that decides (the named one, else the strongest) does not ring above its noise.
int measure_channels(RingdownResult& r, const AccelRecord& rec, const NoiseSpans& spans, std::size_t start,
                     std::size_t head, const RingdownOptions& o, std::vector<double>& noises) {
  int named = -1;
  std::size_t strongest = 0;
  for (std::size_t c = 0; c < rec.channels.size(); ++c) {
    const std::span<const double> x(rec.channels[c]);
    RingdownChannel ch;
    ch.name = rec.channel_names[c];
    ch.signal_rms = ringdown_rms(x.subspan(start, head));
    ch.noise_rms = noise_rms(x, spans);
    ch.strength = ch.noise_rms > 0 ? ch.signal_rms / ch.noise_rms : std::numeric_limits<double>::infinity();
    noises.push_back(ch.noise_rms);
    if (!o.channel.empty() && iequals(ch.name, o.channel)) named = static_cast<int>(c);
    if (r.channels.empty() || ch.strength > r.channels[strongest].strength) strongest = c;
    r.channels.push_back(ch);
  }
  if (!o.channel.empty() && named < 0)
    throw InputError(fmt::format("no channel '{}' in the record", o.channel), rec.path);
  const auto& gate = r.channels[named >= 0 ? static_cast<std::size_t>(named) : strongest];
  if (!(gate.strength >= o.min_strength))
    throw FitError(fmt::format("no ring-down to measure: the decay after the impact at {:.3f} s is {:.2f} times the "
                               "noise floor in {} (RMS {:.4g} over {:.4g} mm/s^2), below the {:g} required; pluck or "
                               "tap harder, or hold the sensor more rigidly",
                               r.impact_s, gate.strength, gate.name, gate.signal_rms, gate.noise_rms, o.min_strength),
                   rec.path);
  return named;
}

// 3-6. The fundamental by its harmonic series over the channels' lines, each line measured
// against its own channel's floor; the series fitted in the best projection. A candidate whose
// fitted fundamental has no amplitude in the record (a line of the other motion at f/2 of a
// clear line) is set aside and the next candidate taken.
void fit_fundamental(RingdownResult& r, const DecayWindow& dw, const RingdownOptions& o) {
  const double max_hz = dw.max_hz;
  const auto lines = pooled_lines(dw.windows, dw.named, dw.nfft, dw.df, o.min_hz, max_hz);
  std::vector<double> excluded;
  for (int attempt = 0;; ++attempt) {
    const auto choice = choose(lines, excluded, max_hz, o);
    if (!choice.found) {
      if (!excluded.empty())
        throw FitError(fmt::format("no decaying line: the candidate fundamental {:.2f} Hz has no amplitude in the "
                                   "fitted decay (it is the other motion's line, not a ring-down's)",
                                   excluded.front()),
                       dw.rec.path);
      throw FitError(
          fmt::format("no decaying line above the noise: the strongest line between {:g} and {:.0f} Hz "
                      "stands {:.1f} times over its channel's spectral median (amplitude), below the {:g} "
                      "required; a weak pluck, a tap or a bump, not a ring-down",
                      o.min_hz, max_hz, lines.empty() ? 0.0 : std::sqrt(lines.front().power), o.min_line_ratio),
          dw.rec.path);
    }
    RingdownResult attempt_r = r;
    if (fit_series(attempt_r, dw, choice, o) || attempt >= 2) {
      r = std::move(attempt_r);
      return;
    }
    excluded.push_back(choice.best.fundamental.freq_hz);
  }
}

}  // namespace

RingdownResult analyze_ringdown(const AccelRecord& rec, const RingdownOptions& o) {
  RingdownResult r;
  r.path = rec.path;
  const double fs = rec.sampling.sample_rate_hz;
  r.sample_rate_hz = fs;
  if (rec.channels.empty() || !(fs > 0)) throw InputError("no acceleration channels to analyse", rec.path);
  const std::size_t n = rec.channels.front().size();
  if (!(o.max_hz >= 0))
    throw InputError(fmt::format("the ring-down's highest line {} Hz is not a frequency (0 or more)", o.max_hz));
  const double max_hz = o.max_hz > 0 ? std::min(o.max_hz, 0.45 * fs) : 0.45 * fs;
  if (!(o.min_hz > 0 && o.min_hz < max_hz))
    throw InputError(fmt::format("the ring-down band {}-{} Hz is empty at {:.0f} Hz sampling", o.min_hz, max_hz, fs),
                     rec.path);

  // 1. The impact and the decay window after it.
  const std::size_t impact = find_impact(rec);
  const auto settle = static_cast<std::size_t>(std::ceil(o.settle_s * fs));
  const std::size_t start = impact + settle;
  const auto min_len = static_cast<std::size_t>(std::max(4.0 * fs / o.min_hz, 0.05 * fs));
  if (start + static_cast<std::size_t>(0.02 * fs) > n)
    throw InputError(
        fmt::format("the record ends {:.3f} s after its impact (at {:.3f} s): there is no decay to analyse",
                    static_cast<double>(n - std::min(n, impact)) / fs, static_cast<double>(impact) / fs),
        rec.path);
  const std::size_t len = std::min(n - start, static_cast<std::size_t>(o.max_window_s * fs));
  r.impact_s = static_cast<double>(impact) / fs;
  r.window_start_s = static_cast<double>(start) / fs;
  r.window_s = static_cast<double>(len) / fs;

  // 2. The noise floor before the impact or in the record's tail, and every channel's strength.
  const auto head = std::min(len, static_cast<std::size_t>(0.1 * fs));
  const auto guard = static_cast<std::size_t>(0.01 * fs);
  const auto min_noise = static_cast<std::size_t>(0.03 * fs);
  NoiseSpans spans;
  if (impact > guard + min_noise) spans.pre_end = impact - guard;
  if (const std::size_t tail = n / 5; n - tail > start + head && tail >= min_noise) spans.tail_begin = n - tail;
  if (spans.pre_end == 0 && spans.tail_begin == 0)
    throw InputError(fmt::format("no noise floor: the record has neither {:.0f} ms before its impact nor a tail "
                                 "after the decay; record a little longer",
                                 1e3 * static_cast<double>(min_noise + guard) / fs),
                     rec.path);
  std::vector<double> noises;
  const int named = measure_channels(r, rec, spans, start, head, o, noises);
  if (len < min_len)
    throw InputError(fmt::format("{:.3f} s of decay after the impact; at least {:.3f} s are needed for lines down to "
                                 "{:g} Hz (record longer, or raise --ringdown-min)",
                                 r.window_s, static_cast<double>(min_len) / fs, o.min_hz),
                     rec.path);

  DecayWindow dw{rec, {}, noises, spans, start, len, head, 1, 0, max_hz, named};
  while (dw.nfft < std::max<std::size_t>(8 * len, 16384)) dw.nfft <<= 1;
  dw.df = fs / static_cast<double>(dw.nfft);
  for (const auto& c : rec.channels) dw.windows.push_back(std::span<const double>(c).subspan(start, len));
  fit_fundamental(r, dw, o);
  check_ringdown(r, o);
  return r;
}

nlohmann::json to_json(const RingdownResult& r) {
  nlohmann::json ch = nlohmann::json::array();
  for (const auto& c : r.channels)
    ch.push_back({{"name", c.name},
                  {"signal_rms_mm_s2", c.signal_rms},
                  {"noise_rms_mm_s2", c.noise_rms},
                  {"strength", c.strength},
                  {"weight", c.weight}});
  nlohmann::json hs = nlohmann::json::array();
  for (const auto& h : r.harmonics)
    hs.push_back({{"k", h.k},
                  {"freq_hz", h.freq_hz},
                  {"rel_amplitude", h.rel_amplitude},
                  {"fitted", h.fitted},
                  {"zeta", h.fitted ? nlohmann::json(h.zeta) : nlohmann::json()}});
  return {{"file", r.path},
          {"channel", r.channel},
          {"projection", r.projection},
          {"sample_rate_hz", r.sample_rate_hz},
          {"impact_s", r.impact_s},
          {"window_start_s", r.window_start_s},
          {"window_s", r.window_s},
          {"strength", r.strength},
          {"channels", ch},
          {"strongest_peak_hz", r.strongest_peak_hz},
          {"spectral_freq_hz", r.spectral_freq_hz},
          {"strongest_is_harmonic", r.strongest_is_harmonic},
          {"harmonic_number", r.harmonic_number},
          {"harmonics", hs},
          {"freq_hz", r.freq_hz},
          {"freq_stderr_hz", r.freq_stderr_hz},
          {"freq_ci95", {r.freq_ci95_lo, r.freq_ci95_hi}},
          {"damped_freq_hz", r.damped_freq_hz},
          {"zeta", r.zeta},
          {"zeta_stderr", r.zeta_stderr},
          {"zeta_ci95", {r.zeta_ci95_lo, r.zeta_ci95_hi}},
          {"zeta_identified", r.zeta_identified},
          {"series_zeta", r.series_zeta},
          {"interval_factor", r.interval_factor},
          {"decay_ratio", r.decay_ratio},
          {"other_lines_hz", r.other_lines_hz},
          {"fit", fitting::to_json(r.fit)}};
}

}  // namespace tunekit::ident
