// Protocols run as labelled on each firmware's planner. The simulator follows the planner rules
// of the firmware it is told to be (SimConfig::firmware), written from the firmwares' source:
//   Klipper klippy/toolhead.py: Move.calc_junction returns early unless both moves are
//     kinematic (extrude-only moves stop at both ends); flush(): a move's peak speed squared is
//     at most a L (1 - minimum_cruise_ratio) (mcr_pseudo_accel, default ratio 0.5, toolhead.py:211);
//     klippy/kinematics/extruder.py:216-221 refuses extrude-only moves longer than
//     max_extrude_only_distance (50 mm) and caps their acceleration by max_extrude_only_accel.
//   Marlin planner.cpp: blocks with fewer than MIN_STEPS_PER_SEGMENT (Configuration_adv.h: 6)
//     steps are joined with the next; blocks shorter than DEFAULT_MINSEGMENTTIME (M205 B, 20000 us)
//     are slowed; M204 is capped by M201 (Configuration.h DEFAULT_MAX_ACCELERATION 3000).
//   RepRapFirmware src/Movement/DDA.cpp MatchSpeeds: a reversal is joined at M566/2.
// Each test also shows that a protocol ignoring the rule is caught (its timing is off).
#include <catch2/catch.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <string>
#include <vector>

#include "test_support.hpp"
#include "tunekit/calibration/analyses/simulated_machine.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/firmware/dialect.hpp"
#include "tunekit/protocols/experiments.hpp"
#include "tunekit/machine/gcode.hpp"
#include "tunekit/protocols/runner.hpp"
#include "tunekit/sim/builtin_profile.hpp"
#include "tunekit/sim/simulator.hpp"

using tunekit::InputError;
using tunekit::MachineError;
using namespace tunekit::protocols;
using namespace tunekit::machine;
using namespace tunekit::firmware;
using namespace tunekit::sim;

namespace {

struct SimTiming {
  double recorded_s = 0;  ///< machine time between ";@record ... on" and "off"
  std::string output;     ///< everything the simulator answered
};

/// Runs a protocol's G-code on the simulator following `firmware`'s planner.
SimTiming run_on(const std::vector<std::string>& gcode, const std::string& firmware,
                 std::vector<std::string> options = {}) {
  std::string fw_option = "firmware=";
  fw_option += firmware;
  options.push_back(fw_option);
  options.push_back("accel_noise_mm_s2=0");
  Simulator sim(SimConfig::from_options(options));
  SimTiming r;
  const Simulator::Emit emit = [&](std::string_view s) { r.output += s; };
  double t_on = 0;
  for (const auto& l : gcode) {
    if (l.rfind(";@record ", 0) == 0) {
      sim.flush(emit);
      if (l.size() > 3 && l.substr(l.size() - 3) == " on") t_on = sim.time_s();
      else r.recorded_s = sim.time_s() - t_on;
      continue;
    }
    if (l.empty() || l[0] == ';') continue;
    sim.handle_line(l.substr(0, l.find(';')), emit);
  }
  sim.flush(emit);
  return r;
}

Firmware fw_of(const std::string& name) { return firmware_from_name(name); }

/// The sweep's labelled duration: half periods 1/(2f) while f rises at hz_per_sec, plus the
/// two settle dwells.
double labelled_sweep_s(double f0, double f1, double rate, double settle) {
  double t = 0, f = f0;
  while (f < f1) {
    t += 1.0 / (2 * f);
    f = f0 + rate * t;
  }
  return t + 2 * settle;
}

}  // namespace

TEST_CASE("axis-sweep keeps its labelled timing within 1 % on each firmware's planner", "[machine]") {
  const auto profile = builtin_sim_profile();
  const std::map<std::string, double> p{{"freq_start_hz", 10}, {"freq_end_hz", 100}, {"hz_per_sec", 4}};
  const double label = labelled_sweep_s(10, 100, 4, 0.3);
  for (const char* fw : {"klipper", "marlin", "rrf"}) {
    INFO(fw);
    const auto e = build_experiment("axis-sweep", p, "x", profile, Dialect(fw_of(fw)));
    const auto t = run_on(e.gcode, fw);
    CHECK(t.output.find("!!") == std::string::npos);
    CHECK(t.recorded_s == Approx(label).epsilon(0.01));
  }
  SECTION("a sweep that ignores the planner's rules is caught") {
    // Built for Marlin, run by Klipper: minimum_cruise_ratio 0.5 stays on, the sweep runs ~6 % slow.
    const auto marlin = build_experiment("axis-sweep", p, "x", profile, Dialect(Firmware::marlin));
    CHECK(run_on(marlin.gcode, "klipper").recorded_s > 1.04 * label);
    // Built for Klipper, run by Marlin: M201 3000 caps the accelerations, 20 ms minimum segment
    // time, moves under 6 steps joined.
    const auto klipper = build_experiment("axis-sweep", p, "x", profile, Dialect(Firmware::klipper));
    CHECK(std::abs(run_on(klipper.gcode, "marlin").recorded_s / label - 1) > 0.05);
    // Built for Marlin, run by RepRapFirmware: reversals at M566/2 (15 mm/s jerk) shorten moves.
    CHECK(std::abs(run_on(marlin.gcode, "rrf").recorded_s / label - 1) > 0.02);
  }
}

TEST_CASE("Klipper's sweep sets MINIMUM_CRUISE_RATIO=0 and input shaping off, and restores both after", "[machine]") {
  // klippy/extras/resonance_tester.py:194-199 does the same for TEST_RESONANCES.
  auto profile = builtin_sim_profile();
  profile.state.shaper["x"] = "mzv:48.6:0.1";
  profile.state.minimum_cruise_ratio = 0.4;
  const auto e = build_experiment("axis-sweep", {}, "y", profile, Dialect(Firmware::klipper));
  const auto& g = e.gcode;
  auto at = [&](const std::string& l) { return std::find(g.begin(), g.end(), l) - g.begin(); };
  const auto on = at(";@record accelerometer on");
  const auto epi = at(";@epilogue");
  CHECK(at("SET_VELOCITY_LIMIT MINIMUM_CRUISE_RATIO=0") < on);
  CHECK(at("SET_INPUT_SHAPER SHAPER_FREQ_X=0 SHAPER_FREQ_Y=0") < on);
  REQUIRE(epi < static_cast<long>(g.size()));
  CHECK(at("SET_VELOCITY_LIMIT ACCEL=3000 MINIMUM_CRUISE_RATIO=0.4") > epi);
  CHECK(at("SET_INPUT_SHAPER SHAPER_TYPE_X=mzv SHAPER_FREQ_X=48.6 DAMPING_RATIO_X=0.1") > epi);
}

TEST_CASE("Marlin and RepRapFirmware sweeps turn shaping off and restore it, with their planner settings",
          "[machine]") {
  auto profile = builtin_sim_profile();
  profile.state.shaper["x"] = "mzv:48.6:0.1";
  profile.state.shaper["y"] = "mzv:40:0.12";
  SECTION("Marlin: M593 F0 (M593.cpp: without X/Y every axis), M205 B0, M201 raised; all restored") {
    profile.state.shaper["x"] = "zv:48.6:0.1";
    profile.state.shaper["y"] = "zv:40:0.12";
    const auto g = build_experiment("axis-sweep", {}, "x", profile, Dialect(Firmware::marlin)).gcode;
    auto at = [&](const std::string& l) { return std::find(g.begin(), g.end(), l) - g.begin(); };
    const auto on = at(";@record accelerometer on"), epi = at(";@epilogue");
    CHECK(at("M593 F0") < on);
    CHECK(at("M205 B0") < on);
    CHECK(at("M593 X F48.6 D0.1") > epi);
    CHECK(at("M593 Y F40 D0.12") > epi);
    CHECK(at("M205 B20000") > epi);
    CHECK(at("M201 X3000 Y3000") > epi);
    CHECK(at("M201 X3000 Y3000") < static_cast<long>(g.size()));
  }
  SECTION("RepRapFirmware: M593 P\"none\", M566 at its minimum; restored") {
    const auto g = build_experiment("axis-sweep", {}, "x", profile, Dialect(Firmware::reprapfirmware)).gcode;
    auto at = [&](const std::string& l) { return std::find(g.begin(), g.end(), l) - g.begin(); };
    const auto on = at(";@record accelerometer on"), epi = at(";@epilogue");
    CHECK(at("M593 P\"none\"") < on);
    CHECK(at("M566 X6 Y6") < on);
    CHECK(at("M566 X900 Y900") > epi);
    CHECK(at("M593 P\"mzv\" F48.6 S0.1") > epi);
    CHECK(at("M593 P\"mzv\" F48.6 S0.1") < static_cast<long>(g.size()));
  }
}

TEST_CASE("Marlin's sweep is designed above MIN_STEPS_PER_SEGMENT or refused with the reason", "[machine]") {
  auto profile = builtin_sim_profile();
  profile.state.steps_per_mm_x = 80;  // Configuration.h DEFAULT_AXIS_STEPS_PER_UNIT
  const std::map<std::string, double> p{{"freq_end_hz", 100}};
  std::string why;
  try {
    build_experiment("axis-sweep", p, "x", profile, Dialect(Firmware::marlin));
  } catch (const InputError& e) {
    why = e.message();
  }
  CHECK(why.find("MIN_STEPS_PER_SEGMENT") != std::string::npos);
  // Every move of a sweep that is built has at least 6 steps.
  profile.state.steps_per_mm_x = 160;
  const auto e = build_experiment("axis-sweep", p, "x", profile, Dialect(Firmware::marlin));
  GcodeInterpreter in;
  bool on = false;
  for (const auto& l : e.gcode) {
    if (l == ";@record accelerometer on") on = true;
    if (l == ";@record accelerometer off") on = false;
    const auto w = parse_gcode(l);
    if (!w) continue;
    const auto m = in.apply(*w);
    if (on && m) CHECK(std::abs(m->end[0] - m->start[0]) * 160 >= 6);
  }
}

TEST_CASE(
    "liquefier sine and chirp staircases keep their labelled timing on Klipper, which stops each extrude-only move",
    "[machine]") {
  const auto profile = builtin_sim_profile();
  for (double accel : {800.0, 5000.0}) {
    INFO(accel);
    const std::map<std::string, double> chirp{{"duration_s", 10}, {"accel_mm_s2", accel}, {"hotend_c", 0}};
    const double label = 2.0 + 10 + 1.0;  // steady feed, chirp, steady feed
    const auto e = build_experiment("liquefier-chirp", chirp, "", profile, Dialect(Firmware::klipper));
    CHECK(e.excitation.at("extrude_only_moves_stop") == true);
    CHECK(run_on(e.gcode, "klipper").recorded_s == Approx(label).epsilon(0.01));
    // The same staircase built for a firmware that blends extrude-only moves runs slow on Klipper.
    const auto blind = build_experiment("liquefier-chirp", chirp, "", profile, Dialect(Firmware::marlin));
    if (accel < 1000) CHECK(run_on(blind.gcode, "klipper").recorded_s > 1.05 * label);
    // On Marlin and RepRapFirmware consecutive extrude-only moves blend: labelled timing.
    CHECK(run_on(blind.gcode, "marlin").recorded_s == Approx(label).epsilon(0.01));
    const auto rrf = build_experiment("liquefier-chirp", chirp, "", profile, Dialect(Firmware::reprapfirmware));
    CHECK(run_on(rrf.gcode, "rrf").recorded_s == Approx(label).epsilon(0.01));
  }
  const std::map<std::string, double> sine{{"freq_count", 3}, {"periods", 2}, {"accel_mm_s2", 800}, {"hotend_c", 0}};
  const auto e = build_experiment("liquefier-sine", sine, "", profile, Dialect(Firmware::klipper));
  // The band and the staircase step as the machine's defaults made them (at 800 mm/s^2 Klipper's
  // stops take over 10 % of a 20 ms step: 50 ms steps, and a band whose period holds 20 of them).
  const double seg = e.params.at("segment_s"), f0 = e.params.at("freq_min_hz"), f1 = e.params.at("freq_max_hz");
  CHECK(seg == Approx(0.05));
  double label = 2.0 + 1.0;
  for (int i = 0; i < 3; ++i) {
    const double f = f0 * std::pow(f1 / f0, i / 2.0);
    const double dt = std::min(seg, 1.0 / (20 * f));
    label += std::ceil(2 / f / dt) * dt;
  }
  CHECK(run_on(e.gcode, "klipper").recorded_s == Approx(label).epsilon(0.01));
}

TEST_CASE("the liquefier step protocol splits long feeds under max_extrude_only_distance for any hold_s up to 60 s",
          "[machine]") {
  const auto profile = builtin_sim_profile();
  REQUIRE(profile.extruder.max_extrude_only_distance_mm == 50);  // Klipper's default, extruder.py:168-169
  for (double hold : {1.0, 3.0, 17.0, 20.0, 45.0, 60.0}) {
    INFO(hold);
    const auto e = build_experiment("liquefier-step", {{"hold_s", hold}}, "", profile, Dialect(Firmware::klipper));
    GcodeInterpreter in;
    double total = 0;
    for (const auto& l : e.gcode) {
      const auto w = parse_gcode(l);
      if (!w) continue;
      if (const auto m = in.apply(*w)) {
        CHECK(m->length_mm() <= 50 + 1e-9);
        total += m->length_mm();
      }
    }
    CHECK(total == Approx(1.0 * 3 + 2 * (3.0 + 1.0) * hold).epsilon(1e-6));
  }
  // Klipper refuses a longer extrude-only move; the split protocol runs without an error.
  const auto e = build_experiment("liquefier-step", {{"hold_s", 20}, {"cycles", 1}, {"hotend_c", 0}}, "", profile,
                                  Dialect(Firmware::klipper));
  const auto t = run_on(e.gcode, "klipper");
  CHECK(t.output.find("!!") == std::string::npos);
  CHECK(t.recorded_s == Approx(3 + 2 * 20).epsilon(0.01));
  const auto refused = run_on({"M83", "G1 E60 F180"}, "klipper");
  CHECK(refused.output.find("!! Extrude only move too long (60.000mm vs 50.000mm)") != std::string::npos);
}

TEST_CASE("extrude-only moves get the acceleration each firmware applies to them", "[machine]") {
  // Marlin planner.cpp: moves without X/Y/Z steps use retract_acceleration (M204 R); RRF DDA.cpp
  // applies M204 to XY moves only (M201 E limits extruder-only moves); Klipper caps them by
  // SET_VELOCITY_LIMIT ACCEL and max_extrude_only_accel.
  const auto profile = builtin_sim_profile();
  const std::map<std::string, double> p{{"accel_mm_s2", 1500}, {"hotend_c", 0}};
  auto has = [](const Experiment& e, const std::string& l) {
    return std::find(e.gcode.begin(), e.gcode.end(), l) != e.gcode.end();
  };
  const auto m = build_experiment("liquefier-step", p, "", profile, Dialect(Firmware::marlin));
  CHECK(has(m, "M204 R1500"));
  const auto r = build_experiment("liquefier-step", p, "", profile, Dialect(Firmware::reprapfirmware));
  CHECK(has(r, "M201 E1500"));
  const auto k = build_experiment("liquefier-step", p, "", profile, Dialect(Firmware::klipper));
  CHECK(has(k, "SET_VELOCITY_LIMIT ACCEL=1500"));
  CHECK(k.excitation.at("extrude_only_accel_mm_s2") == 1500);
  // The interpreter (and the simulator) applies them to extrude-only moves only.
  GcodeInterpreter in;
  for (const char* l : {"M83", "M204 P500 T700", "M204 R1500"}) in.apply(*parse_gcode(l));
  CHECK(in.apply(*parse_gcode("G1 E5 F300"))->accel_mm_s2 == 1500);
  CHECK(in.apply(*parse_gcode("G1 X5 F3000"))->accel_mm_s2 == 700);
  CHECK(in.apply(*parse_gcode("G1 X10 E1 F3000"))->accel_mm_s2 == 500);
  GcodeInterpreter rrf;
  for (const char* l : {"M83", "M204 P500 T700", "M201 X3000 Y3000 E900"}) rrf.apply(*parse_gcode(l));
  CHECK(rrf.apply(*parse_gcode("G1 E5 F300"))->accel_mm_s2 == 900);
}

TEST_CASE("hot-end waits use M109 R on Marlin and RepRapFirmware, and RRF stops with M112", "[machine]") {
  // Marlin M104_M109.cpp: M109 S waits only when heating, R also when cooling; RRF likewise.
  CHECK(Dialect(Firmware::marlin).set_hotend(210, true) == "M109 R210");
  CHECK(Dialect(Firmware::reprapfirmware).set_hotend(210, true) == "M109 R210");
  CHECK(Dialect(Firmware::klipper).set_hotend(210, true) == "M109 S210");
  // RRF GCodes2.cpp has no case 410 (not an RRF command); M112 is its emergency stop.
  const auto safe = Dialect(Firmware::reprapfirmware).safe_state(true);
  CHECK(safe.front() == "M112");
  CHECK(std::find(safe.begin(), safe.end(), "M410") == safe.end());
  CHECK(run_on({"M410"}, "rrf").output.find("not supported") != std::string::npos);
}

TEST_CASE("the rectangle test runs without input shaping and restores it", "[machine]") {
  auto profile = builtin_sim_profile();
  profile.state.shaper["x"] = "zv:48.6:0.1";
  const auto g = build_experiment("axis-rectangle", {}, "", profile, Dialect(Firmware::marlin)).gcode;
  auto at = [&](const std::string& l) { return std::find(g.begin(), g.end(), l) - g.begin(); };
  CHECK(at("M593 F0") < at(";@record accelerometer on"));
  CHECK(at("M593 X F48.6 D0.1") > at(";@epilogue"));
  CHECK(at("M593 X F48.6 D0.1") < static_cast<long>(g.size()));
  // Without a configured shaper nothing is turned off.
  const auto plain = build_experiment("axis-rectangle", {}, "", builtin_sim_profile(), Dialect(Firmware::marlin)).gcode;
  CHECK(std::find(plain.begin(), plain.end(), "M593 F0") == plain.end());
}

TEST_CASE("an aborted sweep on Marlin is stopped with M410, then its test settings are restored", "[machine]") {
  const std::string dir = tunekit::test::scratch_dir("abort_restore");
  std::atomic<bool> abort{false};
  RunOptions o;
  o.protocol = "axis-sweep";
  o.run_dir = dir;
  o.run_dir += "/run";
  o.abort_flag = &abort;
  tunekit::calibration::load_run_machine(o, "", {});
  int lines = 0;
  o.progress = [&](const std::string& m) {
    if (m.rfind("firmware:", 0) == 0) abort = true;  // interrupted before the first line
    ++lines;
  };
  CHECK_THROWS_AS(run_experiment(o), MachineError);
  const std::string received = tunekit::test::read_text(o.run_dir + "/sim_received.gcode");
  const auto stop = received.find("M410");
  REQUIRE(stop != std::string::npos);
  CHECK(received.find("M205 B20000", stop) != std::string::npos);
  CHECK(received.find("M201 X3000 Y3000", stop) != std::string::npos);
}

TEST_CASE("a protocol whose sensor the firmware cannot record fails before heating or homing", "[machine]") {
  // RepRapFirmware records its accelerometer with M956 into a file on the board; over a plain
  // G-code link without a sensor stream nothing can be recorded: stop right after M115.
  const std::string dir = tunekit::test::scratch_dir("no_sensor_stream");
  for (const char* protocol : {"axis-sweep", "liquefier-step"}) {
    INFO(protocol);
    RunOptions o;
    o.protocol = protocol;
    o.run_dir = dir;
    o.run_dir += "/";
    o.run_dir += protocol;
    tunekit::calibration::load_run_machine(o, "", {"firmware=rrf", "sensor_stream=0"});
    std::string why;
    try {
      run_experiment(o);
    } catch (const MachineError& e) {
      why = e.message();
    }
    CHECK(why.find("cannot record") != std::string::npos);
    const std::string received = tunekit::test::read_text(o.run_dir + "/sim_received.gcode");
    CHECK(received.find("M115") != std::string::npos);
    for (const char* never : {"G28", "M109", "M104 S2", "G1 "}) {
      INFO(never);
      CHECK(received.find(never) == std::string::npos);
    }
  }
}
