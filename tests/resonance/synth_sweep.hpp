#pragma once
// Synthetic accelerometer recordings of a Klipper-style resonance test: the commanded
// acceleration is a sine whose amplitude is accel_per_hz * f and whose frequency rises at
// hz_per_sec; the toolhead acceleration is d * a_cmd + sum_k g_k y_k with every mode
// y_k'' + 2 z_k w_k y_k' + w_k^2 y_k = w_k^2 a_cmd (integrated with RK4, 4 substeps per
// sample), plus Gaussian sensor noise. Used by the resonance tests and benchmark.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace tunekit::test {

struct SynthMode {
  double freq_hz;
  double zeta;
  double gain;
};

struct SweepSpec {
  double sample_rate_hz = 3200;
  double f_start_hz = 5;
  double f_end_hz = 133;
  double hz_per_sec = 1;
  double accel_per_hz = 60;  // mm/s^2 per Hz
  double noise_mm_s2 = 100;  // std. dev. per channel
  double direct = 0;         // d
  double t0_s = 1000.0;      // Klipper timestamps are print times
  double clip_mm_s2 = 0;     // >0: saturate the channels at +-clip
  unsigned seed = 1;
};

struct SynthRecord {
  std::vector<double> t, ax, ay, az, cmd;
};

inline SynthRecord synth_sweep(const std::vector<SynthMode>& modes, const SweepSpec& s) {
  const double pi = std::numbers::pi;
  const double T = (s.f_end_hz - s.f_start_hz) / s.hz_per_sec;
  const auto n = static_cast<std::size_t>(T * s.sample_rate_hz);
  const double dt = 1.0 / s.sample_rate_hz;
  const int sub = 4;
  const double h = dt / sub;
  auto cmd = [&](double t) {
    const double f = s.f_start_hz + s.hz_per_sec * t;
    return s.accel_per_hz * f * std::sin(2 * pi * (s.f_start_hz * t + 0.5 * s.hz_per_sec * t * t));
  };
  std::vector<double> x(modes.size(), 0.0), v(modes.size(), 0.0);
  SynthRecord r;
  r.t.resize(n);
  r.ax.resize(n);
  r.ay.resize(n);
  r.az.resize(n);
  r.cmd.resize(n);
  std::mt19937_64 rng(s.seed);
  std::normal_distribution<double> noise(0.0, s.noise_mm_s2);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) * dt;
    const double a = cmd(t);
    double y = s.direct * a;
    for (std::size_t k = 0; k < modes.size(); ++k) y += modes[k].gain * x[k];
    auto clip = [&](double val) { return s.clip_mm_s2 > 0 ? std::clamp(val, -s.clip_mm_s2, s.clip_mm_s2) : val; };
    r.t[i] = s.t0_s + t;
    r.cmd[i] = a;
    r.ax[i] = clip(y + noise(rng));
    r.ay[i] = clip(0.05 * y + noise(rng));
    r.az[i] = clip(9806.65 + noise(rng));
    for (std::size_t k = 0; k < modes.size(); ++k) {
      const double w = 2 * pi * modes[k].freq_hz, z = modes[k].zeta;
      for (int j = 0; j < sub; ++j) {
        const double ts = t + j * h;
        auto acc = [&](double tt, double xx, double vv) { return w * w * (cmd(tt) - xx) - 2 * z * w * vv; };
        const double k1x = v[k], k1v = acc(ts, x[k], v[k]);
        const double k2x = v[k] + 0.5 * h * k1v, k2v = acc(ts + 0.5 * h, x[k] + 0.5 * h * k1x, k2x);
        const double k3x = v[k] + 0.5 * h * k2v, k3v = acc(ts + 0.5 * h, x[k] + 0.5 * h * k2x, k3x);
        const double k4x = v[k] + h * k3v, k4v = acc(ts + h, x[k] + h * k3x, k4x);
        x[k] += h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
        v[k] += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
      }
    }
  }
  return r;
}

/// Klipper's raw format: `#time,accel_x,accel_y,accel_z` then "%.6f,%.6f,%.6f,%.6f" rows;
/// with_cmd appends a commanded-acceleration column `accel_cmd`.
inline std::string to_klipper_csv(const SynthRecord& r, bool with_cmd = false) {
  std::string out = with_cmd ? "#time,accel_x,accel_y,accel_z,accel_cmd\n" : "#time,accel_x,accel_y,accel_z\n";
  out.reserve(r.t.size() * (with_cmd ? 60 : 48));
  char buf[160];
  for (std::size_t i = 0; i < r.t.size(); ++i) {
    const int len =
        with_cmd
            ? std::snprintf(buf, sizeof buf, "%.6f,%.6f,%.6f,%.6f,%.6f\n", r.t[i], r.ax[i], r.ay[i], r.az[i], r.cmd[i])
            : std::snprintf(buf, sizeof buf, "%.6f,%.6f,%.6f,%.6f\n", r.t[i], r.ax[i], r.ay[i], r.az[i]);
    out.append(buf, static_cast<std::size_t>(len));
  }
  return out;
}

}  // namespace tunekit::test
