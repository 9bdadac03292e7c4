// Marlin's fixed-time motion report (M493) in each of its forms, and the axis sweep turning the
// FT_MOTION shaper off and back on. The report texts are written from the format strings of
// say_shaping() in Marlin/src/gcode/feature/ft_motion/M493.cpp of Marlin's bugfix-2.1.x line:
//   2023 (fxdTiCtrl):           "Fixed-Time Motion " en/dis "abled", " with " <mode> " shaping",
//                               "."; "X/A static compensator frequency: " <f,2> "Hz",
//                               "Y/B static compensator frequency: " <f,2> " Hz";
//                               "Linear Advance " en/dis "abled" ". Gain: " <K,5>.
//   2024 (per-axis cmpnstr):    " with X/A axis " <type> " shaping", " and with Y/B axis "...
//   2024-2025 (shaper[]):       " with " AXIS_0_NAME " axis " <type> " shaping" (X, or A on
//                               CoreXY), "X static shaper frequency: " <f,2> "Hz".
//   2025 (Z/E shaping):         " (" <axis> "=" <type> [" ; " ...] ")", listing shaping axes.
//   late 2025 (C letter, V2):   the same list with "None" for unshaped axes, "Axis Sync. ..."
//                               and "X static shaper frequency: " <f,2> " Hz"; M493 V answers
//                               "FTM V" FTM_VERSION (2).
#include <catch2/catch.hpp>

#include <atomic>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/calibration/analyses/simulated_machine.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/file_bytes.hpp"
#include "tunekit/firmware/dialect.hpp"
#include "tunekit/machine/gcode.hpp"
#include "tunekit/machine/machine_profile.hpp"
#include "tunekit/protocols/runner.hpp"
#include "tunekit/sim/simulator.hpp"
#include "sim_m493_answers.hpp"

using tunekit::InputError;
using tunekit::MachineError;
using namespace tunekit::firmware;
using namespace tunekit::protocols;
using namespace tunekit::sim;

namespace {

/// Active, form and each axis's shaper code and frequency agree.
void check_same(const FtMotionReport& a, const FtMotionReport& b) {
  CHECK(a.active == b.active);
  CHECK(a.form == b.form);
  CHECK(a.shapers == b.shapers);
  for (const auto& [axis, s] : a.shapers) {
    CHECK(a.axes.at(axis).code == b.axes.at(axis).code);
    CHECK(a.axes.at(axis).freq_hz == Approx(b.axes.at(axis).freq_hz));
  }
}

struct Form {
  const char* name;
  const char* shaper_x;  // sim option ft_shaper_x
  const char* shaper_y;
};
// The 2023 form has one mode for X and Y (S15 MZV); the others shape each axis on its own.
const Form kForms[] = {{"mode", "8:41.5", "8:37"},
                       {"axis_slash", "1:41", "8:38.2"},
                       {"axis_named", "2:45", "5:40"},
                       {"axis_list", "0:37", "8:52.4"},
                       {"axis_list_v2", "1:36", "0:37"}};

std::vector<std::string> sim_options(const Form& f) {
  return {"firmware=marlin", "ft_motion=on", std::string("m493_form=") + f.name,
          std::string("ft_shaper_x=") + f.shaper_x, std::string("ft_shaper_y=") + f.shaper_y};
}

/// The commands the simulator received, without line numbers and checksums.
std::vector<std::string> received_commands(Simulator& sim) {
  std::vector<std::string> out;
  for (const auto& l : sim.received()) out.push_back(tunekit::machine::split_numbered(l).body);
  return out;
}

std::size_t index_of(const std::vector<std::string>& lines, const std::string& l, std::size_t from = 0) {
  const auto it = std::find(lines.begin() + static_cast<long>(from), lines.end(), l);
  return it == lines.end() ? std::string::npos : static_cast<std::size_t>(it - lines.begin());
}

}  // namespace

TEST_CASE("Marlin's M493 report is read in every form, with the letters that turn its shaper off and back",
          "[machine]") {
  SECTION("2023, one mode for X and Y (M493 S15)") {
    const auto r = parse_m493_report(
        {"Fixed-Time Motion enabled with MZV shaping.", "X/A static compensator frequency: 41.50Hz",
         "Y/B static compensator frequency: 37.00 Hz", "Linear Advance disabled. Gain: 0.00000", "ok"});
    CHECK(r.form == M493Form::mode);
    CHECK(r.shaping());
    CHECK(r.axes.at("x").code == 15);
    CHECK(r.axes.at("y").freq_hz == Approx(37));
    CHECK(m493_shaping_off(r) == std::vector<std::string>{"M493 S1"});
    CHECK(m493_shaping_restore(r) == std::vector<std::string>{"M493 S15 A41.5 B37"});
  }
  SECTION("2024, per-axis shaping reported as X/A and Y/B") {
    const auto r =
        parse_m493_report({"Fixed-Time Motion enabled with X/A axis ZV shaping and with Y/B axis MZV shaping.",
                           "X/A static compensator frequency: 41.00Hz", "Y/B static compensator frequency: 38.20 Hz",
                           "Linear Advance disabled", "ok"});
    CHECK(r.form == M493Form::axis_slash);
    CHECK(r.shapers == std::map<std::string, std::string>{{"x", "ZV"}, {"y", "MZV"}});
    CHECK(m493_shaping_off(r) == std::vector<std::string>{"M493 X0 Y0"});
    CHECK(m493_shaping_restore(r) == std::vector<std::string>{"M493 X1 Y8 A41 B38.2"});
  }
  SECTION("2024-2025, named axes (A/B on a CoreXY build)") {
    const auto r = parse_m493_report({"Fixed-Time Motion enabled with A axis ZVD shaping and with B axis EI shaping.",
                                      "A static shaper frequency: 45.00Hz", "B static shaper frequency: 40.00 Hz",
                                      "Linear Advance enabled. Gain: 0.04", "ok"});
    CHECK(r.form == M493Form::axis_named);
    CHECK(r.axes.at("x").code == 2);
    CHECK(r.axes.at("y").code == 5);
    CHECK(r.linear_advance_k == Approx(0.04));
    CHECK(m493_shaping_off(r) == std::vector<std::string>{"M493 X0 Y0"});
    CHECK(m493_shaping_restore(r) == std::vector<std::string>{"M493 X2 Y5 A45 B40"});
  }
  SECTION("2025, the axis list, shaping axes only, X/Y shaper letters (no FTM version)") {
    const auto r =
        parse_m493_report({"Fixed-Time Motion enabled (Y=MZV)", "X static shaper frequency: 37.00Hz",
                           "Y static shaper frequency: 52.40 Hz", "Linear Advance disabled. Gain: 0.00", "ok", "ok"});
    CHECK(r.form == M493Form::axis_list);
    CHECK(r.version == 1);
    CHECK(r.shapers.count("x") == 0);
    CHECK(m493_shaping_off(r) == std::vector<std::string>{"M493 Y0"});
    CHECK(m493_shaping_restore(r) == std::vector<std::string>{"M493 Y8 B52.4"});
  }
  SECTION("late 2025, the axis list with None, C letter for flagged axes (FTM V2)") {
    const auto r = parse_m493_report({"Fixed-Time Motion enabled (X=ZV ; Y=None)", "Axis Sync. enabled",
                                      "X static shaper frequency: 36.00 Hz", "ok", "FTM V2", "ok"});
    CHECK(r.form == M493Form::axis_list);
    CHECK(r.version == 2);
    CHECK(r.axes.at("y").code == 0);
    CHECK(r.shapers == std::map<std::string, std::string>{{"x", "ZV"}});
    CHECK(m493_shaping_off(r) == std::vector<std::string>{"M493 X C0"});
    CHECK(m493_shaping_restore(r) == std::vector<std::string>{"M493 X C1 A36"});
  }
  SECTION("fixed-time motion off, or not built: nothing to turn off") {
    const auto off = parse_m493_report({"Fixed-Time Motion disabled (X=ZV ; Y=MZV)", "ok"});
    CHECK(off.present);
    CHECK_FALSE(off.shaping());
    CHECK(m493_shaping_off(off).empty());
    const auto none = parse_m493_report({"echo:Unknown command: \"M493\"", "ok"});
    CHECK_FALSE(none.present);
    CHECK(m493_shaping_restore(none).empty());
  }
}

TEST_CASE("the simulator's Marlin answers M493 in each form and takes that form's off and restore letters",
          "[machine]") {
  for (const auto& f : kForms) {
    INFO(f.name);
    Simulator sim(SimConfig::from_options(sim_options(f)));
    const auto original = tunekit::test::ask_sim_m493(sim);
    CHECK(to_string(original.form) == (std::string(f.name) == "axis_list_v2" ? "axis_list" : f.name));
    REQUIRE(original.shaping());
    for (const auto& l : m493_shaping_off(original)) tunekit::test::sim_answer_lines(sim, l);
    const auto off = tunekit::test::ask_sim_m493(sim);
    CHECK(off.active);
    CHECK_FALSE(off.shaping());
    for (const auto& l : m493_shaping_restore(original)) tunekit::test::sim_answer_lines(sim, l);
    check_same(tunekit::test::ask_sim_m493(sim), original);
  }
}

TEST_CASE("an axis sweep on a Marlin running FT_MOTION turns its shaper off and restores it, in each M493 form",
          "[machine]") {
  const std::string dir = tunekit::test::scratch_dir("marlin_m493_sweep");
  for (const auto& f : kForms) {
    INFO(f.name);
    const auto cfg = SimConfig::from_options(sim_options(f));
    Simulator fresh(cfg);
    const auto original = tunekit::test::ask_sim_m493(fresh);
    const auto off = m493_shaping_off(original), back = m493_shaping_restore(original);
    REQUIRE_FALSE(off.empty());
    RunOptions o;
    o.protocol = "axis-sweep";
    o.axis = "x";
    o.params = {{"freq_start_hz", 30}, {"freq_end_hz", 60}};
    tunekit::calibration::load_run_machine(o, "", sim_options(f));
    // The dry run shows both, the restore after the epilogue marker; the gate accepts them.
    o.dry_run = true;
    const auto plan = run_experiment(o).gcode;
    const auto epi = index_of(plan, ";@epilogue");
    CHECK(index_of(plan, off.front()) < epi);
    CHECK(index_of(plan, back.front(), epi) != std::string::npos);
    // The run against the simulated build: off before the sweep, restore after it.
    o.dry_run = false;
    o.run_dir = dir + "/" + f.name;
    SimPtyServer server(cfg);
    o.port = server.path();
    const auto res = run_experiment(o);
    const auto run =
        nlohmann::json::parse(tunekit::read_file_bytes(res.files.at(tunekit::protocols::RunFile::summary)));
    CHECK(run.at("firmware").at("m493_form") == to_string(m493_syntax(original)));
    server.stop();
    server.wait();
    const auto received = received_commands(server.sim());
    const auto at_off = index_of(received, off.front());
    REQUIRE(at_off != std::string::npos);
    CHECK(index_of(received, back.front(), at_off) != std::string::npos);
    check_same(tunekit::test::ask_sim_m493(server.sim()), original);
  }
}

TEST_CASE("a sweep on a Marlin running FT_MOTION stopped part-way still restores its shaper", "[machine]") {
  const std::string dir = tunekit::test::scratch_dir("marlin_m493_abort");
  for (const auto& f : {kForms[0], kForms[4]}) {
    INFO(f.name);
    const auto cfg = SimConfig::from_options(sim_options(f));
    Simulator fresh(cfg);
    const auto original = tunekit::test::ask_sim_m493(fresh);
    const auto off = m493_shaping_off(original), back = m493_shaping_restore(original);
    SimPtyServer server(cfg);
    std::atomic<bool> abort{false};
    RunOptions o;
    o.protocol = "axis-sweep";
    o.axis = "x";
    o.params = {{"freq_start_hz", 30}, {"freq_end_hz", 60}};
    tunekit::calibration::load_run_machine(o, "", sim_options(f));
    o.run_dir = dir + "/" + f.name;
    o.port = server.path();
    o.abort_flag = &abort;
    // Stop once the shaper is off and the sweep has been under way for 40 lines.
    std::thread stopper([&] {
      for (int i = 0; i < 20000 && !abort; ++i) {
        const auto r = received_commands(server.sim());
        const auto at = index_of(r, off.front());
        if (at != std::string::npos && r.size() > at + 40) abort = true;
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
    });
    CHECK_THROWS_AS(run_experiment(o), MachineError);
    abort = true;
    stopper.join();
    server.stop();
    server.wait();
    const auto received = received_commands(server.sim());
    const auto at_stop = index_of(received, "M410");
    REQUIRE(at_stop != std::string::npos);
    CHECK(index_of(received, off.front()) < at_stop);
    CHECK(index_of(received, back.front(), at_stop) != std::string::npos);
    check_same(tunekit::test::ask_sim_m493(server.sim()), original);
  }
}

TEST_CASE("a printer profile keeps its Marlin's M493 report: the dry run shows the FT shaper off and back",
          "[machine]") {
  const std::string dir = tunekit::test::scratch_dir("marlin_m493_profile");
  std::string toml = tunekit::test::read_text(tunekit::test::dataset("machines/sim.toml"));
  const std::string report = R"(m493_report = ["Fixed-Time Motion enabled with X axis MZV shaping.",
  "X static shaper frequency: 47.50Hz", "Y static shaper frequency: 37.00 Hz", "Linear Advance disabled"])";
  const auto at = toml.find("[firmware_state]\n");
  REQUIRE(at != std::string::npos);
  toml.insert(at + 17, report + "\n");
  const std::string path = tunekit::test::write_scratch("marlin_m493_profile.toml", toml);
  const auto profile = tunekit::machine::load_machine_profile(path);
  CHECK(profile.state.m493_report.size() == 4);
  RunOptions o;
  o.protocol = "axis-sweep";
  o.axis = "x";
  o.machine = path;
  o.port = dir + "/no-printer";  // a dry run opens nothing
  tunekit::calibration::load_run_machine(o, "", {});
  o.dry_run = true;
  const auto plan = run_experiment(o).gcode;
  const auto epi = index_of(plan, ";@epilogue");
  CHECK(index_of(plan, "M493 X0") < epi);
  CHECK(index_of(plan, "M493 X8 A47.5", epi) != std::string::npos);
  CHECK(index_of(plan, "M593 F0") == std::string::npos);  // bypassed with fixed-time motion active
  toml.replace(toml.find("m493_report = ["), 15, "m493_report = [1, ");
  CHECK_THROWS_AS(tunekit::machine::parse_machine_profile(toml, path), InputError);
}
