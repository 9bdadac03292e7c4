#include "ringdown_series.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <numbers>

#include "tunekit/fitting/stats.hpp"

namespace tunekit::ident::ringdown_detail {

std::vector<Line> spectral_lines(const std::vector<double>& p, double df, double lo, double hi) {
  std::vector<Line> out;
  if (p.size() < 3) return out;
  const std::size_t k0 = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(lo / df)));
  const std::size_t k1 = std::min(p.size() - 2, static_cast<std::size_t>(hi / df));
  for (std::size_t k = k0; k <= k1; ++k) {
    if (!(p[k] > p[k - 1] && p[k] >= p[k + 1])) continue;
    // Parabola through the log powers (a Gaussian-like peak): the peak's position and height.
    const double a = std::log(std::max(p[k - 1], 1e-300)), b = std::log(std::max(p[k], 1e-300)),
                 c = std::log(std::max(p[k + 1], 1e-300));
    const double den = a - 2 * b + c;
    const double d = den != 0 ? std::clamp(0.5 * (a - c) / den, -0.5, 0.5) : 0.0;
    out.push_back({(static_cast<double>(k) + d) * df, std::exp(b - 0.25 * (a - c) * d)});
  }
  std::sort(out.begin(), out.end(), [](const Line& x, const Line& y) { return x.power > y.power; });
  return out;
}

const Line* line_near(const std::vector<Line>& lines, double f, double tol) {
  const Line* best = nullptr;
  for (const auto& l : lines)
    if (std::abs(l.freq_hz - f) <= tol * f && (!best || l.power > best->power)) best = &l;
  return best;
}

double spectral_floor(const std::vector<double>& p, double df, double lo, double hi) {
  std::vector<double> band;
  for (auto k = static_cast<std::size_t>(lo / df); k < p.size() && static_cast<double>(k) * df <= hi; ++k)
    band.push_back(p[k]);
  return band.empty() ? 0.0 : fitting::median(band);
}

SeriesChoice choose_fundamental(const std::vector<Line>& lines, double min_power, double min_rel, double f_min,
                                double f_max, double tol, double lone_factor, const SubharmonicRule& sub,
                                const std::vector<double>& excluded) {
  SeriesChoice out;
  if (lines.empty()) return out;
  out.strongest = lines.front();
  std::vector<Line> clear;
  for (const auto& l : lines)
    if (l.power >= min_power && l.power >= min_rel * out.strongest.power && l.freq_hz >= f_min) clear.push_back(l);
  std::vector<Line> heads = clear;
  for (const auto& l : clear)
    for (int k = 2; k <= 2 && sub.min_power > 0; ++k) {
      const Line* g = line_near(lines, l.freq_hz / k, tol);
      if (g == nullptr || g->freq_hz < f_min || g->power < sub.min_power || g->power < sub.min_rel * l.power) continue;
      if (line_near(heads, g->freq_hz, 1e-9) == nullptr) heads.push_back(*g);
    }
  for (const auto& g : lines) {
    if (sub.pair_power <= 0 || g.power < sub.pair_power || g.freq_hz < f_min) continue;
    const Line* h = line_near(lines, 2 * g.freq_hz, tol);
    if (h != nullptr && h->power >= sub.pair_power && line_near(heads, g.freq_hz, 1e-9) == nullptr) heads.push_back(g);
  }
  const double harmonic_power = sub.pair_power > 0 ? std::min(min_power, sub.pair_power) : min_power;
  std::vector<Series> candidates;
  for (const auto& l : heads) {
    if (std::any_of(excluded.begin(), excluded.end(), [&](double f) { return std::abs(f - l.freq_hz) <= 1e-9 * f; }))
      continue;
    Series s;
    s.fundamental = l;
    s.power = l.power;
    const int k_max = static_cast<int>(std::floor(f_max * (1 + tol) / l.freq_hz));
    for (int k = 2; k <= k_max; ++k) {
      const auto* h = line_near(lines, k * l.freq_hz, tol);
      if (h == nullptr || h->power < harmonic_power) continue;
      s.harmonics.emplace_back(k, *h);
      s.power += h->power;
    }
    candidates.push_back(std::move(s));
  }
  if (candidates.empty()) return out;
  auto better = [&](const Series& a, const Series& b) {  // a preferred over b
    const bool ha = !a.harmonics.empty(), hb = !b.harmonics.empty();
    if (ha && !hb) return b.power <= lone_factor * a.power;
    if (!ha && hb) return a.power > lone_factor * b.power;
    return a.power > b.power;
  };
  out.best = candidates.front();
  for (const auto& c : candidates)
    if (better(c, out.best)) out.best = c;
  out.found = true;
  return out;
}

std::vector<double> best_projection(const std::vector<std::span<const double>>& windows,
                                    const std::vector<double>& noise, double f_hz, double fs) {
  const std::size_t m = windows.size();
  std::vector<std::complex<double>> z(m);
  for (std::size_t c = 0; c < m; ++c) {
    const auto& x = windows[c];
    const std::size_t n = x.size();
    double mean = 0;
    for (double v : x) mean += v;
    mean /= static_cast<double>(std::max<std::size_t>(n, 1));
    std::complex<double> acc = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const double w = 0.5 - 0.5 * std::cos(2 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(n));
      acc += (x[i] - mean) * w * std::polar(1.0, -2 * std::numbers::pi * f_hz * static_cast<double>(i) / fs);
    }
    z[c] = noise[c] > 0 ? acc / noise[c] : acc;  // whitened: equal noise in every channel
  }
  // A = Re z Re z^T + Im z Im z^T; its principal eigenvector by power iteration.
  std::vector<double> a(m * m);
  for (std::size_t i = 0; i < m; ++i)
    for (std::size_t j = 0; j < m; ++j) a[i * m + j] = z[i].real() * z[j].real() + z[i].imag() * z[j].imag();
  std::vector<double> u(m, 1.0 / std::sqrt(static_cast<double>(m)));
  std::size_t best = 0;
  for (std::size_t c = 1; c < m; ++c)
    if (std::abs(z[c]) > std::abs(z[best])) best = c;
  std::fill(u.begin(), u.end(), 0.0);
  u[best] = 1.0;
  for (int it = 0; it < 200; ++it) {
    std::vector<double> v(m, 0.0);
    for (std::size_t i = 0; i < m; ++i)
      for (std::size_t j = 0; j < m; ++j) v[i] += a[i * m + j] * u[j];
    double norm = 0;
    for (double e : v) norm += e * e;
    norm = std::sqrt(norm);
    if (!(norm > 0)) break;
    for (std::size_t i = 0; i < m; ++i) u[i] = v[i] / norm;
  }
  // Back to the channels' own units: y = sum_c (u_c / noise_c) x_c, normalised to unit weights.
  std::vector<double> w(m);
  double s = 0;
  for (std::size_t c = 0; c < m; ++c) {
    w[c] = noise[c] > 0 ? u[c] / noise[c] : u[c];
    s += w[c] * w[c];
  }
  s = std::sqrt(s);
  if (!(s > 0)) {
    std::fill(w.begin(), w.end(), 0.0);
    w[best] = 1.0;
    return w;
  }
  // Sign: the largest weight positive.
  std::size_t big = 0;
  for (std::size_t c = 1; c < m; ++c)
    if (std::abs(w[c]) > std::abs(w[big])) big = c;
  const double sign = w[big] < 0 ? -1.0 : 1.0;
  for (double& e : w) e = sign * e / s;
  return w;
}

}  // namespace tunekit::ident::ringdown_detail
