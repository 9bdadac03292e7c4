// What a live Marlin or RepRapFirmware machine tells tunekit, and how tunekit reads its data.
//
// Marlin FT_MOTION (fixed-time motion):
//   Marlin/src/gcode/host/M115.cpp: the capability report has no FT_MOTION line (its cap_line
//     list: SERIAL_XON_XOFF, BINARY_FILE_TRANSFER, EEPROM, ... CONFIG_EXPORT).
//   Marlin/src/gcode/feature/ft_motion/M493.cpp: M493 without parameters sets flag.report
//     ("if (!parser.seen_any()) flag.report = true", GcodeSuite::M493, line 182) and prints
//     say_shaping() (line 57): "Fixed-Time Motion enabled|disabled" (SERIAL_ECHO_TERNARY), then
//     " with X axis <type> shaping", " and with Y axis <type> shaping", "."; then the static
//     frequencies and "Linear Advance enabled. Gain: <K>" / "Linear Advance disabled".
//     Parameters (usage comment, line 138-175): S on/off, X/Y shaper 0 NONE .. 8 MZV, P/K linear
//     advance, A/B frequency, I/J damping.
//   Marlin/src/gcode/gcode.cpp: an unknown command answers "echo:Unknown command: "M493"".
//   Marlin/src/module/stepper.cpp Stepper::isr(): with ftMotion.cfg.active the classic shaper
//     and linear advance are not run (only ftMotion_stepper()).
// RepRapFirmware accelerometer files:
//   src/GCodes/GCodes2.cpp: file commands M20 (line 953, list), M28 (1310, write), M29, M30
//     (1331, delete), M36 (1351, file info), M38 (1436, SHA1), M39 (1466, card info): none
//     returns a file's contents over serial; fileread() (GCodeBuffer/ExpressionParser.cpp:882)
//     reads one line of values.
//   src/Accelerometers/Accelerometers.cpp: M956 (StartAccelerometer, line 391) needs P, S, A,
//     writes 0:/sys/accelerometer/<F name> (line 443) with the header "Sample,X,Y,Z" (478) and the
//     trailer "Rate %u, overflows %u" (200); M955 P0 reports "... samples at %uHz ..." (383).
//   src/Networking/HttpResponder.cpp: rr_download?name= (line 1063) -> SendFile: "HTTP/1.1 200
//     OK" (931) with Content-Length (986); RejectMessage "HTTP/1.1 404 file not found" (1353).
#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/calibration/analyses/simulated_machine.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/ident/rrf_accelerometer.hpp"
#include "tunekit/firmware/dialect.hpp"
#include "tunekit/firmware/firmware_export.hpp"
#include "tunekit/machine/rrf_http.hpp"
#include "tunekit/protocols/runner.hpp"
#include "tunekit/sim/simulator.hpp"
#include "tunekit/core/file_bytes.hpp"
#include "sim_m493_answers.hpp"

using tunekit::InputError;
using tunekit::MachineError;
using namespace tunekit::protocols;
using namespace tunekit::machine;
using namespace tunekit::firmware;
using namespace tunekit::sim;

TEST_CASE("Marlin M493 reports: fixed-time motion present, active, its shapers and advance", "[machine]") {
  const auto on =
      parse_m493_report({"Fixed-Time Motion enabled with X axis ZV shaping and with Y axis 2 Hump EI shaping.",
                         "X static shaper frequency: 41.00Hz", "Y static shaper frequency: 37.50 Hz",
                         "Linear Advance enabled. Gain: 0.05", "ok"});
  CHECK(on.present);
  CHECK(on.active);
  CHECK(on.shapers.at("x") == "ZV");
  CHECK(on.shapers.at("y") == "2 Hump EI");
  CHECK(on.linear_advance);
  CHECK(on.linear_advance_k == Approx(0.05));
  const auto y_only = parse_m493_report({"Fixed-Time Motion disabled and with Y axis MZV shaping.", "ok"});
  CHECK(y_only.present);
  CHECK_FALSE(y_only.active);
  CHECK(y_only.shapers.count("x") == 0);
  CHECK(y_only.shapers.at("y") == "MZV");
  const auto none = parse_m493_report({"echo:Unknown command: \"M493\"", "ok"});
  CHECK_FALSE(none.present);
  CHECK_FALSE(none.active);
}

TEST_CASE("the simulator's Marlin answers M493 like an FT_MOTION build, or as an unknown command", "[machine]") {
  Simulator built(SimConfig::from_options({"firmware=marlin", "ft_motion=on"}));
  auto r = parse_m493_report(tunekit::test::sim_answer_lines(built, "M493"));
  CHECK(r.present);
  CHECK(r.active);
  // M493 X1 A41 sets ZV at 41 Hz on X and reports (flag.report); S0 switches it off.
  const auto set = tunekit::test::sim_answer_lines(built, "M493 X1 A41 I0.12");
  r = parse_m493_report(set);
  CHECK(r.shapers.at("x") == "ZV");
  CHECK(std::find(set.begin(), set.end(), "X static shaper frequency: 41.00Hz") != set.end());
  CHECK_FALSE(parse_m493_report(tunekit::test::sim_answer_lines(built, "M493 S0")).active);
  Simulator classic(SimConfig::from_options({"firmware=marlin"}));
  const auto unknown = tunekit::test::sim_answer_lines(classic, "M493");
  CHECK(unknown.front() == "echo:Unknown command: \"M493\"");
  CHECK_FALSE(parse_m493_report(unknown).present);
  CHECK_THROWS_AS(SimConfig::from_options({"ft_motion=maybe"}), InputError);
}

TEST_CASE("a live Marlin with FT_MOTION active is detected from M493, and its settings go to M493", "[machine]") {
  const std::string dir = tunekit::test::scratch_dir("marlin_ft_live");
  for (const char* mode : {"on", "off", "none"}) {
    INFO(mode);
    RunOptions o;
    o.protocol = "axis-sweep";
    o.run_dir = dir + "/" + mode;
    o.params = {{"freq_start_hz", 30}, {"freq_end_hz", 60}};
    tunekit::calibration::load_run_machine(o, "", {"firmware=marlin", std::string("ft_motion=") + mode});
    const auto res = run_experiment(o);
    const auto run =
        nlohmann::json::parse(tunekit::read_file_bytes(res.files.at(tunekit::protocols::RunFile::summary)));
    const auto* ft = run.at("firmware").contains("ft_motion") ? &run.at("firmware").at("ft_motion") : nullptr;
    if (std::string(mode) == "on") {
      REQUIRE(ft != nullptr);
      CHECK(ft->get<std::string>() == "active");
    } else if (std::string(mode) == "off") {
      REQUIRE(ft != nullptr);
      CHECK(ft->get<std::string>() == "built, inactive");
    } else {
      CHECK(ft == nullptr);
    }
    CHECK(tunekit::test::read_text(res.files.at(tunekit::protocols::RunFile::sim_received)).find("M493") !=
          std::string::npos);
  }
  // The export for the active machine: M493 instead of M593 / M900.
  CompensatorSettings s;
  s.pa_k_s = 0.045;
  s.pa_smooth_s = 0.02;
  s.shapers["x"] = {"mzv", 45.2, 0.1};
  s.shapers["y"] = {"zv", 38, 0.08};
  s.marlin_ft_motion_live = true;
  const std::string cfg = tunekit::read_file_bytes(std::string(TUNEKIT_DATASETS_DIR) + "/firmware/Configuration_adv.h");
  const auto r = export_config_text(ExportFirmware::marlin, cfg, "Configuration_adv.h", s);
  CHECK(r.gcode == "M493 S1 X8 Y1 A45.2 B38 I0.1 J0.08\nM493 P1 K0.045\nM500\n");
  CHECK(r.gcode.find("M593") == std::string::npos);
  CHECK(r.gcode.find("M900") == std::string::npos);
  // This file does not build FT_MOTION: not the running build's; its classic lines stay.
  CHECK_FALSE(r.changed());
  bool said = false;
  for (const auto& w : r.warnings) said |= w.find("does not enable FT_MOTION") != std::string::npos;
  CHECK(said);
}

TEST_CASE("calibrate on a simulated Marlin running FT_MOTION writes M493, on a classic one M593", "[machine][cli]") {
  for (const char* mode : {"on", "none"}) {
    INFO(mode);
    const std::string dir = tunekit::test::scratch_dir(std::string("calibrate_ft_") + mode) + "/run";
    const auto cli =
        tunekit::test::run_cli({"calibrate", "--machine", "sim", "--firmware", "marlin", "--skip-liquefier", "--out",
                                dir, "--sim", std::string("ft_motion=") + mode});
    INFO(cli.err);
    REQUIRE(cli.code == 0);
    const auto res = nlohmann::json::parse(tunekit::read_file_bytes(dir + "/results.json")).at("results");
    const std::string gcode = res.at("compensators").at("export").at("gcode").get<std::string>();
    INFO(gcode);
    if (std::string(mode) == "on") {
      CHECK(gcode.rfind("M493 S1 X1 ", 0) == 0);
      // The simulated build shapes no axis at the start: its report does not show its form.
      bool said = false;
      for (const auto& w : res.at("compensators").at("export").at("warnings"))
        said |= w.get<std::string>().find("did not show which letters") != std::string::npos;
      CHECK(said);
      CHECK(gcode.find("M593") == std::string::npos);
    } else {
      CHECK(gcode.find("M593 X F") != std::string::npos);
      CHECK(gcode.find("M493") == std::string::npos);
    }
  }
}

TEST_CASE("RepRapFirmware's files over its web server: addresses, M955 rate, finished runs, 404", "[machine]") {
  CHECK(parse_http_address("http://192.168.1.20").port == 80);
  CHECK(parse_http_address("http://duet.local:8080/").port == 8080);
  CHECK(parse_http_address("http://duet.local:8080/").host == "duet.local");
  CHECK_THROWS_AS(parse_http_address("https://duet.local"), InputError);
  CHECK_THROWS_AS(parse_http_address("http://duet.local:0"), InputError);
  CHECK(url_encode("0:/sys/accelerometer/a b.csv") == "0%3A%2Fsys%2Faccelerometer%2Fa%20b.csv");
  CHECK(*parse_m955_rate_hz({"Accelerometer 0 type LIS3DH with orientation 20 samples at 1344Hz with 10-bit "
                             "resolution, SPI frequency 2000000",
                             "ok"}) == Approx(1344));
  CHECK_FALSE(parse_m955_rate_hz({"Error: M955: Accelerometer not found"}));
  CHECK(rrf_accelerometer_file_complete("Sample,X,Y,Z\n0,0.1,0.2,1.0\nRate 1344, overflows 0\n"));
  CHECK(rrf_accelerometer_file_complete("Sample,X,Y,Z\nFailed to collect data from accelerometer\n"));
  CHECK_FALSE(rrf_accelerometer_file_complete("Sample,X,Y,Z\n0,0.1,0.2,1.0\n"));
  // The simulated board's server: a missing file is RRF's 404.
  SimPtyServer server(SimConfig::from_options({"firmware=rrf", "rrf_http=1"}));
  const auto addr = parse_http_address(server.http_url());
  const auto miss = http_get(addr, "/rr_download?name=" + url_encode("0:/sys/accelerometer/none.csv"),
                             std::chrono::milliseconds(3000));
  CHECK(miss.status == 404);
  CHECK(miss.reason == "file not found");
  CHECK_THROWS_AS(rrf_download(addr, "0:/sys/accelerometer/none.csv", std::chrono::milliseconds(3000)), MachineError);
}

TEST_CASE("axis-sweep on RepRapFirmware records with M956 and fetches the file over the board's web server",
          "[machine]") {
  const std::string dir = tunekit::test::scratch_dir("rrf_m956_fetch");
  RunOptions o;
  o.protocol = "axis-sweep";
  o.run_dir = dir + "/run";
  o.params = {{"freq_start_hz", 30}, {"freq_end_hz", 70}};
  tunekit::calibration::load_run_machine(o, "",
                                         {"firmware=rrf", "sensor_stream=0", "rrf_http=1", "accel_rate_hz=1344"});
  const auto res = run_experiment(o);
  REQUIRE(res.status == "complete");
  const std::string sent = tunekit::test::read_text(res.files.at(tunekit::protocols::RunFile::sim_received));
  const auto m955 = sent.find("M955 P0"), m956 = sent.find("M956 P0 S"), g1 = sent.find("G1 X");
  REQUIRE(m955 != std::string::npos);
  REQUIRE(m956 != std::string::npos);
  CHECK(m955 < m956);
  CHECK(sent.find("F\"tunekit_1.csv\"", m956) != std::string::npos);
  CHECK(sent.find("M4100") == std::string::npos);  // no tunekit stream on this board
  // The file as the board wrote it is kept, and reads as an RRF accelerometer file.
  const auto run = nlohmann::json::parse(tunekit::read_file_bytes(res.files.at(tunekit::protocols::RunFile::summary)));
  const std::string kept = res.run_dir + "/" + run.at("link").at("rrf_accelerometer_files").at(0).get<std::string>();
  const std::string bytes = tunekit::read_file_bytes(kept);
  CHECK(tunekit::ident::is_rrf_accelerometer_csv(bytes));
  CHECK(rrf_accelerometer_file_complete(bytes));
  // The accelerometer record the analysis reads, and the simulated X mode (48 Hz) in it.
  REQUIRE(res.files.count(tunekit::protocols::RunFile::accel));
  const auto cli =
      tunekit::test::run_cli({"resonance", res.files.at(tunekit::protocols::RunFile::accel), "--axis", "x", "--json"});
  INFO(cli.err);
  REQUIRE(cli.code == 0);
  const auto modes = nlohmann::json::parse(cli.out).at("results").at("axes").at("x").at("modes");
  REQUIRE(!modes.empty());
  CHECK(modes.at(0).at("freq_hz").get<double>() == Approx(48).epsilon(0.03));
  CHECK(g1 != std::string::npos);
}

TEST_CASE("serial-only RepRapFirmware is refused before heating or homing, with the reason", "[machine]") {
  const std::string dir = tunekit::test::scratch_dir("rrf_serial_only");
  RunOptions o;
  o.protocol = "axis-sweep";
  o.run_dir = dir + "/run";
  tunekit::calibration::load_run_machine(o, "", {"firmware=rrf", "sensor_stream=0"});  // no web server
  std::string why;
  try {
    run_experiment(o);
  } catch (const MachineError& e) {
    why = e.message();
  }
  CHECK(why.find("no way to read a file over USB serial") != std::string::npos);
  CHECK(why.find("[network] http") != std::string::npos);
  const std::string received = tunekit::test::read_text(o.run_dir + "/sim_received.gcode");
  for (const char* never : {"G28", "M109", "M956", "G1 "}) {
    INFO(never);
    CHECK(received.find(never) == std::string::npos);
  }
}
