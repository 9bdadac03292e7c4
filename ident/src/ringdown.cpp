#include "tunekit/ident/ringdown.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>

#include <fmt/format.h>

#include "tunekit/fitting/damped_sinusoids.hpp"
#include "tunekit/fitting/stats.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/ident/csv.hpp"
#include "tunekit/ident/spectrum.hpp"

namespace tunekit::ident {
namespace {

double ringdown_rms(std::span<const double> x) {
  if (x.empty()) return 0;
  double mean = 0;
  for (double v : x) mean += v;
  mean /= static_cast<double>(x.size());
  double s = 0;
  for (double v : x) s += (v - mean) * (v - mean);
  return std::sqrt(s / static_cast<double>(x.size()));
}

struct RingdownLine {
  double freq_hz = 0;
  double height = 0;
};

// Local maxima of the amplitude spectrum in [lo, hi] Hz, highest first (parabolic
// interpolation of the peak bin).
std::vector<RingdownLine> ringdown_lines(const std::vector<double>& mag, double df, double lo, double hi) {
  std::vector<RingdownLine> out;
  const std::size_t k0 = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(lo / df)));
  const std::size_t k1 = std::min(mag.size() - 2, static_cast<std::size_t>(hi / df));
  for (std::size_t k = k0; k <= k1; ++k) {
    if (!(mag[k] > mag[k - 1] && mag[k] >= mag[k + 1])) continue;
    const double a = mag[k - 1], b = mag[k], c = mag[k + 1];
    const double den = a - 2 * b + c;
    const double d = den != 0 ? 0.5 * (a - c) / den : 0.0;
    out.push_back({(static_cast<double>(k) + d) * df, b});
  }
  std::sort(out.begin(), out.end(), [](const auto& x, const auto& y) { return x.height > y.height; });
  return out;
}

// The highest line within a relative tolerance of f, or nullptr.
const RingdownLine* ringdown_line_near(const std::vector<RingdownLine>& lines, double f, double tol) {
  const RingdownLine* best = nullptr;
  for (const auto& l : lines)
    if (std::abs(l.freq_hz - f) <= tol * f && (!best || l.height > best->height)) best = &l;
  return best;
}

}  // namespace

RingdownResult analyze_ringdown(const AccelRecord& rec, const RingdownOptions& o) {
  RingdownResult r;
  r.path = rec.path;
  const double fs = rec.sampling.sample_rate_hz;
  r.sample_rate_hz = fs;
  if (rec.channels.empty() || !(fs > 0)) throw InputError("no acceleration channels to analyse", rec.path);
  const std::size_t n = rec.channels.front().size();
  const double max_hz = o.max_hz > 0 ? std::min(o.max_hz, 0.49 * fs) : 0.45 * fs;
  if (!(o.min_hz > 0 && o.min_hz < max_hz))
    throw InputError(fmt::format("the ring-down band {}-{} Hz is empty at {:.0f} Hz sampling", o.min_hz, max_hz, fs),
                     rec.path);

  // 1. The impact: the largest excursion of all channels together (each about its median).
  std::size_t impact = 0;
  {
    std::vector<double> med;
    for (const auto& c : rec.channels) med.push_back(fitting::median(c));
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
  }
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

  // 2. Strength of every channel (decay RMS over the noise floor) and its fundamental: the
  // strongest line of the window's spectrum, or the line at a half (third) of it when that
  // line is clearly there (then the strongest line is its harmonic).
  const auto head = std::min(len, static_cast<std::size_t>(0.1 * fs));
  const auto guard = static_cast<std::size_t>(0.01 * fs);
  const auto min_noise = static_cast<std::size_t>(0.03 * fs);
  std::size_t nfft = 1;
  while (nfft < std::max<std::size_t>(8 * len, 16384)) nfft <<= 1;
  const double df = fs / static_cast<double>(nfft);
  struct ChannelLines {
    std::vector<RingdownLine> lines;
    double floor = 0;
    RingdownLine top, fund;
    int harmonic = 1;
    double prominence = 0;
  };
  std::vector<ChannelLines> per_channel;
  int chosen = -1;
  for (std::size_t c = 0; c < rec.channels.size(); ++c) {
    const std::span<const double> x(rec.channels[c]);
    RingdownChannel ch;
    ch.name = rec.channel_names[c];
    ch.signal_rms = ringdown_rms(x.subspan(start, head));
    double noise = std::numeric_limits<double>::infinity();
    if (impact > guard + min_noise) noise = ringdown_rms(x.subspan(0, impact - guard));
    const std::size_t tail = n / 5;
    if (n - tail > start + head && tail >= min_noise) noise = std::min(noise, ringdown_rms(x.subspan(n - tail)));
    if (!std::isfinite(noise))
      throw InputError(fmt::format("no noise floor: the record has neither {:.0f} ms before its impact nor a tail "
                                   "after the decay; record a little longer",
                                   1e3 * static_cast<double>(min_noise + guard) / fs),
                       rec.path);
    ch.noise_rms = noise;
    ch.strength = noise > 0 ? ch.signal_rms / noise : std::numeric_limits<double>::infinity();
    r.channels.push_back(ch);

    ChannelLines cl;
    const auto mag = padded_amplitude_spectrum(x.subspan(start, len), nfft);
    cl.lines = ringdown_lines(mag, df, o.min_hz, max_hz);
    std::vector<double> band;
    for (auto k = static_cast<std::size_t>(o.min_hz / df); k < mag.size() && static_cast<double>(k) * df <= max_hz; ++k)
      band.push_back(mag[k]);
    cl.floor = fitting::median(band);
    if (!cl.lines.empty()) {
      cl.top = cl.fund = cl.lines.front();
      for (int d : {3, 2}) {
        const double f = cl.top.freq_hz / d;
        if (f < o.min_hz) continue;
        const auto* l = ringdown_line_near(cl.lines, f, o.harmonic_tolerance);
        if (l && l->height >= o.min_subharmonic_ratio * cl.top.height && l->height >= 4 * cl.floor) {
          cl.fund = *l;
          cl.harmonic = d;
          break;
        }
      }
      cl.prominence = cl.floor > 0 ? cl.fund.height / cl.floor : 0.0;
    }
    per_channel.push_back(cl);
    const bool named = !o.channel.empty() && iequals(ch.name, o.channel);
    if (named || (o.channel.empty() && !cl.lines.empty() &&
                  (chosen < 0 || cl.prominence > per_channel[static_cast<std::size_t>(chosen)].prominence)))
      chosen = static_cast<int>(c);
  }
  if (chosen < 0) {
    if (!o.channel.empty()) throw InputError(fmt::format("no channel '{}' in the record", o.channel), rec.path);
    throw FitError(fmt::format("no spectral line between {} and {:.0f} Hz in any channel", o.min_hz, max_hz), rec.path);
  }
  const auto& ch = r.channels[static_cast<std::size_t>(chosen)];
  const auto& cl = per_channel[static_cast<std::size_t>(chosen)];
  r.channel = ch.name;
  r.strength = ch.strength;
  if (!(ch.strength >= o.min_strength))
    throw FitError(fmt::format("no ring-down to measure: the decay after the impact at {:.3f} s is {:.2f} times the "
                               "noise floor in {} (RMS {:.4g} over {:.4g} mm/s^2), below the {:g} required; pluck or "
                               "tap harder, or hold the sensor more rigidly",
                               r.impact_s, ch.strength, ch.name, ch.signal_rms, ch.noise_rms, o.min_strength),
                   rec.path);
  if (len < min_len)
    throw InputError(fmt::format("{:.3f} s of decay after the impact; at least {:.3f} s are needed for lines down to "
                                 "{:g} Hz (record longer, or raise --ringdown-min)",
                                 r.window_s, static_cast<double>(min_len) / fs, o.min_hz),
                     rec.path);
  if (cl.lines.empty())
    throw FitError(fmt::format("no spectral line between {} and {:.0f} Hz", o.min_hz, max_hz), rec.path);
  const std::span<const double> xall(rec.channels[static_cast<std::size_t>(chosen)]);
  const std::vector<double> win(xall.begin() + static_cast<std::ptrdiff_t>(start),
                                xall.begin() + static_cast<std::ptrdiff_t>(start + len));
  const auto& lines = cl.lines;
  const double floor = cl.floor;
  const RingdownLine top = cl.top;
  const RingdownLine fund = cl.fund;
  r.strongest_peak_hz = top.freq_hz;
  r.spectral_freq_hz = fund.freq_hz;
  r.strongest_is_harmonic = cl.harmonic > 1;
  r.harmonic_number = cl.harmonic;
  if (r.strongest_is_harmonic)
    r.warnings.push_back(fmt::format("{}: the strongest line, {:.2f} Hz, is harmonic {} of the fundamental {:.2f} Hz",
                                     ch.name, top.freq_hz, r.harmonic_number, fund.freq_hz));

  // Components: the fundamental, its second harmonic, then the other strong lines.
  std::vector<RingdownLine> comps{fund};
  auto distinct = [&](double f) {
    for (const auto& c : comps)
      if (std::abs(c.freq_hz - f) <= o.harmonic_tolerance * c.freq_hz) return false;
    return true;
  };
  if (const auto* h2 = ringdown_line_near(lines, 2 * fund.freq_hz, o.harmonic_tolerance);
      h2 && h2->height >= 4 * floor && static_cast<int>(comps.size()) < o.max_components && distinct(h2->freq_hz))
    comps.push_back(*h2);
  for (const auto& l : lines) {
    if (static_cast<int>(comps.size()) >= o.max_components) break;
    if (l.height >= 0.3 * top.height && l.height >= 4 * floor && distinct(l.freq_hz)) comps.push_back(l);
  }

  // 4. Start values from the matrix pencil where it finds the line, then least squares.
  std::vector<fitting::PencilComponent> pencil;
  try {
    pencil = fitting::matrix_pencil(win, fs, 2 * o.max_components + 4);
  } catch (const Error&) {
    pencil.clear();  // the spectral start values below serve
  }
  std::vector<fitting::PencilComponent> starts;
  for (const auto& c : comps) {
    fitting::PencilComponent s;
    s.freq_hz = c.freq_hz;
    s.zeta = 0.01;
    for (const auto& p : pencil)
      if (std::abs(p.freq_hz - c.freq_hz) <= o.harmonic_tolerance * c.freq_hz && p.zeta > 0 && p.zeta < 0.5) {
        s.freq_hz = p.freq_hz;
        s.zeta = p.zeta;
        break;
      }
    starts.push_back(s);
  }
  try {
    r.fit = fitting::fit_damped_sinusoids(win, fs, starts, o.max_line_shift);
  } catch (const Error& e) {
    throw FitError(fmt::format("the damped-sinusoid fit of the decay in {} failed: {}", ch.name, e.message()),
                   rec.path);
  }
  const auto& pf = r.fit.param("f0_hz");
  const auto& pz = r.fit.param("zeta0");
  if (std::abs(pf.value - fund.freq_hz) >= 0.999 * o.max_line_shift * fund.freq_hz)
    throw FitError(fmt::format("the fit moved the fundamental from {:.2f} Hz (spectrum) to {:.2f} Hz; the decay is "
                               "not a sum of damped sinusoids",
                               fund.freq_hz, pf.value),
                   rec.path);
  r.freq_hz = pf.value;
  r.freq_stderr_hz = pf.std_error;
  r.freq_ci95_lo = pf.ci95_lo;
  r.freq_ci95_hi = pf.ci95_hi;
  r.zeta = pz.value;
  r.zeta_stderr = pz.std_error;
  r.zeta_ci95_lo = pz.ci95_lo;
  r.zeta_ci95_hi = pz.ci95_hi;
  r.damped_freq_hz = r.freq_hz * std::sqrt(1 - r.zeta * r.zeta);
  for (std::size_t i = 1; i < starts.size(); ++i) r.other_lines_hz.push_back(r.fit.value(fmt::format("f{}_hz", i)));
  if (r.fit.diagnostics.whiteness_p < 0.01)
    r.warnings.push_back(
        fmt::format("{}: the fit's residuals are not white (p = {:.2g}): other motion than the fitted "
                    "lines; the intervals are optimistic",
                    ch.name, r.fit.diagnostics.whiteness_p));
  return r;
}

nlohmann::json to_json(const RingdownResult& r) {
  nlohmann::json ch = nlohmann::json::array();
  for (const auto& c : r.channels)
    ch.push_back({{"name", c.name},
                  {"signal_rms_mm_s2", c.signal_rms},
                  {"noise_rms_mm_s2", c.noise_rms},
                  {"strength", c.strength}});
  return {{"file", r.path},
          {"channel", r.channel},
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
          {"freq_hz", r.freq_hz},
          {"freq_stderr_hz", r.freq_stderr_hz},
          {"freq_ci95", {r.freq_ci95_lo, r.freq_ci95_hi}},
          {"damped_freq_hz", r.damped_freq_hz},
          {"zeta", r.zeta},
          {"zeta_stderr", r.zeta_stderr},
          {"zeta_ci95", {r.zeta_ci95_lo, r.zeta_ci95_hi}},
          {"other_lines_hz", r.other_lines_hz},
          {"fit", fitting::to_json(r.fit)}};
}

}  // namespace tunekit::ident
