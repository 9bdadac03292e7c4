// The axis sweep with the slow sweeping motion Klipper's TEST_RESONANCES adds since 6 December
// 2024 (O'Connor, Butyugin et al., Klipper 3D printer firmware, klippy/extras/resonance_tester.py:
// SweepingVibrationsTestGenerator, defaults sweeping_accel 400 mm/s^2, sweeping_period 1.2 s):
// the G-code's moves, the safety gate on them, the motion the simulator runs and the resonance
// fit on it, by the power spectrum and by the frequency response to the commanded acceleration.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/firmware/dialect.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/machine/gcode.hpp"
#include "tunekit/protocols/experiments.hpp"
#include "tunekit/protocols/runner.hpp"
#include "tunekit/sim/builtin_profile.hpp"

using tunekit::test::run_cli;
using namespace tunekit::protocols;
using tunekit::firmware::Dialect;
using tunekit::firmware::Firmware;

namespace {

/// The lowest and highest position of the swept axis while the accelerometer records, mm from
/// the centre, from the G-code's own moves.
std::pair<double, double> recorded_range(const Experiment& e) {
  tunekit::machine::GcodeInterpreter in;
  const std::size_t k = e.axis == "x" ? 0 : 1;
  const double c = e.params.at("center_mm");
  double lo = 0, hi = 0;
  bool on = false;
  for (const auto& l : e.gcode) {
    if (l == ";@record accelerometer on") on = true;
    if (l == ";@record accelerometer off") on = false;
    const auto w = tunekit::machine::parse_gcode(l);
    if (!w) continue;
    const auto m = in.apply(*w);
    if (!m || !on) continue;
    lo = std::min(lo, m->end[k] - c);
    hi = std::max(hi, m->end[k] - c);
  }
  return {lo, hi};
}

/// Columns of a CSV file the run wrote.
tunekit::formats::CsvTable read_table(const std::string& path) {
  return tunekit::formats::read_csv(path, {{}, "time"});
}

}  // namespace

TEST_CASE("Klipper's axis sweep swings about the centre by sweeping_accel sweeping_period^2 / 32", "[machine]") {
  const auto profile = tunekit::sim::builtin_sim_profile();
  const std::map<std::string, double> p{{"freq_start_hz", 20}, {"freq_end_hz", 60}, {"hz_per_sec", 4}};
  const auto on = build_experiment("axis-sweep", p, "x", profile, Dialect(Firmware::klipper));
  CHECK(on.params.at("sweeping_accel") == 400);
  CHECK(on.params.at("sweeping_period") == 1.2);
  const double swing = 400 * 1.2 * 1.2 / 32;  // 18 mm
  const auto [lo, hi] = recorded_range(on);
  // The pulses alone move at most accel_per_hz / (16 f) = 0.19 mm at 20 Hz.
  CHECK(hi == Approx(swing).margin(0.5));
  CHECK(-lo == Approx(swing).margin(0.5));
  CHECK(on.excitation["excursion_mm"][1].get<double>() == Approx(hi).margin(1e-4));
  // Turned off by either parameter, as in Klipper (sweeping_period 0) or by no acceleration.
  for (const char* off : {"sweeping_period", "sweeping_accel"}) {
    INFO(off);
    auto q = p;
    q[off] = 0;
    const auto plain = build_experiment("axis-sweep", q, "x", profile, Dialect(Firmware::klipper));
    const auto [plo, phi] = recorded_range(plain);
    CHECK(plo >= -1e-9);
    CHECK(phi <= 60.0 / (16 * 20) + 1e-4);
  }
}

TEST_CASE("the sweeping motion is refused on Marlin and RepRapFirmware with the way out, off there by default",
          "[machine]") {
  const auto profile = tunekit::sim::builtin_sim_profile();
  for (const auto fw : {Firmware::marlin, Firmware::reprapfirmware}) {
    const auto e = build_experiment("axis-sweep", {}, "x", profile, Dialect(fw));
    CHECK(e.params.at("sweeping_accel") == 0);
    std::string why;
    try {
      build_experiment("axis-sweep", {{"sweeping_accel", 400}}, "x", profile, Dialect(fw));
    } catch (const tunekit::InputError& err) {
      why = err.message();
    }
    CHECK(why.find("sweeping_accel=0") != std::string::npos);
  }
}

TEST_CASE("the safety gate sees the sweeping motion's travel and the dry run prints its moves", "[machine][safety]") {
  // 15 mm from the end of the travel: room for the pulses, not for the 18 mm swing of Klipper's
  // 400 mm/s^2. Asked for, it is refused; by default the swing is lowered to fit the travel.
  const auto near_end =
      run_cli({"run", "axis-sweep", "--axis", "x", "--machine", "sim", "--sim", "firmware=klipper", "--dry-run", "-p",
               "center_mm=15", "-p", "freq_end_hz=40", "-p", "sweeping_accel=400"});
  CHECK(near_end.code == 2);
  CHECK(near_end.err.find("outside the travel 0..220") != std::string::npos);
  const auto fitted = run_cli({"run", "axis-sweep", "--axis", "x", "--machine", "sim", "--sim", "firmware=klipper",
                               "--dry-run", "--json", "-p", "center_mm=15", "-p", "freq_end_hz=40"});
  REQUIRE(fitted.code == 0);
  const auto params = nlohmann::json::parse(fitted.out).at("results").at("experiment").at("params");
  // 32 x 90 % of the 15 mm to the travel's end over the 1.2 s period squared: 300 mm/s^2.
  CHECK(params.at("sweeping_accel").get<double>() == Approx(300));
  const auto no_swing = run_cli({"run", "axis-sweep", "--axis", "x", "--machine", "sim", "--sim", "firmware=klipper",
                                 "--dry-run", "-p", "center_mm=15", "-p", "freq_end_hz=40", "-p", "sweeping_period=0"});
  CHECK(no_swing.code == 0);
  const auto dry = run_cli({"run", "axis-sweep", "--axis", "x", "--machine", "sim", "--sim", "firmware=klipper",
                            "--dry-run", "-p", "freq_end_hz=40"});
  REQUIRE(dry.code == 0);
  // The moves the sweeping motion adds are printed: positions 18 mm either side of 110.
  double lo = 1e9, hi = -1e9;
  std::istringstream in(dry.out);
  for (std::string l; std::getline(in, l);)
    if (l.rfind("G1 X", 0) == 0 && l.find(" Y") == std::string::npos) {
      const double x = std::stod(l.substr(4));
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
  CHECK(lo < 110 - 17);
  CHECK(hi > 110 + 17);
}

TEST_CASE("a simulated Klipper sweep with the sweeping motion runs it and still gives the axis mode",
          "[machine][e2e]") {
  const auto dir = tunekit::test::scratch_dir("machine_sweeping_fit") + "/run";
  const auto run = run_cli({"run", "axis-sweep", "--axis", "x", "--machine", "sim", "--run-dir", dir, "--sim",
                            "firmware=klipper", "--sim", "mode_x=52:0.07", "-p", "freq_start_hz=20", "-p",
                            "freq_end_hz=90", "-p", "hz_per_sec=5", "--json"});
  INFO(run.err);
  REQUIRE(run.code == 0);
  const auto files = nlohmann::json::parse(run.out)["results"]["files"];
  const auto truth = tunekit::test::read_json(dir + "/truth.json")["axes"]["x"]["modes"][0];
  const double f_true = truth["freq_hz"].get<double>(), zeta_true = truth["zeta"].get<double>();

  // The commanded motion the simulator ran carries the sweeping motion: its speed, the
  // acceleration integrated with the pulses averaged out over 0.1 s, is a triangle wave of
  // amplitude sweeping_accel sweeping_period / 4 = 120 mm/s (110 mm/s after the averaging; the
  // pulses alone: 15 mm/s). Over the first 2.7 s (two swings each way; later the summed
  // sampling error of the faster pulses' acceleration steps grows to several mm/s).
  const auto cmd = read_table(files["commanded_accel"]);
  const auto& t = cmd.column("time").values;
  const auto& a = cmd.column("accel_x").values;
  REQUIRE(t.size() > 1000);
  std::size_t i0 = 0;
  while (i0 < a.size() && a[i0] == 0) ++i0;  // the settle before the sweep
  std::vector<double> v(t.size(), 0.0);
  for (std::size_t i = i0 + 1; i < t.size(); ++i) v[i] = v[i - 1] + a[i - 1] * (t[i] - t[i - 1]);
  double slow_lo = 0, slow_hi = 0, sum = 0;
  const std::size_t w = 320;  // 0.1 s at 3200 Hz
  for (std::size_t i = i0; i < v.size() && t[i] < t[i0] + 2.7; ++i) {
    sum += v[i];
    if (i >= i0 + w) sum -= v[i - w];
    if (i + 1 >= i0 + w) {
      slow_lo = std::min(slow_lo, sum / w);
      slow_hi = std::max(slow_hi, sum / w);
    }
  }
  CHECK((slow_hi - slow_lo) / 2 == Approx(110).epsilon(0.05));
  CHECK(std::abs(slow_hi + slow_lo) / 2 < 5);

  SECTION("the power spectrum's fit") {
    const auto fit = run_cli({"resonance", files["accel"], "--axis", "x", "--json"});
    INFO(fit.err);
    REQUIRE(fit.code == 0);
    const auto modes = nlohmann::json::parse(fit.out)["results"]["axes"]["x"]["modes"];
    REQUIRE(!modes.empty());
    CHECK(modes[0]["freq_hz"].get<double>() == Approx(f_true).epsilon(0.05));
    CHECK(modes[0]["zeta"].get<double>() == Approx(zeta_true).epsilon(0.20));
  }
  SECTION("the frequency response to the commanded acceleration, sweeping motion included") {
    const auto acc = read_table(files["accel"]);
    REQUIRE(acc.rows == cmd.rows);
    const std::string joined = tunekit::test::scratch_dir("machine_sweeping_fit") + "/joined.csv";
    std::ofstream out(joined);
    out << "time,ax,ax_cmd\n";
    for (std::size_t i = 0; i < t.size(); ++i)
      out << t[i] << ',' << acc.column("accel_x").values[i] << ',' << a[i] << '\n';
    out.close();
    const auto fit = run_cli(
        {"resonance", joined, "--axis", "x", "--time", "time", "--accel", "ax", "--excitation", "ax_cmd", "--json"});
    INFO(fit.err);
    REQUIRE(fit.code == 0);
    const auto res = nlohmann::json::parse(fit.out)["results"]["axes"]["x"];
    REQUIRE(res["psd"].contains("frf"));
    CHECK(res["fit"]["method"] == "frf");
    const auto& modes = res["modes"];
    REQUIRE(!modes.empty());
    CHECK(modes[0]["freq_hz"].get<double>() == Approx(f_true).epsilon(0.05));
    CHECK(modes[0]["zeta"].get<double>() == Approx(zeta_true).epsilon(0.20));
  }
}
