#include "tunekit/ident/spectrum.hpp"

#include <cmath>
#include <future>
#include <mutex>
#include <stdexcept>
#include <numbers>

#include <boost/math/special_functions/bessel.hpp>
#include <fftw3.h>
#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/core/text.hpp"
#include "tunekit/formats/csv.hpp"

namespace tunekit::ident {

using core::iequals;
namespace {

// FFTW's planner is not thread-safe; execution with new-array functions is.
std::mutex& planner_mutex() {
  static std::mutex m;
  return m;
}

// A real-to-complex transform of fixed length with its own aligned buffers.
class RealFft {
 public:
  explicit RealFft(std::size_t n) : n_(n), in_(fftw_alloc_real(n)), out_(fftw_alloc_complex(n / 2 + 1)) {
    std::lock_guard lock(planner_mutex());
    plan_ = fftw_plan_dft_r2c_1d(static_cast<int>(n), in_, out_, FFTW_ESTIMATE);
    owns_plan_ = true;
  }
  // Buffers of its own that execute `planned`'s plan (FFTW's new-array execution, which is
  // thread-safe; fftw_alloc gives every buffer the alignment the plan was made for): channels
  // transformed side by side share one plan instead of each planning under the lock.
  explicit RealFft(const RealFft& planned)
      : n_(planned.n_), in_(fftw_alloc_real(n_)), out_(fftw_alloc_complex(n_ / 2 + 1)), plan_(planned.plan_) {}
  ~RealFft() {
    if (owns_plan_) {
      std::lock_guard lock(planner_mutex());
      fftw_destroy_plan(plan_);
    }
    fftw_free(in_);
    fftw_free(out_);
  }
  RealFft& operator=(const RealFft&) = delete;
  double* input() { return in_; }
  std::complex<double> bin(std::size_t k) const { return {out_[k][0], out_[k][1]}; }
  void execute() { fftw_execute_dft_r2c(plan_, in_, out_); }
  std::size_t bins() const { return n_ / 2 + 1; }

 private:
  std::size_t n_;
  double* in_;
  fftw_complex* out_;
  fftw_plan plan_;
  bool owns_plan_ = false;
};

// One segment of x, detrended and windowed, into out: out[i] = (x[i] - trend[i]) * w[i], the
// same operations as detrending a copy in place and then windowing it, in one pass.
void detrended_windowed(const double* x, std::size_t n, Detrend d, const double* w, double* out) {
  if (d == Detrend::none) {
    for (std::size_t i = 0; i < n; ++i) out[i] = x[i] * w[i];
    return;
  }
  double mean = 0;
  for (std::size_t i = 0; i < n; ++i) mean += x[i];
  mean /= static_cast<double>(n);
  if (d == Detrend::constant) {
    for (std::size_t i = 0; i < n; ++i) out[i] = (x[i] - mean) * w[i];
    return;
  }
  const double tm = 0.5 * static_cast<double>(n - 1);
  double sxy = 0, sxx = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double dt = static_cast<double>(i) - tm;
    sxy += dt * (x[i] - mean);
    sxx += dt * dt;
  }
  const double slope = sxx > 0 ? sxy / sxx : 0;
  for (std::size_t i = 0; i < n; ++i) out[i] = (x[i] - (mean + slope * (static_cast<double>(i) - tm))) * w[i];
}

struct SegmentPlan {
  std::size_t nperseg, step, count;
};

SegmentPlan plan_segments(std::size_t n, double fs, const WelchOptions& o) {
  const std::size_t nperseg = resolve_segment_length(o, fs);
  const auto noverlap = static_cast<std::size_t>(std::floor(o.overlap * static_cast<double>(nperseg)));
  const std::size_t step = nperseg - noverlap;
  if (n < nperseg + step)
    throw InputError(
        fmt::format("the record has {} samples; Welch's method needs at least two segments of {} "
                    "samples ({} s at {} Hz); record longer or use a shorter segment",
                    n, nperseg, static_cast<double>(nperseg + step) / fs, fs));
  return {nperseg, step, (n - nperseg) / step + 1};
}

}  // namespace

WindowType parse_window(const std::string& name) {
  if (iequals(name, "hann") || iequals(name, "hanning")) return WindowType::hann;
  if (iequals(name, "hamming")) return WindowType::hamming;
  if (iequals(name, "kaiser")) return WindowType::kaiser;
  if (iequals(name, "rect") || iequals(name, "rectangular") || iequals(name, "boxcar")) return WindowType::rectangular;
  throw InputError("unknown window '" + name + "' (hann, hamming, kaiser, rect)");
}

std::string to_string(WindowType w) {
  switch (w) {
    case WindowType::hann: return "hann";
    case WindowType::hamming: return "hamming";
    case WindowType::kaiser: return "kaiser";
    case WindowType::rectangular: return "rect";
  }
  return "?";
}

std::vector<double> make_window(WindowType type, std::size_t n, double beta) {
  std::vector<double> w(n, 1.0);
  if (n <= 1) return w;
  const double pi = std::numbers::pi;
  const double N = static_cast<double>(n);
  switch (type) {
    case WindowType::rectangular: break;
    case WindowType::hann:
      for (std::size_t i = 0; i < n; ++i) w[i] = 0.5 - 0.5 * std::cos(2 * pi * static_cast<double>(i) / N);
      break;
    case WindowType::hamming:
      for (std::size_t i = 0; i < n; ++i) w[i] = 0.54 - 0.46 * std::cos(2 * pi * static_cast<double>(i) / N);
      break;
    case WindowType::kaiser: {
      const double i0b = boost::math::cyl_bessel_i(0, beta);
      for (std::size_t i = 0; i < n; ++i) {
        const double r = 2.0 * static_cast<double>(i) / (N - 1) - 1.0;
        w[i] = boost::math::cyl_bessel_i(0, beta * std::sqrt(std::max(0.0, 1 - r * r))) / i0b;
      }
      break;
    }
  }
  return w;
}

WelchOptions klipper_welch_options() {
  WelchOptions o;
  o.window = WindowType::kaiser;
  o.kaiser_beta = 6.0;
  o.segment_length = 0;
  o.overlap = 0.5;
  o.detrend = Detrend::constant;
  return o;
}

std::size_t resolve_segment_length(const WelchOptions& o, double fs) {
  if (!(fs > 0) || !std::isfinite(fs)) throw InputError(fmt::format("sampling rate {} Hz is not positive", fs));
  if (!(o.overlap >= 0 && o.overlap < 1)) throw InputError(fmt::format("overlap {} must be in [0, 1)", o.overlap));
  std::size_t n = o.segment_length;
  if (n == 0) n = std::size_t{1} << static_cast<int>(std::ceil(std::log2(std::max(2.0, fs * 0.5))));
  if (n < 8) throw InputError(fmt::format("segment length {} is too short (at least 8 samples)", n));
  return n;
}

std::vector<double> padded_amplitude_spectrum(std::span<const double> x, std::size_t nfft) {
  if (x.size() < 2 || nfft < x.size()) throw InputError("padded spectrum: nfft must be at least the record length");
  const auto w = make_window(WindowType::hann, x.size());
  double mean = 0;
  for (double v : x) mean += v;
  mean /= static_cast<double>(x.size());
  RealFft fft(nfft);
  double* in = fft.input();
  for (std::size_t i = 0; i < nfft; ++i) in[i] = i < x.size() ? (x[i] - mean) * w[i] : 0.0;
  fft.execute();
  std::vector<double> mag(fft.bins());
  for (std::size_t k = 0; k < mag.size(); ++k) mag[k] = std::abs(fft.bin(k));
  return mag;
}

namespace {

// The Welch PSD of x with its segments, window (and the window's energy) and a transform of the
// segment length given.
Spectrum welch_with(std::span<const double> x, double fs, const WelchOptions& o, const SegmentPlan& sp,
                    const std::vector<double>& w, double wss, RealFft& fft) {
  Spectrum s;
  s.sample_rate_hz = fs;
  s.segment_length = sp.nperseg;
  s.segments = sp.count;
  s.psd.assign(fft.bins(), 0.0);
  for (std::size_t k = 0; k < sp.count; ++k) {
    detrended_windowed(x.data() + k * sp.step, sp.nperseg, o.detrend, w.data(), fft.input());
    fft.execute();
    for (std::size_t b = 0; b < fft.bins(); ++b) s.psd[b] += std::norm(fft.bin(b));
  }
  const double scale = 1.0 / (fs * wss * static_cast<double>(sp.count));
  s.freq_hz.resize(fft.bins());
  for (std::size_t b = 0; b < fft.bins(); ++b) {
    s.freq_hz[b] = static_cast<double>(b) * fs / static_cast<double>(sp.nperseg);
    const bool edge = b == 0 || (sp.nperseg % 2 == 0 && b == fft.bins() - 1);
    s.psd[b] *= scale * (edge ? 1.0 : 2.0);
  }
  return s;
}

double window_energy(const std::vector<double>& w) {
  double wss = 0;
  for (double v : w) wss += v * v;
  return wss;
}

}  // namespace

Spectrum welch_psd(std::span<const double> x, double fs, const WelchOptions& o) {
  const auto sp = plan_segments(x.size(), fs, o);
  const auto w = make_window(o.window, sp.nperseg, o.kaiser_beta);
  RealFft fft(sp.nperseg);
  return welch_with(x, fs, o, sp, w, window_energy(w), fft);
}

std::vector<Spectrum> welch_psds(std::span<const std::span<const double>> channels, double fs, const WelchOptions& o) {
  std::vector<Spectrum> out(channels.size());
  if (channels.empty()) return out;
  const std::size_t n = channels.front().size();
  for (const auto& c : channels)
    if (c.size() != n) throw std::invalid_argument("welch_psds: the channels differ in length");
  const auto sp = plan_segments(n, fs, o);
  const auto w = make_window(o.window, sp.nperseg, o.kaiser_beta);
  const double wss = window_energy(w);
  RealFft planned(sp.nperseg);
  std::vector<std::future<Spectrum>> others;
  for (std::size_t c = 1; c < channels.size(); ++c)
    others.push_back(std::async(std::launch::async, [&, c] {
      RealFft fft(planned);
      return welch_with(channels[c], fs, o, sp, w, wss, fft);
    }));
  out[0] = welch_with(channels[0], fs, o, sp, w, wss, planned);
  for (std::size_t c = 1; c < channels.size(); ++c) out[c] = others[c - 1].get();
  return out;
}

CrossSpectrum welch_csd(std::span<const double> x, std::span<const double> y, double fs, const WelchOptions& o) {
  if (x.size() != y.size())
    throw InputError(fmt::format("input and output records differ in length ({} and {} samples)", x.size(), y.size()));
  const auto sp = plan_segments(x.size(), fs, o);
  const auto w = make_window(o.window, sp.nperseg, o.kaiser_beta);
  double wss = 0;
  for (double v : w) wss += v * v;
  RealFft fx(sp.nperseg), fy(fx);
  CrossSpectrum c;
  c.sample_rate_hz = fs;
  c.segment_length = sp.nperseg;
  c.segments = sp.count;
  const std::size_t nb = fx.bins();
  c.pxy.assign(nb, {0, 0});
  c.pxx.assign(nb, 0);
  c.pyy.assign(nb, 0);
  for (std::size_t k = 0; k < sp.count; ++k) {
    detrended_windowed(x.data() + k * sp.step, sp.nperseg, o.detrend, w.data(), fx.input());
    detrended_windowed(y.data() + k * sp.step, sp.nperseg, o.detrend, w.data(), fy.input());
    fx.execute();
    fy.execute();
    for (std::size_t b = 0; b < nb; ++b) {
      const auto X = fx.bin(b), Y = fy.bin(b);
      c.pxy[b] += std::conj(X) * Y;
      c.pxx[b] += std::norm(X);
      c.pyy[b] += std::norm(Y);
    }
  }
  const double scale = 1.0 / (fs * wss * static_cast<double>(sp.count));
  c.freq_hz.resize(nb);
  for (std::size_t b = 0; b < nb; ++b) {
    c.freq_hz[b] = static_cast<double>(b) * fs / static_cast<double>(sp.nperseg);
    const double s = scale * ((b == 0 || (sp.nperseg % 2 == 0 && b == nb - 1)) ? 1.0 : 2.0);
    c.pxy[b] *= s;
    c.pxx[b] *= s;
    c.pyy[b] *= s;
  }
  return c;
}

FrequencyResponse h1_estimate(std::span<const double> x, std::span<const double> y, double fs, const WelchOptions& o) {
  const auto c = welch_csd(x, y, fs, o);
  FrequencyResponse r;
  r.freq_hz = c.freq_hz;
  r.segments = c.segments;
  r.h.resize(c.freq_hz.size());
  r.coherence.resize(c.freq_hz.size());
  for (std::size_t b = 0; b < c.freq_hz.size(); ++b) {
    r.h[b] = c.pxx[b] > 0 ? c.pxy[b] / c.pxx[b] : std::complex<double>(0, 0);
    const double den = c.pxx[b] * c.pyy[b];
    r.coherence[b] = den > 0 ? std::min(1.0, std::norm(c.pxy[b]) / den) : 0.0;
  }
  return r;
}

}  // namespace tunekit::ident
