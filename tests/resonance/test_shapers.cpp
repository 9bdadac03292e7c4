// Input shapers against their closed-form textbook definitions (Singer & Seering 1990;
// Singhose, Seering & Singer 1994/1997) and the defining residual-vibration properties.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>

#include "tunekit/design/input_shaper.hpp"

using namespace tunekit::design;

namespace {
constexpr double kPi = std::numbers::pi;
double K(double z) { return std::exp(-z * kPi / std::sqrt(1 - z * z)); }
double half_damped_period(double f, double z) { return 0.5 / (f * std::sqrt(1 - z * z)); }

void require_sequence(const Shaper& s, const std::vector<double>& a, const std::vector<double>& t, double tol) {
  REQUIRE(s.amplitudes.size() == a.size());
  REQUIRE(s.times_s.size() == t.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    INFO("impulse " << i);
    CHECK(s.amplitudes[i] == Approx(a[i]).margin(tol));
    CHECK(s.times_s[i] == Approx(t[i]).margin(tol * t.back()));
  }
}
}  // namespace

TEST_CASE("ZV and ZVD impulses equal the closed forms at damping 0 and 0.1", "[shaper]") {
  const double f = 47.5;
  for (double z : {0.0, 0.1}) {
    INFO("zeta " << z);
    const double k = K(z), h = half_damped_period(f, z);
    require_sequence(design_shaper(ShaperType::zv, f, z), {1 / (1 + k), k / (1 + k)}, {0, h}, 1e-12);
    const double d = (1 + k) * (1 + k);
    require_sequence(design_shaper(ShaperType::zvd, f, z), {1 / d, 2 * k / d, k * k / d}, {0, h, 2 * h}, 1e-12);
    const double d3 = d * (1 + k);
    require_sequence(design_shaper(ShaperType::zvdd, f, z), {1 / d3, 3 * k / d3, 3 * k * k / d3, k * k * k / d3},
                     {0, h, 2 * h, 3 * h}, 1e-12);
  }
}

TEST_CASE("EI impulses equal Singhose's closed form at damping 0 and 0.1", "[shaper]") {
  const double f = 40, V = 0.05;
  for (double z : {0.0, 0.1}) {
    INFO("zeta " << z);
    // Undamped: [(1+V)/4, (1-V)/2, (1+V)/4] at 0, T/2, T; with damping impulse i is scaled by K^i.
    const double k = K(z), h = half_damped_period(f, z);
    const double a1 = (1 + V) / 4, a2 = (1 - V) / 2 * k, a3 = (1 + V) / 4 * k * k, sum = a1 + a2 + a3;
    require_sequence(design_shaper(ShaperType::ei, f, z), {a1 / sum, a2 / sum, a3 / sum}, {0, h, 2 * h}, 1e-12);
  }
}

TEST_CASE("2-hump and 3-hump EI at zero damping match Singhose's closed forms", "[shaper]") {
  const double f = 50, V = 0.05;  // independent of the damped scaling checked above for EI
  const double X = std::cbrt(V * V * (std::sqrt(1 - V * V) + 1));
  const double a1 = (3 * X * X + 2 * X + 3 * V * V) / (16 * X);
  require_sequence(design_shaper(ShaperType::two_hump_ei, f, 0.0), {a1, 0.5 - a1, 0.5 - a1, a1},
                   {0, 0.5 / f, 1 / f, 1.5 / f}, 1e-12);
  const double b1 = (1 + 3 * V + 2 * std::sqrt(2 * (V + 1) * V)) / 16;
  const double b2 = (1 - V) / 4;
  require_sequence(design_shaper(ShaperType::three_hump_ei, f, 0.0), {b1, b2, 1 - 2 * (b1 + b2), b2, b1},
                   {0, 0.5 / f, 1 / f, 1.5 / f, 2 / f}, 1e-12);
}

TEST_CASE("every shaper leaves under 5 % vibration at its design frequency (EI family: at most its tolerance)",
          "[shaper]") {
  for (ShaperType t : all_shaper_types())
    for (double z : {0.0, 0.05, 0.1}) {
      const auto s = design_shaper(t, 60.0, z);
      const double v = residual_vibration(s, 60.0, z);
      INFO(to_string(t) << " zeta " << z << " V " << v);
      const bool ei_family = t == ShaperType::ei || t == ShaperType::two_hump_ei || t == ShaperType::three_hump_ei;
      if (!ei_family) CHECK(v < 0.05);
      if (t == ShaperType::zv || t == ShaperType::zvd || t == ShaperType::zvdd) CHECK(v < 1e-9);
      if (ei_family) CHECK(v <= kDefaultVibrationTolerance + 1e-12);
      double sum = 0;
      for (double a : s.amplitudes) {
        CHECK(a > 0);
        sum += a;
      }
      CHECK(sum == Approx(1.0));
      // Far below the design frequency it is not suppressed (the shaped move is nearly a step).
      CHECK(residual_vibration(s, 0.25 * 60.0, z) > 0.5);
    }
}

TEST_CASE("EI is insensitive: within +-10 % of the design frequency vibration stays near the tolerance", "[shaper]") {
  for (double z : {0.0, 0.1}) {
    const auto ei = design_shaper(ShaperType::ei, 50.0, z);
    const auto zv = design_shaper(ShaperType::zv, 50.0, z);
    for (double r = 0.9; r <= 1.1001; r += 0.02) {
      INFO("zeta " << z << " ratio " << r);
      CHECK(residual_vibration(ei, 50.0 * r, z) <= 0.06);
    }
    // ZV is far more sensitive to a frequency error.
    CHECK(residual_vibration(zv, 50.0 * 0.8, z) > residual_vibration(ei, 50.0 * 0.8, z));
  }
}

TEST_CASE("residual vibration curve on a uniform grid equals the direct formula", "[shaper]") {
  const auto s = design_shaper(ShaperType::three_hump_ei, 55.0, 0.07);
  std::vector<double> f;
  for (int i = 0; i < 300; ++i) f.push_back(0.78125 * i);
  const auto curve = residual_vibration_curve(s, f, 0.12);
  for (std::size_t i = 0; i < f.size(); i += 7)
    CHECK(curve[i] == Approx(residual_vibration(s, f[i], 0.12)).margin(1e-10));
}

TEST_CASE("smoothing of ZV has the closed form and max_accel reaches the target smoothing", "[shaper]") {
  const double f = 40, a = 5000, scv = 5;
  const auto zv = design_shaper(ShaperType::zv, f, 0.0);
  // A = [1/2, 1/2], T = [0, 1/(2f)], centroid 1/(4f).
  const double d = 1 / (4 * f);
  const double s90 = std::sqrt(2.0) * 0.5 * (scv + a / 2 * d) * d;
  const double s180 = a / 2 * d * d;
  CHECK(shaper_smoothing(zv, a, scv) == Approx(std::max(s90, s180)));
  for (ShaperType t : all_shaper_types()) {
    const auto s = design_shaper(t, 45.0, 0.1);
    const double amax = shaper_max_accel(s, scv, 0.12);
    INFO(to_string(t));
    CHECK(amax > 0);
    CHECK(shaper_smoothing(s, amax, scv) == Approx(0.12).epsilon(1e-9));
    CHECK(shaper_smoothing(s, amax * 1.01, scv) > 0.12);
  }
  // Longer shapers smooth more, so they allow less acceleration.
  CHECK(shaper_max_accel(design_shaper(ShaperType::zv, 45, 0.1)) >
        shaper_max_accel(design_shaper(ShaperType::three_hump_ei, 45, 0.1)));
}

TEST_CASE("automatic selection puts the shaper near a single resonance", "[shaper]") {
  // A resonance at 52 Hz, zeta 0.05, in a Klipper-like normalized PSD on 1.5625 Hz bins.
  std::vector<double> f, psd;
  for (int b = 0; b < 130; ++b) {
    const double x = 1.5625 * b, r = x / 52.0;
    f.push_back(x);
    psd.push_back(1e4 / ((1 - r * r) * (1 - r * r) + (0.1 * r) * (0.1 * r)) + 10);
  }
  ShaperSelectionOptions o;
  const auto sel = select_shaper(f, psd, o);
  REQUIRE(sel.candidates.size() == 5);
  for (const auto& c : sel.candidates) {
    INFO(to_string(c.type) << " " << c.freq_hz << " Hz, v " << c.vibrations << " smoothing " << c.smoothing_mm);
    CHECK(c.vibrations < 0.2);
    CHECK(c.smoothing_mm > 0);
    CHECK(c.max_accel_mm_s2 > 0);
    CHECK(c.score == Approx(c.smoothing_mm * (std::pow(c.vibrations, 1.5) + 0.2 * c.vibrations + 0.01)));
    // The selection's fast evaluation equals the plain definition, pessimized over the test ratios.
    const auto sh = design_shaper(c.type, c.freq_hz, c.damping_ratio, kDefaultVibrationTolerance, o.ei_design);
    double worst = 0;
    for (double z : o.test_damping_ratios) worst = std::max(worst, remaining_vibrations(sh, f, psd, z));
    CHECK(c.vibrations == Approx(worst).margin(1e-9));
  }
  INFO(to_string(sel.recommended.type) << " " << sel.recommended.freq_hz);
  CHECK(sel.recommended.vibrations < 0.1);
  CHECK(sel.recommended.freq_hz > 35);
  CHECK(sel.recommended.freq_hz < 80);
  CHECK(sel.recommended.damping_ratio == 0.1);
}

TEST_CASE("Singhose's damped EI fits stay within the tolerance over +-20 % of the frequency at their damping",
          "[shaper]") {
  for (ShaperType t : {ShaperType::ei, ShaperType::two_hump_ei, ShaperType::three_hump_ei})
    for (double z : {0.0, 0.05, 0.1, 0.15}) {
      const auto s = design_shaper(t, 60.0, z, kDefaultVibrationTolerance, EiDesign::damped_fit);
      double sum = 0;
      for (double a : s.amplitudes) {
        CHECK(a > 0);
        sum += a;
      }
      CHECK(sum == Approx(1.0));
      CHECK(s.times_s.front() == 0.0);
      for (double r = 0.8; r <= 1.2001; r += 0.01) {
        INFO(to_string(t) << " zeta " << z << " ratio " << r);
        CHECK(residual_vibration(s, 60.0 * r, z) <= 0.055);
      }
      // Far below the design frequency it is not suppressed.
      CHECK(residual_vibration(s, 15.0, z) > 0.3);
    }
  // At zero damping the fits are close to the closed forms they were fitted to (amplitudes to
  // 2e-3, times to 0.3 % of a period).
  for (ShaperType t : {ShaperType::ei, ShaperType::two_hump_ei, ShaperType::three_hump_ei}) {
    const auto fit = design_shaper(t, 50.0, 0.0, kDefaultVibrationTolerance, EiDesign::damped_fit);
    const auto closed = design_shaper(t, 50.0, 0.0);
    REQUIRE(fit.amplitudes.size() == closed.amplitudes.size());
    for (std::size_t i = 0; i < fit.amplitudes.size(); ++i) {
      INFO(to_string(t) << " impulse " << i);
      CHECK(fit.amplitudes[i] == Approx(closed.amplitudes[i]).margin(2e-3));
      CHECK(fit.times_s[i] == Approx(closed.times_s[i]).margin(3e-3 / 50.0));
    }
  }
  // The 2-hump and 3-hump fits exist for V = 5 % only.
  CHECK_THROWS(design_shaper(ShaperType::two_hump_ei, 50.0, 0.1, 0.1, EiDesign::damped_fit));
}

TEST_CASE("shaper vibrations against several spectra are the worst over them", "[shaper]") {
  std::vector<double> f, p1, p2;
  for (int b = 0; b < 128; ++b) {
    const double x = 1.5625 * b, r1 = x / 45.0, r2 = x / 70.0;
    f.push_back(x);
    p1.push_back(1e4 / ((1 - r1 * r1) * (1 - r1 * r1) + (0.1 * r1) * (0.1 * r1)) + 10);
    p2.push_back(1e4 / ((1 - r2 * r2) * (1 - r2 * r2) + (0.1 * r2) * (0.1 * r2)) + 10);
  }
  ShaperSelectionOptions o;
  o.types = {ShaperType::mzv};
  const std::vector<PsdDataset> both = {{f, p1}, {f, p2}};
  const auto sel = select_shaper(both, o);
  const auto& c = sel.recommended;
  const auto sh = design_shaper(c.type, c.freq_hz, c.damping_ratio, kDefaultVibrationTolerance, o.ei_design);
  double worst = 0;
  for (const auto* p : {&p1, &p2})
    for (double z : o.test_damping_ratios) worst = std::max(worst, remaining_vibrations(sh, f, *p, z));
  CHECK(c.vibrations == Approx(worst).margin(1e-9));
  // A shaper for one resonance alone is tuned differently from one that must cover both.
  const auto alone = select_shaper(f, p1, o).recommended;
  CHECK(std::abs(alone.freq_hz - c.freq_hz) > 1.0);
}

TEST_CASE("shaper names parse as Klipper spells them", "[shaper]") {
  for (ShaperType t : all_shaper_types()) CHECK(parse_shaper_type(to_string(t)) == t);
  CHECK(to_string(ShaperType::two_hump_ei) == "2hump_ei");
  CHECK_THROWS(parse_shaper_type("zvx"));
  CHECK_THROWS(design_shaper(ShaperType::zv, 0.0, 0.1));
  CHECK_THROWS(design_shaper(ShaperType::zv, 40.0, 1.0));
}
