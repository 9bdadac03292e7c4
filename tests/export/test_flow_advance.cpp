// Flow-dependent advance: the stored-volume design, its band, the single K's range, and the
// Kalico fit re-evaluated with Kalico's own formula (written here from Kalico's source, not
// from tunekit's evaluator).
#include <catch2/catch.hpp>
#include <cmath>

#include "tunekit/core/error.hpp"
#include "tunekit/design/flow_advance.hpp"
#include "tunekit/firmware/config_edit.hpp"

using namespace tunekit;
using Catch::Detail::Approx;

namespace {

// Kalico (KalicoCrew/kalico, bleeding-edge-v2, klippy/chelper/kin_extruder.c):
//   pressure_advance_tanh_model_func:   position += linear_advance * pa_velocity;
//                                        if (nonlinear_offset) position += nonlinear_offset * tanh(pa_velocity /
//                                        linearization_velocity)
//   pressure_advance_recipr_model_func: ... nonlinear_offset * (1. - 1. / (1. + pa_velocity / linearization_velocity))
double kalico_reference(const std::string& model, double la, double off, double lv, double v) {
  double pos = la * v;
  if (off) {
    const double rel = v / lv;
    pos += model == "tanh" ? off * std::tanh(rel) : off * (1. - 1. / (1. + rel));
  }
  return pos;
}

/// The values as the export writes them (6 decimals, Kalico's own %.6f precision).
double written(double v) { return std::stod(firmware::format_number(v, 6)); }

design::FlowAdvanceInputs power_law_levels(double a, double b, bool with_ci) {
  design::FlowAdvanceInputs in;
  in.filament_area_mm2 = M_PI * 0.875 * 0.875;
  for (double q : {2.0, 4.0, 6.5, 9.0, 13.0, 18.0}) {
    design::FlowTau l;
    l.flow_mm3_s = q;
    l.tau_s = a * std::pow(q, b);
    if (with_ci) {
      l.tau_lo_s = 0.9 * l.tau_s;
      l.tau_hi_s = 1.1 * l.tau_s;
    }
    in.levels.push_back(l);
  }
  in.trend = design::TauPowerLaw{a, b};
  return in;
}

/// A power law's stored volume up to q >= q0 with the part below the lowest level q0 taken as tau
/// held at q0 (`below` = "held"), the power law to zero flow ("power") or the middle of the two
/// ("middle", the estimate: the value whose largest error over that range is smallest).
double trend_volume(double a, double b, double q0, double q, const std::string& below) {
  const double held = a * std::pow(q0, b) * q0, power = a * std::pow(q0, b + 1) / (b + 1);
  const double low = below == "held" ? held : below == "power" ? power : 0.5 * (held + power);
  return low + a * (std::pow(q, b + 1) - std::pow(q0, b + 1)) / (b + 1);
}

}  // namespace

TEST_CASE("flow advance: a constant tau needs K = tau at every flow") {
  design::FlowAdvanceInputs in;
  in.filament_area_mm2 = 2.405;
  in.levels = {{2.0, 0.05}, {8.0, 0.05}, {15.0, 0.05}};
  in.design_flow_mm3_s = 6;
  const auto d = design::design_flow_advance(in);
  CHECK(d.k_design_s == Approx(0.05).epsilon(1e-12));
  for (const auto& s : d.curve) CHECK(s.k_need_s == Approx(0.05).epsilon(1e-12));
  CHECK(d.k_within_lo_mm3_s == Approx(2.0));
  CHECK(d.k_within_hi_mm3_s == Approx(15.0));
  CHECK(d.kalico.max_rel_error < 1e-6);
}

TEST_CASE("flow advance: the need is the integral of tau over flow, V(Q)/Q") {
  // tau = a Q^b: V = a Q^(b+1)/(b+1), K = a Q^b/(b+1) (larger than tau(Q) when b < 0). Below the
  // lowest level (2 mm^3/s) no level measured tau: the lower bound holds tau at 2 mm^3/s there.
  const double a = 0.09, b = -0.45;
  auto in = power_law_levels(a, b, false);
  for (double q : {3.0, 10.0, 17.0}) {
    CHECK(design::needed_advance_s(in, q) == Approx(trend_volume(a, b, 2.0, q, "middle") / q).epsilon(1e-12));
    CHECK(design::needed_advance_s(in, q, -1) == Approx(trend_volume(a, b, 2.0, q, "held") / q).epsilon(1e-12));
    CHECK(design::needed_advance_s(in, q, +1) == Approx(trend_volume(a, b, 2.0, q, "power") / q).epsilon(1e-12));
  }
  CHECK(design::stored_volume_mm3(in, 1.0, -1) == Approx(a * std::pow(2.0, b) * 1.0).epsilon(1e-12));
  // The design says how much of the stored melt lies below the data, and its bounds span both.
  in.design_flow_mm3_s = 10;
  const auto d = design::design_flow_advance(in);
  CHECK(d.low_flow_share == Approx(trend_volume(a, b, 2.0, 2.0, "middle") / trend_volume(a, b, 2.0, 10.0, "middle")));
  CHECK(d.k_design_lo_s == Approx(trend_volume(a, b, 2.0, 10.0, "held") / 10.0));
  CHECK(d.k_design_hi_s == Approx(trend_volume(a, b, 2.0, 10.0, "power") / 10.0));
  CHECK(d.k_design_s == Approx(0.5 * (d.k_design_lo_s + d.k_design_hi_s)));
  // The piecewise-linear table (no trend): tau held below the first level, exact trapezoids.
  in.trend.reset();
  const double t0 = a * std::pow(2.0, b), t1 = a * std::pow(4.0, b);
  CHECK(design::stored_volume_mm3(in, 1.5) == Approx(t0 * 1.5));
  CHECK(design::stored_volume_mm3(in, 4.0) == Approx(t0 * 2.0 + 0.5 * (t0 + t1) * 2.0));
  CHECK_THROWS_AS(design::needed_advance_s(in, 0.0), InputError);
}

TEST_CASE("flow advance: the single K holds within 10 % over a stated range around the design flow") {
  // A level at a very low flow leaves almost nothing below the data (0.7 % of the volume at
  // 8 mm^3/s), so K(Q) is the power law's c Q^b to within 0.2 %.
  auto in = power_law_levels(0.09, -0.45, false);
  in.levels.insert(in.levels.begin(), design::FlowTau{0.001, 0.09 * std::pow(0.001, -0.45)});
  in.design_flow_mm3_s = 8;
  const auto d = design::design_flow_advance(in);
  REQUIRE(std::isfinite(d.k_within_lo_mm3_s));
  CHECK(d.k_within_lo_mm3_s < 8);
  CHECK(d.k_within_hi_mm3_s > 8);
  // K(Q) = c Q^b (b < 0): below Qd, K(Q) - K(Qd) = 0.1 K(Q) at Q = Qd 0.9^(-1/b); above,
  // K(Qd) - K(Q) = 0.1 K(Q) at Q = Qd 1.1^(-1/b).
  const double b = -0.45;
  CHECK(d.k_within_lo_mm3_s == Approx(8 * std::pow(0.9, -1 / b)).epsilon(0.01));
  CHECK(d.k_within_hi_mm3_s == Approx(std::min(18.0, 8 * std::pow(1.1, -1 / b))).epsilon(0.01));
}

TEST_CASE(
    "flow advance: Kalico parameters re-evaluated with Kalico's formula reproduce the designed advance within 5 %") {
  for (double b : {-0.2, -0.45, -0.7}) {
    auto in = power_law_levels(0.08, b, true);
    in.theta_s = 0.03;
    const auto d = design::design_flow_advance(in);
    const auto& k = d.kalico;
    const std::string model = design::to_string(k.model);
    REQUIRE((model == "tanh" || model == "recipr"));
    CHECK(k.linear_advance_s >= 0);
    CHECK(k.nonlinear_offset_mm >= 0);
    CHECK(k.linearization_velocity_mm_s > 0);
    CHECK(d.kalico_time_offset_s == Approx(0.03));
    const double la = written(k.linear_advance_s), off = written(k.nonlinear_offset_mm),
                 lv = written(k.linearization_velocity_mm_s);
    double worst = 0;
    for (int i = 0; i <= 200; ++i) {
      const double q = 2.0 + (18.0 - 2.0) * i / 200.0;
      const double v = q / in.filament_area_mm2;
      const double need_mm = design::stored_volume_mm3(in, q) / in.filament_area_mm2;
      worst = std::max(worst, std::abs(kalico_reference(model, la, off, lv, v) - need_mm) / need_mm);
    }
    INFO("b = " << b << ", model " << model << ", worst relative error " << worst);
    CHECK(worst < 0.05);
    // The chosen model is the better one.
    CHECK(d.kalico.max_rel_error <= d.kalico_other.max_rel_error);
  }
}

TEST_CASE("flow advance: the 95 % band brackets the need and the Orca table is the need at each level") {
  auto in = power_law_levels(0.08, -0.4, true);
  in.orca_accels_mm_s2 = {10000, 3000};
  const auto d = design::design_flow_advance(in);
  REQUIRE(d.has_band);
  for (const auto& s : d.curve) {
    CHECK(s.k_lo_s <= s.k_need_s);
    CHECK(s.k_hi_s >= s.k_need_s);
    // The levels' 10 % intervals scale the bounds of the melt below the data (held / power law).
    const double q = s.flow_mm3_s;
    CHECK(s.k_lo_s == Approx(0.9 * trend_volume(0.08, -0.4, 2.0, q, "held") / q));
    CHECK(s.k_hi_s == Approx(1.1 * trend_volume(0.08, -0.4, 2.0, q, "power") / q));
  }
  CHECK(d.band_from_levels);
  REQUIRE(d.orca.size() == 12);
  for (std::size_t i = 1; i < d.orca.size(); ++i) {
    CHECK(d.orca[i].flow_mm3_s >= d.orca[i - 1].flow_mm3_s);
    if (d.orca[i].flow_mm3_s == d.orca[i - 1].flow_mm3_s) CHECK(d.orca[i].accel_mm_s2 > d.orca[i - 1].accel_mm_s2);
  }
  CHECK(d.orca.front().k_s == Approx(design::needed_advance_s(in, 2.0)));
}

TEST_CASE("flow advance: bad levels are refused") {
  design::FlowAdvanceInputs in;
  in.filament_area_mm2 = 2.4;
  in.levels = {{2.0, 0.05}};
  CHECK_THROWS_AS(design::design_flow_advance(in), InputError);
  in.levels = {{2.0, 0.05}, {2.0, 0.04}};
  CHECK_THROWS_AS(design::design_flow_advance(in), InputError);
  in.levels = {{2.0, 0.05}, {4.0, -0.04}};
  CHECK_THROWS_AS(design::design_flow_advance(in), InputError);
  in.levels = {{2.0, 0.05, 0.06, 0.07}, {4.0, 0.04}};
  CHECK_THROWS_AS(design::design_flow_advance(in), InputError);
}

TEST_CASE("flow advance: a trend steeper than 1/Q is set aside and the levels design, with the reason") {
  design::FlowAdvanceInputs in;
  in.filament_area_mm2 = 2.4;
  in.levels = {{2.0, 0.05}, {4.0, 0.04}};
  in.design_flow_mm3_s = 3.0;
  const double from_levels = design::design_flow_advance(in).k_design_s;
  in.trend = design::TauPowerLaw{0.1, -1.2};
  const auto d = design::design_flow_advance(in);
  CHECK(d.k_design_s == Approx(from_levels));
  bool reason = false;
  for (const auto& w : d.warnings) reason = reason || w.find("designed from the measured levels") != std::string::npos;
  CHECK(reason);
}

TEST_CASE("flow advance: a measured volume at the first level replaces the bounds below the data") {
  // tau = 0.08 Q^-0.5 above 2 mm^3/s; the volume at 2 mm^3/s measured as 0.3 mm^3 +- 0.01 (a melt
  // Newtonian below the data stores less than the power law's 0.08 * 2 * sqrt(2) = 0.453 mm^3).
  auto in = power_law_levels(0.08, -0.5, false);
  in.low_volume = design::MeasuredVolume{2.0, 0.3, 0.01};
  in.trend_rel_half_width = 0.02;
  in.design_flow_mm3_s = 8;
  const auto d = design::design_flow_advance(in);
  const double above = 0.08 * 2 * (std::sqrt(8.0) - std::sqrt(2.0));
  CHECK(d.k_design_s == Approx((0.3 + above) / 8).epsilon(1e-12));
  // Without the trend's covariance its integral is widened by its widest relative half-width; the
  // two half-widths add in quadrature.
  const double hw = std::hypot(0.01, 0.02 * above) / 8;
  CHECK(d.band_is_interval);
  CHECK(d.k_design_lo_s == Approx(d.k_design_s - hw).epsilon(1e-12));
  CHECK(d.k_design_hi_s == Approx(d.k_design_s + hw).epsilon(1e-12));
  CHECK(d.low_flow_share == Approx(0.3 / (0.3 + above)).epsilon(1e-9));

  // With the covariance: the delta method. A tau_ref known to 1 % and b exact scales the integral:
  // its standard error is 1 % of it.
  in.trend_covariance = design::FlowAdvanceInputs::TrendCovariance{4.0, 1e-4, 0.0, 0.0};
  const auto c = design::design_flow_advance(in);
  const double hw_c = std::hypot(0.01, 1.959963984540054 * 0.01 * above) / 8;
  CHECK(c.k_design_hi_s - c.k_design_s == Approx(hw_c).epsilon(1e-9));

  // A non-positive measured volume is an input error.
  in.low_volume->volume_mm3 = 0;
  CHECK_THROWS_AS(design::design_flow_advance(in), InputError);
}

TEST_CASE("flow advance: a sensor that reads the stored volume needs no bound below the data") {
  auto in = power_law_levels(0.08, -0.5, false);
  in.volume_measured = true;
  in.volume_rel_half_width = 0.03;
  in.design_flow_mm3_s = 8;
  const auto d = design::design_flow_advance(in);
  const double v = 0.08 * std::pow(8.0, 0.5) / 0.5;
  CHECK(d.k_design_s == Approx(v / 8).epsilon(1e-12));
  CHECK(d.band_is_interval);
  CHECK(d.k_design_lo_s == Approx(0.97 * v / 8).epsilon(1e-12));
  CHECK(d.k_design_hi_s == Approx(1.03 * v / 8).epsilon(1e-12));
  // b uncertain: dV/db = V (ln(Q / Q_ref) - 1 / (b + 1)); at Q = Q_ref that is -2 V for b = -0.5.
  in.trend_covariance = design::FlowAdvanceInputs::TrendCovariance{8.0, 0.0, 0.0, 0.01 * 0.01};
  const auto c = design::design_flow_advance(in);
  CHECK(c.k_design_hi_s - c.k_design_s == Approx(1.959963984540054 * 2 * 0.01 * v / 8).epsilon(1e-9));
}
