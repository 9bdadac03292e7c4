// Protocol defaults from the machine at hand (protocols/src/machine_defaults.cpp): on the limits a
// stock printer ships with (Klipper's example configurations: max_accel 3000 mm/s^2, the
// extrude-only acceleration Klipper computes from it, 798.1 mm/s^2 for a 0.4 mm nozzle and 1.75
// mm filament; a Prusa MINI+'s 332.6 mm/s^2), every protocol's default experiment passes the gate
// on every firmware, the sweep never asks for more than the axis' limit, and the values written are
// never above what was checked.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <string>

#include "tunekit/core/error.hpp"
#include "tunekit/firmware/dialect.hpp"
#include "tunekit/machine/gcode.hpp"
#include "tunekit/protocols/experiments.hpp"
#include "tunekit/protocols/runner.hpp"
#include "tunekit/protocols/safety.hpp"
#include "tunekit/sim/builtin_profile.hpp"

using namespace tunekit::protocols;
using tunekit::firmware::Dialect;
using tunekit::firmware::Firmware;
using tunekit::machine::MachineProfile;

namespace {

/// The built-in printer with a stock Klipper printer's limits (generic-ramps.cfg's max_accel and
/// max_velocity, Klipper's extrude-only defaults, a hot end melting 8 mm^3/s).
MachineProfile stock_profile(double max_accel, double extruder_accel) {
  MachineProfile p = tunekit::sim::builtin_sim_profile();
  for (const char* a : {"x", "y"}) {
    p.axes[a].max_accel_mm_s2 = max_accel;
    p.axes[a].max_velocity_mm_s = 300;
  }
  p.extruder.max_accel_mm_s2 = extruder_accel;
  p.extruder.max_velocity_mm_s = 300 * 4 * 0.4 * 0.4 / p.filament_area_mm2();
  p.extruder.max_flow_mm3_s = 8;
  p.print.max_accel_mm_s2 = max_accel;
  p.state.max_accel_xy_mm_s2 = max_accel;
  p.state.retract_accel_mm_s2 = extruder_accel;
  p.state.max_accel_e_mm_s2 = extruder_accel;
  p.state.steps_per_mm_x = p.state.steps_per_mm_y = 80;
  return p;
}

/// The protocol's violations of the profile, as one string ("" when it passes).
std::string violations(const Experiment& e, const MachineProfile& p) {
  std::string all;
  for (const auto& v : check_protocol(e.gcode, p, e.sensors, ProtocolLimits{}))
    all += std::to_string(v.line) + " '" + v.gcode + "': " + v.what + "; ";
  return all;
}

}  // namespace

TEST_CASE("every protocol's default experiment passes the gate on a stock printer's limits, on every firmware",
          "[machine]") {
  const double extruder = GENERATE(798.1, 332.601);
  const auto profile = stock_profile(extruder > 500 ? 3000 : 1250, extruder);
  for (const auto fw : {Firmware::klipper, Firmware::marlin, Firmware::reprapfirmware}) {
    for (const auto& spec : protocol_specs()) {
      for (const std::string axis : {"x", "y"}) {
        if (!spec.uses_axis && axis == "y") continue;
        INFO(spec.name << " " << axis << " on " << to_string(fw) << ", extruder " << extruder << " mm/s^2");
        Experiment e;
        REQUIRE_NOTHROW(e = build_experiment(spec.name, {}, axis, profile, Dialect(fw)));
        CHECK(violations(e, profile).empty());
        CHECK(e.estimated_duration_s > 0);
      }
    }
  }
}

TEST_CASE("the sweep keeps within the axis' limit: accel_per_hz lowered by default, or held at the limit",
          "[machine]") {
  const auto profile = stock_profile(3000, 798.1);
  const auto e = build_experiment("axis-sweep", {}, "x", profile, Dialect(Firmware::klipper));
  // Klipper's 60 mm/s^2/Hz would ask 6000 mm/s^2 at 100 Hz; with its 400 mm/s^2 sweeping motion
  // the pulses have 2600 mm/s^2, reached at the sweep's end.
  CHECK(e.params.at("accel_per_hz") == Approx(26.0));
  CHECK(e.excitation.at("machine_defaults").at("accel_per_hz").get<std::string>().find("lowered") != std::string::npos);
  CHECK(e.excitation.at("peak_accel_mm_s2").get<double>() <= 3000 + 1e-9);
  // Klipper's own accel_per_hz asked for: held at 2600 mm/s^2 above 43.3 Hz, never above the limit.
  const auto held = build_experiment("axis-sweep", {{"accel_per_hz", 60}}, "x", profile, Dialect(Firmware::klipper));
  CHECK(held.excitation.at("accel_held_above_hz").get<double>() == Approx(2600.0 / 60));
  CHECK(held.excitation.at("peak_accel_mm_s2").get<double>() <= 3000 + 1e-9);
  CHECK(violations(held, profile).empty());
}

TEST_CASE("Marlin's sweep ends where MIN_STEPS_PER_SEGMENT meets the axis' limit, and says so", "[machine]") {
  const auto profile = stock_profile(3000, 798.1);
  const auto e = build_experiment("axis-sweep", {}, "x", profile, Dialect(Firmware::marlin));
  // 6 steps at 80 steps/mm is 0.075 mm; a half period covers a / (16 f^2) >= 1.5 x 0.075 mm
  // up to sqrt(3000 / (24 x 0.075)) = 40.8 Hz.
  CHECK(e.params.at("freq_end_hz") == 40);
  const std::string why = e.excitation.at("machine_defaults").at("freq_end_hz");
  CHECK(why.find("MIN_STEPS_PER_SEGMENT") != std::string::npos);
  CHECK(why.find("80 steps/mm") != std::string::npos);
  // Asked explicitly for 100 Hz, the refusal names the limit that binds, with its real numbers.
  try {
    build_experiment("axis-sweep", {{"freq_end_hz", 100}}, "x", profile, Dialect(Firmware::marlin));
    FAIL("a sweep to 100 Hz at 80 steps/mm and 3000 mm/s^2 was built on Marlin");
  } catch (const tunekit::InputError& err) {
    const std::string m = err.message();
    CHECK(m.find("MIN_STEPS_PER_SEGMENT") != std::string::npos);
    CHECK(m.find("0.075 mm") != std::string::npos);
  }
  // Klipper has no such rule: its sweep goes to 100 Hz on the same machine.
  CHECK(build_experiment("axis-sweep", {}, "x", profile, Dialect(Firmware::klipper)).params.at("freq_end_hz") == 100);
}

TEST_CASE("accelerations are written rounded down: an extrude-only limit of 332.601 is sent as 332", "[machine]") {
  const auto profile = stock_profile(1250, 332.601);
  for (const auto fw : {Firmware::klipper, Firmware::marlin, Firmware::reprapfirmware}) {
    INFO(to_string(fw));
    const auto e = build_experiment("liquefier-flow-sweep", {}, "", profile, Dialect(fw));
    CHECK(e.params.at("accel_mm_s2") == Approx(332.601));
    const std::string set = fw == Firmware::klipper  ? "SET_VELOCITY_LIMIT ACCEL=332"
                            : fw == Firmware::marlin ? "M204 R332"
                                                     : "M201 E332";
    CHECK(std::find(e.gcode.begin(), e.gcode.end(), set) != e.gcode.end());
    CHECK(violations(e, profile).empty());
  }
}

TEST_CASE("the chirp's staircase step is one the extruder keeps, and its feeds stay within the hot end", "[machine]") {
  const auto profile = stock_profile(1250, 332.601);
  const auto e =
      build_experiment("liquefier-chirp", {{"expected_tau_s", 0.03}}, "", profile, Dialect(Firmware::klipper));
  const double top = e.params.at("feed_mean_mm_s") + e.params.at("amplitude_mm_s");
  // The raised speed of a step stays within 25 % of its feed: t >= 1.25^2 v / (0.25 a).
  CHECK(e.params.at("segment_s") >= 1.5625 * top / (0.25 * 332) - 1e-12);
  CHECK(top * 1.25 * profile.filament_area_mm2() <= profile.extruder.max_flow_mm3_s);
  CHECK(violations(e, profile).empty());
  // A step shorter than the extruder keeps, asked for, is refused with the acceleration it needs.
  CHECK_THROWS_WITH(build_experiment("liquefier-chirp", {{"segment_s", 0.01}}, "", profile, Dialect(Firmware::klipper)),
                    Catch::Contains("mm/s^2"));
}
