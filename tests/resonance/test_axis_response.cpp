// The output-error fit of an axis against its commanded motion (axis_response_fit.hpp) and the
// exact response of a base-excited mode it rests on (base_excited_mode.hpp). The records here are
// made by a fine Runge-Kutta integration, independent of the closed form under test.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "tunekit/core/error.hpp"
#include "tunekit/ident/axis_response_fit.hpp"
#include "tunekit/ident/base_excited_mode.hpp"
#include "tunekit/ident/commanded_motion.hpp"

using namespace tunekit;

namespace {

struct State {
  double z = 0, v = 0;
};

/// Classical Runge-Kutta over h with `steps` steps of z'' = -c z' - k z - a(s), a = a0 + j s.
State rk4(State x, double f, double zeta, double h, double a0, double j, int steps) {
  const double w = 2 * std::numbers::pi * f, c = 2 * zeta * w, k = w * w, dt = h / steps;
  auto acc = [&](double s, double z, double v) { return -c * v - k * z - (a0 + j * s); };
  for (int i = 0; i < steps; ++i) {
    const double s = i * dt;
    const double k1z = x.v, k1v = acc(s, x.z, x.v);
    const double k2z = x.v + dt / 2 * k1v, k2v = acc(s + dt / 2, x.z + dt / 2 * k1z, x.v + dt / 2 * k1v);
    const double k3z = x.v + dt / 2 * k2v, k3v = acc(s + dt / 2, x.z + dt / 2 * k2z, x.v + dt / 2 * k2v);
    const double k4z = x.v + dt * k3v, k4v = acc(s + dt, x.z + dt * k3z, x.v + dt * k3v);
    x.z += dt / 6 * (k1z + 2 * k2z + 2 * k3z + k4z);
    x.v += dt / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
  }
  return x;
}

/// A sweep as a planner runs one: the acceleration +-A(f) held for each half period of a
/// frequency rising from f0 at `rate` Hz/s, A = accel_per_hz * f (Klipper's test_resonances).
std::vector<ident::AccelPiece> square_sweep(double t_start, double f0, double f1, double rate, double accel_per_hz) {
  std::vector<ident::AccelPiece> out;
  double t = t_start, sign = 1;
  for (double f = f0; f < f1;) {
    const double half = 0.5 / f;
    out.push_back({t, half, sign * accel_per_hz * f, 0.0});
    t += half;
    sign = -sign;
    f += rate * half;
  }
  return out;
}

struct Synth {
  ident::AccelRecord record;
  std::vector<ident::AccelPiece> motion;
};

/// The accelerometer of one mode (f, zeta, gain 1) on the sweep, sampled at fs from t = 0 with
/// white noise; the motion starts at 0.25 s.
Synth synth(double f, double zeta, double noise, unsigned seed) {
  Synth s;
  const double fs = 3200;
  s.motion = square_sweep(0.25, 15, 80, 5, 60);
  const double t_end = s.motion.back().t0_s + s.motion.back().duration_s + 0.5;
  const auto n = static_cast<std::size_t>(t_end * fs);
  std::vector<double> ax(n), ay(n, 0.0), az(n, 9806.65);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, noise);
  State x;
  std::size_t p = 0;
  double t = 0;
  const double w = 2 * std::numbers::pi * f;
  auto a_at = [&](double tt) {
    for (std::size_t q = p; q < s.motion.size() && s.motion[q].t0_s <= tt; ++q)
      if (tt < s.motion[q].t0_s + s.motion[q].duration_s) return s.motion[q].accel_mm_s2;
    return 0.0;
  };
  for (std::size_t i = 0; i < n; ++i) {
    const double ti = static_cast<double>(i) / fs;
    while (t < ti) {  // up to the next piece boundary or the sample, with the piece's acceleration
      while (p < s.motion.size() && s.motion[p].t0_s + s.motion[p].duration_s <= t) ++p;
      double to = ti, a = 0;
      if (p < s.motion.size() && s.motion[p].t0_s <= t) {
        to = std::min(ti, s.motion[p].t0_s + s.motion[p].duration_s);
        a = s.motion[p].accel_mm_s2;
      } else if (p < s.motion.size()) {
        to = std::min(ti, s.motion[p].t0_s);
      }
      x = rk4(x, f, zeta, to - t, a, 0, 8);
      t = to;
    }
    const double rel = -2 * zeta * w * x.v - w * w * x.z - a_at(ti);
    ax[i] = a_at(ti) + rel + gauss(rng);
  }
  auto& r = s.record;
  r.path = "synthetic";
  r.axis = 'x';
  r.channel_names = {"accel_x", "accel_y", "accel_z"};
  r.channels = {ax, ay, az};
  r.sampling.sample_rate_hz = fs;
  r.sampling.samples = n;
  r.start_time_s = 0;
  return s;
}

}  // namespace

TEST_CASE("a base-excited mode over a piece of linear acceleration is exact", "[resonance]") {
  for (double zeta : {0.04, 1.0, 2.5}) {
    const ident::BaseExcitedMode mode(37.5, zeta);
    const ident::ModeState x0{0.01, -3.0};
    for (const auto& [h, a0, j] :
         std::vector<std::array<double, 3>>{{3e-4, 2500, 0}, {0.02, -800, 4e6}, {1e-6, 0, 1e8}}) {
      const auto e = mode.advance(x0, h, a0, j);
      const auto r = rk4({x0.z_mm, x0.v_mm_s}, 37.5, zeta, h, a0, j, 20000);
      INFO("zeta " << zeta << " h " << h << " a0 " << a0 << " j " << j);
      CHECK(e.z_mm == Approx(r.z).epsilon(1e-9).margin(1e-12));
      CHECK(e.v_mm_s == Approx(r.v).epsilon(1e-9).margin(1e-9));
      const auto s = ident::BaseExcitedMode::apply(mode.step(h), x0, a0, j);
      CHECK(s.z_mm == Approx(e.z_mm).epsilon(1e-12).margin(1e-15));
      CHECK(s.v_mm_s == Approx(e.v_mm_s).epsilon(1e-12).margin(1e-12));
    }
  }
  CHECK_THROWS_AS(ident::BaseExcitedMode(0, 0.1), InputError);
  CHECK_THROWS_AS(ident::BaseExcitedMode(40, std::nan("")), InputError);
}

TEST_CASE("the fit against the commanded motion finds the mode, and its intervals cover it 95 % of the time",
          "[resonance]") {
  const double f = 45.3, zeta = 0.07;
  int f_covered = 0, zeta_covered = 0;
  double f_ratio = 0;
  const int seeds = 20;
  for (int seed = 1; seed <= seeds; ++seed) {
    const Synth s = synth(f, zeta, 30, static_cast<unsigned>(seed));
    const auto fit = ident::fit_axis_response(s.record, s.motion, {{44.0, 0.1, 1.0}});
    REQUIRE(fit.modes.size() == 1);
    const auto& m = fit.modes[0];
    INFO("seed " << seed << ": f " << m.freq_hz << " [" << m.freq_ci95_lo << ", " << m.freq_ci95_hi << "], zeta "
                 << m.zeta << " [" << m.zeta_ci95_lo << ", " << m.zeta_ci95_hi << "]");
    CHECK(std::abs(m.freq_hz - f) < 0.01);
    CHECK(std::abs(m.zeta - zeta) < 0.001);
    CHECK(m.gain == Approx(1).epsilon(1e-3));
    CHECK(fit.variance_inflation < 1.2);  // white noise: no inflation to speak of
    f_covered += m.freq_ci95_lo <= f && f <= m.freq_ci95_hi;
    zeta_covered += m.zeta_ci95_lo <= zeta && zeta <= m.zeta_ci95_hi;
    f_ratio += std::abs(m.freq_hz - f) / (0.5 * (m.freq_ci95_hi - m.freq_ci95_lo));
  }
  // 95 % intervals: 15 or fewer of 20 covering has a probability of 0.3 %; the mean |error| of a
  // right interval is 0.41 half-widths (0.8 / 1.96), of one twice too wide 0.2.
  CHECK(f_covered >= 16);
  CHECK(zeta_covered >= 16);
  CHECK(f_ratio / seeds > 0.25);
  CHECK(f_ratio / seeds < 0.7);
}

TEST_CASE("the fit against the commanded motion refuses what it cannot use", "[resonance]") {
  Synth s = synth(45.3, 0.07, 30, 1);
  std::vector<ident::AccelPiece> late = s.motion;
  for (auto& p : late) p.t0_s += 1000;
  CHECK_THROWS_AS(ident::fit_axis_response(s.record, late, {{44.0, 0.1, 1.0}}), InputError);
  CHECK_THROWS_AS(ident::fit_axis_response(s.record, s.motion, {}), InputError);
  s.record.channel_names = {"a", "b", "c"};
  CHECK_THROWS_AS(ident::fit_axis_response(s.record, s.motion, {{44.0, 0.1, 1.0}}), InputError);
}

TEST_CASE("commanded motion files: read, found beside their record, and refused when malformed", "[resonance]") {
  const std::string head = "time (s),duration (s),accel_x (mm/s^2),accel_y (mm/s^2),jerk_x (mm/s^3),jerk_y (mm/s^3)\n";
  const auto p = ident::load_commanded_motion_csv("m.csv", head + "1.0,0.5,100,0,0,0\n1.5,0.25,-50,20,1000,0\n", 'x');
  REQUIRE(p.size() == 2);
  CHECK(p[1].t0_s == 1.5);
  CHECK(p[1].accel_mm_s2 == -50);
  CHECK(p[1].jerk_mm_s3 == 1000);
  CHECK(ident::load_commanded_motion_csv("m.csv", head + "1.0,0.5,100,7,0,0\n", 'y')[0].accel_mm_s2 == 7);
  for (const char* bad : {"1.0,-0.5,100,0,0,0\n", "1.0,0.5,nan,0,0,0\n", "2.0,0.5,1,0,0,0\n1.0,0.5,1,0,0,0\n", ""})
    CHECK_THROWS_AS(ident::load_commanded_motion_csv("m.csv", head + bad, 'x'), InputError);
  CHECK_THROWS_AS(ident::load_commanded_motion_csv("m.csv", "time,duration,accel_x\n1,1,1\n", 'x'), InputError);
  CHECK_THROWS_AS(ident::load_commanded_motion_csv("m.csv", head + "1.0,0.5,100,0,0,0\n", 'z'), InputError);
  CHECK(ident::commanded_motion_beside("/nonexistent/raw_data_x_1.csv").empty());
  CHECK(ident::commanded_motion_beside("accel_x.csv").empty());
}

TEST_CASE("modes from the spectrum are refined against the motion, unless the two do not agree", "[resonance]") {
  const Synth s = synth(45.3, 0.07, 30, 3);
  const auto spectrum = ident::record_spectrum(s.record, ident::klipper_welch_options());
  ident::ResonanceOptions ro;
  ro.fit_min_hz = 15;
  ro.fit_max_hz = 80;
  const ident::AxisModes from_spectrum = ident::identify_modes(spectrum, ro);
  REQUIRE(from_spectrum.modes.size() == 1);
  ident::AxisModes refined = from_spectrum;
  ident::refine_modes_with_motion(refined, s.record, s.motion);
  CHECK(refined.method == "output_error");
  REQUIRE(refined.time_fit.has_value());
  CHECK(std::abs(refined.modes[0].freq_hz - 45.3) < std::abs(from_spectrum.modes[0].freq_hz - 45.3) + 1e-9);
  CHECK(refined.warnings.size() == from_spectrum.warnings.size());
  // The motion on a clock 5 ms off the samples': the fit against it is not believed.
  std::vector<ident::AccelPiece> late = s.motion;
  for (auto& p : late) p.t0_s += 0.005;
  ident::AxisModes kept = from_spectrum;
  ident::refine_modes_with_motion(kept, s.record, late);
  CHECK(kept.method == from_spectrum.method);
  CHECK(kept.modes[0].freq_hz == from_spectrum.modes[0].freq_hz);
  REQUIRE(kept.warnings.size() == from_spectrum.warnings.size() + 1);
  CHECK(kept.warnings.back().find("commanded motion") != std::string::npos);
}
