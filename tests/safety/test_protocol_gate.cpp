// The gate between a protocol and a machine: no non-finite number, nothing outside the
// profile and no unbounded protocol reaches a machine, whatever the parameters; and the link's
// last check refuses such a line whatever produced it.
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>

#include "test_support.hpp"
#include "tunekit/calibration/analyses/simulated_machine.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/firmware/dialect.hpp"
#include "tunekit/protocols/experiments.hpp"
#include "tunekit/machine/gcode_link.hpp"
#include "tunekit/protocols/runner.hpp"
#include "tunekit/protocols/safety.hpp"
#include "tunekit/sim/builtin_profile.hpp"
#include "tunekit/sim/simulator.hpp"
#include "tunekit/machine/transport.hpp"

using namespace tunekit::protocols;
using namespace tunekit::machine;
using namespace tunekit::firmware;
using namespace tunekit::sim;
using tunekit::test::run_cli;
using tunekit::test::scratch_dir;
namespace fs = std::filesystem;

namespace {

/// An independent reading of G-code for the property test: every word is a letter (or
/// KEY=) followed by a plain decimal number that is finite; positions, feed rates,
/// accelerations and temperatures inside the profile. Returns what is wrong ("" if nothing).
std::string independent_check(const std::vector<std::string>& gcode, const MachineProfile& p) {
  static const std::regex number(R"(^[-+]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][-+]?[0-9]+)?$)");
  double max_v = p.extruder.max_velocity_mm_s, max_a = p.extruder.max_accel_mm_s2;
  for (const auto& [n, a] : p.axes) {
    max_v = std::max(max_v, a.max_velocity_mm_s);
    max_a = std::max(max_a, a.max_accel_mm_s2);
  }
  for (const auto& raw : gcode) {
    std::string line = raw.substr(0, raw.find(';'));
    std::istringstream in(line);
    std::string head, tok;
    if (!(in >> head)) continue;
    while (in >> tok) {
      std::string key, value;
      if (const auto eq = tok.find('='); eq != std::string::npos) key = tok.substr(0, eq), value = tok.substr(eq + 1);
      else key = tok.substr(0, 1), value = tok.substr(1);
      if (!std::regex_match(value, number)) return "'" + tok + "' is not a plain number in: " + raw;
      const double v = std::stod(value);
      if (!std::isfinite(v)) return "'" + tok + "' is not finite in: " + raw;
      if (head == "G1" || head == "G0") {
        if (key == "X" || key == "Y" || key == "Z") {
          std::string axis(1, static_cast<char>(std::tolower(key[0])));
          const auto& a = p.axes.at(axis);
          if (v < a.min_mm - 1e-6 || v > a.max_mm + 1e-6) return "position outside the travel: " + raw;
        }
        if (key == "F" && !(v > 0 && v / 60 <= max_v + 1e-6)) return "feed rate outside the profile: " + raw;
      }
      // Klipper's SET_VELOCITY_LIMIT (klippy/toolhead.py cmd_SET_VELOCITY_LIMIT): ACCEL is an
      // acceleration, MINIMUM_CRUISE_RATIO a fraction in [0, 1).
      const bool is_accel = head == "M204" || (head == "SET_VELOCITY_LIMIT" && key == "ACCEL");
      if (is_accel && !(v > 0 && v <= max_a + 1e-6)) return "acceleration outside the profile: " + raw;
      if (head == "SET_VELOCITY_LIMIT" && key == "MINIMUM_CRUISE_RATIO" && !(v >= 0 && v < 1))
        return "minimum cruise ratio outside [0, 1): " + raw;
      if ((head == "M104" || head == "M109") && key == "S" && !(v >= 0 && v <= p.temperature.hotend_max_c))
        return "temperature outside the profile: " + raw;
      if (head == "G4" && !(v >= 0)) return "negative dwell: " + raw;
    }
  }
  return "";
}

const std::vector<double>& hostile_values() {
  static const std::vector<double> v{0.0,
                                     -0.0,
                                     std::numeric_limits<double>::denorm_min(),
                                     1e-300,
                                     1e-9,
                                     1e200,
                                     std::numeric_limits<double>::max(),
                                     std::numeric_limits<double>::infinity(),
                                     -std::numeric_limits<double>::infinity(),
                                     std::numeric_limits<double>::quiet_NaN(),
                                     -1.0,
                                     -1e308};
  return v;
}

}  // namespace

TEST_CASE("property: every protocol and parameter with hostile values is refused or gives G-code inside the profile",
          "[safety]") {
  const auto profile = builtin_sim_profile();
  std::size_t refused = 0, accepted = 0;
  for (const auto& spec : protocol_specs()) {
    for (const auto& prm : spec.params) {
      for (const double value : hostile_values()) {
        for (const auto fw : {Firmware::marlin, Firmware::klipper, Firmware::reprapfirmware}) {
          INFO(spec.name << " " << prm.name << "=" << value << " (" << to_string(fw) << ")");
          const auto t0 = std::chrono::steady_clock::now();
          std::vector<std::string> gcode;
          try {
            const auto e = build_experiment(spec.name, {{prm.name, value}}, "y", profile, Dialect(fw));
            require_within_limits(e.gcode, profile, e.sensors);
            gcode = e.gcode;
          } catch (const tunekit::InputError& err) {
            ++refused;
            CHECK(err.code() == tunekit::ExitCode::bad_input);
            CHECK(std::chrono::steady_clock::now() - t0 < std::chrono::seconds(5));
            continue;
          }
          ++accepted;
          CHECK(independent_check(gcode, profile) == "");
          CHECK(gcode.size() <= ProtocolLimits{}.max_lines);
          CHECK(estimate_gcode_duration_s(gcode) <= ProtocolLimits{}.max_duration_s);
        }
      }
    }
  }
  // Both outcomes occur: the property is not satisfied by refusing everything.
  CHECK(refused > 100);
  CHECK(accepted > 20);
}

TEST_CASE("non-finite G-code is refused by the gate: item accel_per_hz=1e308 and friends", "[safety]") {
  const auto runs = scratch_dir("gate_nonfinite");
  const std::vector<std::vector<std::string>> cases{
      {"run", "axis-sweep", "--axis", "y", "--dry-run", "-p", "accel_per_hz=1e308"},
      {"run", "liquefier-chirp", "--dry-run", "-p", "segment_s=1e200"},
      {"run", "ring-print", "--dry-run", "-p", "speed_mm_s=1e308"},
      {"run", "liquefier-sine", "--dry-run", "-p", "freq_min_hz=5e-324"},
      {"run", "axis-sweep", "--axis", "y", "--dry-run", "-p", "accel_per_hz=nan"},
      {"run", "axis-sweep", "--axis", "y", "--dry-run", "-p", "accel_per_hz=inf"},
      {"run", "axis-sweep", "--axis", "y", "--dry-run", "-p", "accel_per_hz=1e400"},
  };
  for (auto args : cases) {
    args.insert(args.end(), {"--runs-root", runs});
    const auto r = run_cli(args);
    INFO(args[1] << " " << args.back() << ": " << r.err);
    CHECK(r.code == 2);
    CHECK(r.out.find("inf") == std::string::npos);
    CHECK(r.out.find("nan") == std::string::npos);
    CHECK(r.err.rfind("tunekit: error: ", 0) == 0);
  }
  CHECK(fs::is_empty(runs));
}

TEST_CASE("the simulator hears nothing of a protocol with accel_per_hz=1e308", "[safety]") {
  SimPtyServer server(SimConfig{});
  RunOptions o;
  o.protocol = "axis-sweep";
  o.axis = "y";
  o.machine = tunekit::test::dataset("machines/sim.toml");
  o.port = server.path();
  o.run_dir = scratch_dir("gate_sim_1e308") + "/run";
  tunekit::calibration::load_run_machine(o, "", {});
  o.params = {{"accel_per_hz", 1e308}};
  CHECK_THROWS_AS(run_experiment(o), tunekit::InputError);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  CHECK(server.sim().received().empty());
  CHECK_FALSE(fs::exists(o.run_dir));
}

TEST_CASE("every protocol on a profile without the X, Y or Z axis is refused with the axis named", "[safety]") {
  // A profile may list only the axes it has (a loaded TOML needs one); a protocol that moves an
  // absent axis says which one, as bad input, instead of failing on a lookup.
  const Dialect marlin;
  for (const std::string missing : {"x", "y", "z"}) {
    auto profile = builtin_sim_profile();
    profile.axes.erase(missing);
    for (const auto& spec : protocol_specs()) {
      INFO(spec.name << " without " << missing);
      try {
        const auto e = build_experiment(spec.name, {}, "x", profile, marlin);
        require_within_limits(e.gcode, profile, e.sensors, ProtocolLimits{});
      } catch (const tunekit::InputError& err) {
        CHECK(std::string(err.what()).find("'" + missing + "'") != std::string::npos);
      } catch (const tunekit::Error&) {
        // A refusal of another kind (the gate's own message) is a refusal too.
      }
    }
  }
}

TEST_CASE("unbounded protocols are refused before they are generated", "[safety]") {
  const std::vector<std::vector<std::string>> cases{
      {"run", "axis-sweep", "--dry-run", "-p", "hz_per_sec=0.001"},
      {"run", "axis-sweep", "--dry-run", "-p", "freq_end_hz=1e200"},
      {"run", "axis-sweep", "--dry-run", "-p", "hz_per_sec=1e-9"},
      {"run", "liquefier-sine", "--dry-run", "-p", "freq_max_hz=1e-9"},
      {"run", "liquefier-sine", "--dry-run", "-p", "segment_s=1e-9"},
      {"run", "liquefier-chirp", "--dry-run", "-p", "segment_s=1e-9"},
      {"run", "liquefier-step", "--dry-run", "-p", "cycles=1e300"},
  };
  for (const auto& args : cases) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto r = run_cli(args);
    INFO(args[1] << " " << args.back() << ": " << r.err);
    CHECK(r.code == 2);
    CHECK(std::chrono::steady_clock::now() - t0 < std::chrono::seconds(5));
  }
  // The caps are configurable: a 45-minute sweep passes the default 2 h cap; a 30-minute cap refuses it.
  CHECK(run_cli({"run", "axis-sweep", "--dry-run", "--json", "-p", "hz_per_sec=0.033333"}).code == 0);
  const auto capped =
      run_cli({"run", "axis-sweep", "--dry-run", "-p", "hz_per_sec=0.033333", "--max-duration", "1800"});
  CHECK(capped.code == 2);
  CHECK(capped.err.find("--max-duration") != std::string::npos);
  const auto lines = run_cli({"run", "axis-sweep", "--dry-run", "--max-lines", "1000"});
  CHECK(lines.code == 2);
  CHECK(lines.err.find("--max-lines") != std::string::npos);
}

TEST_CASE("the gate lists non-finite words and non-positive feed and acceleration", "[safety]") {
  const auto profile = builtin_sim_profile();
  const std::vector<std::string> g{"G28",           "M204 Sinf", "G1 Yinf Finf",
                                   "G1 Y-nan Finf", "G1 X10 F0", "SET_VELOCITY_LIMIT ACCEL=nan",
                                   "G1 E1e999 F60", "M204 S0",   "G1 X20 F600"};
  const auto v = check_protocol(g, profile, {});
  std::string all;
  for (const auto& x : v) all += x.what + "\n";
  INFO(all);
  CHECK(all.find("'Sinf' is not a finite number") != std::string::npos);
  CHECK(all.find("'Yinf' is not a finite number") != std::string::npos);
  CHECK(all.find("'Y-nan' is not a finite number") != std::string::npos);
  CHECK(all.find("'ACCEL=nan' is not a finite number") != std::string::npos);
  CHECK(all.find("'E1e999' is not a finite number") != std::string::npos);
  CHECK(all.find("feed rate 0 mm/s is not positive") != std::string::npos);
  CHECK(all.find("acceleration 0 mm/s^2 is not positive") != std::string::npos);
  CHECK(non_finite_word("G1X10Yinf") == std::optional<std::string>("Yinf"));
  CHECK(non_finite_word("N10 G1 Yinf Finf*6") == std::optional<std::string>("Yinf"));
  CHECK_FALSE(non_finite_word("G1 X10 Y20 F600 ; nan in a comment"));
  CHECK_FALSE(non_finite_word("M117 infinite loop"));
  CHECK_FALSE(non_finite_word("SET_INPUT_SHAPER SHAPER_TYPE_X=mzv SHAPER_FREQ_X=45"));
}

TEST_CASE("the link's last check refuses a non-finite or out-of-travel line and sends nothing of it", "[safety]") {
  const auto profile = builtin_sim_profile();
  SendGuard guard(profile);
  CHECK(guard.refuse("G28") == std::nullopt);
  CHECK(guard.refuse("G1 X10 Y10 F6000") == std::nullopt);
  CHECK(guard.refuse("G1 Yinf Finf").value().find("not a finite number") != std::string::npos);
  CHECK(guard.refuse("G1 X500").value().find("outside the travel") != std::string::npos);
  CHECK(guard.refuse("G91") == std::nullopt);
  CHECK(guard.refuse("G1 X-20").value().find("x position -10") != std::string::npos);  // relative: 10 - 20
  CHECK(guard.refuse("G1 X5") == std::nullopt);  // the refused line changed nothing
  CHECK(guard.refuse("M109 S400").value().find("hotend_max_c") != std::string::npos);

  auto pair = make_transport_pair();
  GcodeLink link(*pair.first, nullptr, {std::chrono::milliseconds(200), 0, true});
  SendGuard g2(profile);
  link.guard = &g2;
  CHECK_THROWS_AS(link.send("G1 Yinf Finf"), tunekit::MachineError);
  CHECK_THROWS_AS(link.send("G1 X1000 F600"), tunekit::MachineError);
  CHECK(pair.second->read_some(std::chrono::milliseconds(100)).empty());
}

TEST_CASE("a machine that hangs up mid-write is a MachineError, not SIGPIPE", "[safety]") {
  // Found by fuzz_gcode_reply: the firmware side closed the socket and the next write killed
  // the process (exit 141) before the journal was flushed or the safe state sent.
  auto pair = make_transport_pair();
  pair.second->close();
  CHECK_THROWS_AS(pair.first->write("N1 G1 X10*99\n"), tunekit::MachineError);
  GcodeLink link(*pair.first, nullptr, {std::chrono::milliseconds(50), 0, true});
  CHECK_THROWS_AS(link.send("G1 X10 F600"), tunekit::MachineError);
}
