#pragma once
// Synthetic belt plucks for the ring-down and belt tests: a harmonic series (fundamental, 2nd
// and 3rd harmonic, each with its own amplitude, damping, phase and direction in the sensor's
// three axes), white noise in every axis, 0.1 s of quiet before the pluck. Also a tap (a
// heavily damped frame mode), a fan's steady tone and a bump (one half-sine, no ringing).

#include <cmath>
#include <numbers>
#include <random>
#include <sstream>
#include <string>

#include "tunekit/ident/resonance.hpp"

namespace tunekit::test {

struct PluckTruth {
  double f_hz = 110.0;
  double zeta[3] = {0.012, 0.010, 0.015};                                  // fundamental, 2nd, 3rd harmonic
  double amp[3] = {400.0, 800.0, 200.0};                                   // mm/s^2 at the pluck
  double dir[3][3] = {{0.8, 0.6, 0.0}, {0.3, 0.9, 0.3}, {0.6, 0.0, 0.8}};  // unit vectors in (x, y, z)
  double phase[3] = {0.3, -0.2, 1.1};
  double noise = 20.0;  // mm/s^2 per axis, white
  double fs = 3200.0;
  double post_s = 0.6;
};

enum class Event { pluck, tap, fan, bump, none };

/// A random pluck: f in [70, 150] Hz, the 2nd harmonic at 0.5-3x the fundamental's amplitude,
/// the 3rd at 0.5x, random directions and phases.
inline PluckTruth random_pluck(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> g(0.0, 1.0);
  PluckTruth t;
  t.f_hz = 70 + 80 * u(rng);
  t.amp[0] = 400;
  t.amp[1] = 400 * (0.5 + 2.5 * u(rng));
  t.amp[2] = 200;
  for (int k = 0; k < 3; ++k) {
    t.zeta[k] = 0.008 + 0.012 * u(rng);
    t.phase[k] = 2 * std::numbers::pi * u(rng);
    double n = 0;
    for (double& d : t.dir[k]) {
      d = g(rng);
      n += d * d;
    }
    for (double& d : t.dir[k]) d /= std::sqrt(n);
  }
  return t;
}

inline ident::AccelRecord synth_event(const PluckTruth& tr, unsigned seed, Event ev = Event::pluck) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, tr.noise);
  ident::AccelRecord r;
  r.path = "synthetic";
  r.channel_names = {"accel_x", "accel_y", "accel_z"};
  r.channels.resize(3);
  const int pre = static_cast<int>(0.1 * tr.fs), post = static_cast<int>(tr.post_s * tr.fs);
  const double two_pi = 2 * std::numbers::pi;
  for (int i = -pre; i < post; ++i) {
    const double t = i / tr.fs;
    double s[3] = {0, 0, 9806.0};
    auto mode = [&](double f, double z, double a, double ph) {
      const double w = two_pi * f;
      return a * std::exp(-z * w * t) * std::cos(w * std::sqrt(1 - z * z) * t + ph);
    };
    if (ev == Event::pluck && i >= 0)
      for (int k = 0; k < 3; ++k) {
        const double m = mode((k + 1) * tr.f_hz, tr.zeta[k], tr.amp[k], tr.phase[k]);
        for (int c = 0; c < 3; ++c) s[c] += tr.dir[k][c] * m;
      }
    if (ev == Event::tap && i >= 0) {  // a sharp knock, then a frame mode with zeta 0.15
      const double m = (i < 3 ? 3000.0 : 0.0) + mode(48.0, 0.15, 1500.0, 0.0);
      s[0] += 0.7 * m;
      s[1] += 0.7 * m;
    }
    if (ev == Event::fan)  // a steady tone throughout, and one small knock
      s[0] += 300 * std::cos(two_pi * 117.0 * t) + (i == 0 ? 600.0 : 0.0);
    if (ev == Event::bump && i >= 0 && t < 0.04)  // a push: one half-sine of 40 ms
      s[1] += 1500 * std::sin(std::numbers::pi * t / 0.04);
    for (int c = 0; c < 3; ++c) r.channels[static_cast<std::size_t>(c)].push_back(s[c] + noise(rng));
  }
  r.sampling.sample_rate_hz = tr.fs;
  r.sampling.samples = r.channels[0].size();
  r.sampling.duration_s = static_cast<double>(r.sampling.samples) / tr.fs;
  return r;
}

/// The record as a Klipper-style CSV (#time,accel_x,accel_y,accel_z).
inline std::string to_csv(const ident::AccelRecord& r) {
  std::ostringstream os;
  os.precision(10);
  os << "#time,accel_x,accel_y,accel_z\n";
  for (std::size_t i = 0; i < r.channels[0].size(); ++i)
    os << 100.0 + static_cast<double>(i) / r.sampling.sample_rate_hz << ',' << r.channels[0][i] << ','
       << r.channels[1][i] << ',' << r.channels[2][i] << '\n';
  return os.str();
}

}  // namespace tunekit::test
