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
#include "tunekit/ident/csv.hpp"
#include "tunekit/ident/spectrum.hpp"

namespace tunekit::ident {
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

// Start values from the matrix pencil where it finds the line, then least squares; the
// fundamental (component 0) into r.
void fit_components(RingdownResult& r, const std::vector<double>& win, double fs,
                    const std::vector<std::pair<int, double>>& comps, const RingdownOptions& o) {
  std::vector<fitting::PencilComponent> pencil;
  try {
    pencil = fitting::matrix_pencil(win, fs, 2 * o.max_components + 4);
  } catch (const Error&) {
    pencil.clear();  // the spectral start values below serve
  }
  std::vector<fitting::PencilComponent> starts;
  for (const auto& c : comps) {
    fitting::PencilComponent s;
    s.freq_hz = c.second;
    s.zeta = 0.01;
    for (const auto& p : pencil)
      if (std::abs(p.freq_hz - c.second) <= o.harmonic_tolerance * c.second && p.zeta > 0 && p.zeta < 0.5) {
        s.freq_hz = p.freq_hz;
        s.zeta = p.zeta;
        break;
      }
    starts.push_back(s);
  }
  try {
    r.fit = fitting::fit_damped_sinusoids(win, fs, starts, o.max_line_shift);
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
  r.damped_freq_hz = r.freq_hz * std::sqrt(std::max(0.0, 1 - r.zeta * r.zeta));
  for (std::size_t i = 1; i < starts.size(); ++i) r.other_lines_hz.push_back(r.fit.value(fmt::format("f{}_hz", i)));
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

  // 2. Strength of every channel: decay RMS over the noise floor.
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
  int named = -1;
  std::size_t strongest = 0;
  std::vector<double> noises;
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
  if (len < min_len)
    throw InputError(fmt::format("{:.3f} s of decay after the impact; at least {:.3f} s are needed for lines down to "
                                 "{:g} Hz (record longer, or raise --ringdown-min)",
                                 r.window_s, static_cast<double>(min_len) / fs, o.min_hz),
                     rec.path);

  // 3. The fundamental by its harmonic series on the channels' summed power spectrum.
  std::size_t nfft = 1;
  while (nfft < std::max<std::size_t>(8 * len, 16384)) nfft <<= 1;
  const double df = fs / static_cast<double>(nfft);
  std::vector<std::span<const double>> windows;
  for (const auto& c : rec.channels) windows.push_back(std::span<const double>(c).subspan(start, len));
  std::vector<double> psum(nfft / 2 + 1, 0.0);
  for (std::size_t c = 0; c < windows.size(); ++c) {
    if (named >= 0 && static_cast<int>(c) != named) continue;
    const auto mag = padded_amplitude_spectrum(windows[c], nfft);
    for (std::size_t k = 0; k < psum.size() && k < mag.size(); ++k) psum[k] += mag[k] * mag[k];
  }
  const double ratio2 = o.min_line_ratio * o.min_line_ratio;
  const auto lines = rd::spectral_lines(psum, df, o.min_hz, max_hz);
  const double floor = rd::spectral_floor(psum, df, o.min_hz, max_hz);
  const auto choice = rd::choose_fundamental(lines, ratio2 * floor, o.min_subharmonic_ratio * o.min_subharmonic_ratio,
                                             o.min_hz, max_hz, o.harmonic_tolerance, 5.0,
                                             {o.min_fundamental_line_ratio * o.min_fundamental_line_ratio * floor,
                                              o.min_fundamental_to_harmonic * o.min_fundamental_to_harmonic,
                                              o.min_pair_line_ratio * o.min_pair_line_ratio * floor});
  if (!choice.found)
    throw FitError(
        fmt::format("no decaying line above the noise: the strongest line between {:g} and {:.0f} Hz "
                    "stands {:.1f} times over the spectrum's median (amplitude), below the {:g} "
                    "required; a weak pluck, a tap or a bump, not a ring-down",
                    o.min_hz, max_hz, lines.empty() || !(floor > 0) ? 0.0 : std::sqrt(lines.front().power / floor),
                    o.min_line_ratio),
        rec.path);
  const auto& series = choice.best;
  const double f_spec = series.fundamental.freq_hz;

  // 4. The projection in which the fundamental stands highest over the noise.
  std::vector<double> w(rec.channels.size(), 0.0);
  if (named >= 0) w[static_cast<std::size_t>(named)] = 1.0;
  else w = rd::best_projection(windows, noises, f_spec, fs);
  for (std::size_t c = 0; c < w.size(); ++c) r.channels[c].weight = w[c];
  const auto y = weighted_sum(rec, w);
  r.channel = named >= 0 ? rec.channel_names[static_cast<std::size_t>(named)] : std::string("projection");
  r.projection = projection_text(rec, w);
  const std::span<const double> ys(y);
  const double y_noise = noise_rms(ys, spans);
  r.strength = y_noise > 0 ? ringdown_rms(ys.subspan(start, head)) / y_noise : std::numeric_limits<double>::infinity();
  const std::vector<double> win(y.begin() + static_cast<std::ptrdiff_t>(start),
                                y.begin() + static_cast<std::ptrdiff_t>(start + len));

  // 5. Components: the fundamental, its harmonics present in the projection, then the other
  // strong lines of the projection.
  std::vector<double> pp = padded_amplitude_spectrum(win, nfft);
  for (double& v : pp) v *= v;
  const auto plines = rd::spectral_lines(pp, df, 0.5 * o.min_hz, max_hz);
  const double pfloor = rd::spectral_floor(pp, df, o.min_hz, max_hz);
  std::vector<std::pair<int, double>> comps{{1, f_spec}};  // (harmonic number or 0, start Hz)
  if (const auto* l = rd::line_near(plines, f_spec, o.harmonic_tolerance)) comps.front().second = l->freq_hz;
  auto distinct = [&](double f) {
    return std::none_of(comps.begin(), comps.end(),
                        [&](const auto& c) { return std::abs(c.second - f) <= o.harmonic_tolerance * c.second; });
  };
  for (const auto& [k, hl] : series.harmonics) {
    if (static_cast<int>(comps.size()) >= o.max_components) break;
    const auto* l = rd::line_near(plines, hl.freq_hz, o.harmonic_tolerance);
    if (l && l->power >= ratio2 * pfloor && distinct(l->freq_hz)) comps.emplace_back(k, l->freq_hz);
  }
  const double ptop = plines.empty() ? 0.0 : plines.front().power;
  for (const auto& l : plines) {
    if (static_cast<int>(comps.size()) >= o.max_components) break;
    if (l.freq_hz >= o.min_hz && l.power >= 0.09 * ptop && l.power >= ratio2 * pfloor && distinct(l.freq_hz))
      comps.emplace_back(0, l.freq_hz);
  }
  fit_components(r, win, fs, comps, o);

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

  // 6. A ring-down decays, and a belt's decays slowly.
  r.decay_ratio = std::exp(-r.zeta * 2 * std::numbers::pi * r.freq_hz * r.window_s);
  if (r.decay_ratio > o.max_decay_ratio)
    throw FitError(fmt::format("the {:.2f} Hz line does not decay: its envelope keeps {:.0f} % of its amplitude over "
                               "the {:.2f} s window (more than {:.0f} %); a steady tone (a fan, a motor), not a "
                               "ring-down",
                               r.freq_hz, 100 * r.decay_ratio, r.window_s, 100 * o.max_decay_ratio),
                   rec.path);
  if (o.max_zeta > 0 && r.zeta > o.max_zeta)
    throw FitError(fmt::format("the {:.2f} Hz line decays too fast for a plucked belt: damping ratio {:.3f}, above "
                               "{:g}; a tap or a bump of the frame, not a pluck",
                               r.freq_hz, r.zeta, o.max_zeta),
                   rec.path);
  if (r.fit.diagnostics.whiteness_p < 0.01)
    r.warnings.push_back(
        fmt::format("{}: the fit's residuals are not white (p = {:.2g}): other motion than the fitted "
                    "lines; the intervals are optimistic",
                    r.channel, r.fit.diagnostics.whiteness_p));
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
          {"decay_ratio", r.decay_ratio},
          {"other_lines_hz", r.other_lines_hz},
          {"fit", fitting::to_json(r.fit)}};
}

}  // namespace tunekit::ident
