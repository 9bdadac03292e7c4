// Unit tests of the machine link: G-code framing, firmware identification, S-curve profiles,
// safety limits, the line protocol against the in-process simulator (with injected faults).
#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <cmath>
#include <thread>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/calibration/analyses/simulated_machine.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/firmware/dialect.hpp"
#include "tunekit/protocols/experiments.hpp"
#include "tunekit/machine/gcode.hpp"
#include "tunekit/machine/gcode_link.hpp"
#include "tunekit/machine/journal.hpp"
#include "tunekit/machine/profile_import.hpp"
#include "tunekit/protocols/runner.hpp"
#include "tunekit/protocols/safety.hpp"
#include "tunekit/sim/builtin_profile.hpp"
#include "tunekit/sim/simulator.hpp"
#include "tunekit/machine/trajectory.hpp"
#include "tunekit/machine/transport.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/formats/heater_log.hpp"

using namespace tunekit::protocols;
using namespace tunekit::machine;
using namespace tunekit::firmware;
using namespace tunekit::sim;

TEST_CASE("Marlin line numbers and checksums", "[machine]") {
  const std::string l = numbered_line(12, "G1 X10");
  int cs = 0;
  for (char c : std::string("N12 G1 X10")) cs ^= static_cast<unsigned char>(c);
  CHECK(l == "N12 G1 X10*" + std::to_string(cs));
  const auto s = split_numbered(l);
  REQUIRE(s.number);
  CHECK(*s.number == 12);
  CHECK(s.checksum_ok);
  CHECK(s.body == "G1 X10");
  std::string bad = l;
  bad[5] = 'Y';
  CHECK_FALSE(split_numbered(bad).checksum_ok);
}

TEST_CASE("G-code words, comments and extended commands", "[machine]") {
  const auto w = parse_gcode("N3 G1 X10 Y-5.5 E0.2 F3000 ; comment*99");
  REQUIRE(w);
  CHECK(w->command == "G1");
  CHECK(w->get("Y", 0) == Approx(-5.5));
  CHECK(w->get("F", 0) == Approx(3000));
  const auto k = parse_gcode("SET_VELOCITY_LIMIT ACCEL=4000");
  REQUIRE(k);
  CHECK(k->command == "SET_VELOCITY_LIMIT");
  CHECK(k->get("ACCEL", 0) == Approx(4000));
  CHECK_FALSE(parse_gcode("; only a comment"));
  GcodeInterpreter in;
  in.apply(*parse_gcode("M83"));
  in.apply(*parse_gcode("M204 S2500"));
  const auto m = in.apply(*parse_gcode("G1 E6 F120"));
  REQUIRE(m);
  CHECK(m->extruder_only());
  CHECK(m->feed_mm_s == Approx(2.0));
  CHECK(m->accel_mm_s2 == Approx(2500));
}

TEST_CASE("firmware identification from M115 reports", "[machine]") {
  CHECK(parse_m115({"FIRMWARE_NAME:Marlin 2.1.2.1 (Jan 1 2024) SOURCE_CODE_URL:github.com PROTOCOL_VERSION:1.0 "
                    "MACHINE_TYPE:Ender EXTRUDER_COUNT:1",
                    "Cap:EEPROM:1"})
            .firmware == Firmware::marlin);
  const auto k = parse_m115({"FIRMWARE_NAME:Klipper FIRMWARE_VERSION:v0.12.0-85"});
  CHECK(k.firmware == Firmware::klipper);
  CHECK(k.version == "v0.12.0-85");
  CHECK(parse_m115({"FIRMWARE_NAME: RepRapFirmware for Duet 3 MB6HC FIRMWARE_VERSION: 3.5.1 ELECTRONICS: Duet 3"})
            .firmware == Firmware::reprapfirmware);
  CHECK(parse_m115({"FIRMWARE_NAME:Prusa-Firmware-Buddy 5.1.0 (Github) SOURCE_CODE_URL:x"}).firmware ==
        Firmware::prusa);
  const auto sim = parse_m115(
      {"FIRMWARE_NAME:Marlin 2.1.2 (tunekit-sim 0.1.0) MACHINE_TYPE:tunekit-sim", "Cap:TUNEKIT_SENSOR_STREAM:1"});
  CHECK(sim.sensor_stream());
  CHECK(Dialect(Firmware::klipper).set_accel(3000) == "SET_VELOCITY_LIMIT ACCEL=3000");
  CHECK(Dialect(Firmware::reprapfirmware).set_accel(3000) == "M204 P3000 T3000");
}

TEST_CASE("jerk-limited profiles reach the distance within the limits", "[machine]") {
  const double a = 3000, j = 1e6;
  const auto p = Profile::move(20, 0, 100, 0, a, j);
  CHECK(p.distance_mm() == Approx(20).epsilon(1e-6));
  CHECK(p.exit_speed() == Approx(0).margin(1e-9));
  CHECK(p.peak_accel() <= a * (1 + 1e-9));
  // Jerk is bounded: acceleration changes by at most j * dt.
  double prev = p.at(0).accel_mm_s2, worst = 0;
  for (double t = 1e-4; t <= p.duration_s(); t += 1e-4) {
    const double acc = p.at(t).accel_mm_s2;
    worst = std::max(worst, std::abs(acc - prev) / 1e-4);
    prev = acc;
  }
  CHECK(worst <= j * 1.01);
  // A short move never reaches its speed and still ends at rest.
  const auto s = Profile::move(0.2, 0, 300, 0, a, j);
  CHECK(s.distance_mm() == Approx(0.2).epsilon(1e-4));
  CHECK(s.at(s.duration_s() / 2).vel_mm_s < 300);
  // A blended move keeps its exit speed.
  const auto b = Profile::move(5, 1, 3, 3, a, j);
  CHECK(b.exit_speed() == Approx(3));
}

TEST_CASE("a short move from rest to rest peaks where the search for its peak speed does", "[machine]") {
  // The rest-to-rest case is solved in closed form; entering at 1e-9 mm/s takes the search.
  for (const double a : {500.0, 3000.0, 20000.0})
    for (const double j : {1e4, 1e6, 1e8})
      for (const double d : {1e-4, 0.01, 0.4, 3.0, 40.0}) {
        INFO("a " << a << " j " << j << " d " << d);
        const auto closed = Profile::move(d, 0, 300, 0, a, j);
        const auto searched = Profile::move(d, 1e-9, 300, 0, a, j);
        CHECK(closed.distance_mm() == Approx(d).epsilon(1e-9));
        CHECK(closed.exit_speed() == Approx(0).margin(1e-12));
        CHECK(closed.duration_s() == Approx(searched.duration_s()).epsilon(1e-6));
        CHECK(Profile::move_duration_s(d, 0, 300, 0, a, j) == Approx(closed.duration_s()).epsilon(1e-12));
        CHECK(Profile::move_duration_s(d, 1e-9, 300, 0, a, j) == Approx(searched.duration_s()).epsilon(1e-12));
        CHECK(closed.at(closed.duration_s() / 2).vel_mm_s ==
              Approx(searched.at(searched.duration_s() / 2).vel_mm_s).epsilon(1e-6));
      }
}

TEST_CASE("safety check lists every violation at once", "[machine]") {
  const auto profile = builtin_sim_profile();
  const std::vector<std::string> g{"G28", "M109 S400", "M204 S20000", "G1 X500 F30000", "M83", "G1 E100 F6000"};
  const auto v = check_protocol(g, profile, {"load_cell", "camera"});
  std::string all;
  for (const auto& x : v) all += x.what + "\n";
  CHECK(all.find("camera") != std::string::npos);
  CHECK(all.find("hot-end temperature 400") != std::string::npos);
  CHECK(all.find("x position 500") != std::string::npos);
  CHECK(all.find("x speed 500") != std::string::npos);
  CHECK(all.find("x acceleration 20000") != std::string::npos);
  CHECK(all.find("filament feed 100") != std::string::npos);
  CHECK(all.find("volumetric flow") != std::string::npos);
  CHECK(all.find("filament acceleration 20000") != std::string::npos);
  CHECK(v.size() >= 8);
  CHECK_THROWS_AS(require_within_limits(g, profile, {}), tunekit::InputError);
  // Every built-in protocol passes with its defaults on the simulator's profile.
  for (const auto& spec : protocol_specs()) {
    const auto e = build_experiment(spec.name, {}, "x", profile, Dialect(Firmware::marlin));
    INFO(spec.name);
    CHECK(check_protocol(e.gcode, profile, e.sensors).empty());
    CHECK(e.estimated_duration_s > 0);
  }
  CHECK_THROWS_AS(build_experiment("liquefier-step", {{"no_such_param", 1}}, "x", profile, Dialect()),
                  tunekit::InputError);
}

namespace {

/// An in-process simulator on one end of a socket pair, the link on the other.
struct InProcess {
  explicit InProcess(std::vector<std::string> opts)
      : sim(SimConfig::from_options(opts)),
        pair(make_transport_pair()),
        thread([this] { serve_simulator(sim, *pair.second, stop); }) {}
  ~InProcess() {
    stop = true;
    thread.join();
  }
  Simulator sim;
  std::pair<std::unique_ptr<Transport>, std::unique_ptr<Transport>> pair;
  std::atomic<bool> stop{false};
  std::thread thread;
};

}  // namespace

TEST_CASE("line protocol recovers from a garbled line with Resend", "[machine]") {
  InProcess ip({"fault=garble@3"});
  Journal j(tunekit::test::scratch_dir("machine_link_garble"));
  GcodeLink link(*ip.pair.first, &j, {std::chrono::milliseconds(2000), 2, true});
  link.reset_line_numbers();  // line 1
  link.send("M83");           // line 2
  link.send("G1 E1 F60");     // line 3: garbled, resent
  link.send("M400");
  CHECK(link.stats().resends == 1);
  const auto rx = ip.sim.received();
  REQUIRE(rx.size() == 5);
  CHECK(rx[2] == rx[3]);  // the same numbered line arrived twice
}

TEST_CASE("line protocol hands Marlin's temperature auto-reports between ok replies to the reader", "[machine]") {
  InProcess ip({});
  GcodeLink link(*ip.pair.first, nullptr, {std::chrono::milliseconds(2000), 1, true});
  std::vector<std::string> reports;
  link.on_line = [&](std::string_view l) {
    if (l.find(" T:") != 0) return false;
    reports.emplace_back(l);
    return true;
  };
  link.reset_line_numbers();
  for (const char* l : {"M104 S200", "M155 S1", "G4 P3500"}) CHECK(link.send(l).empty());
  CHECK(reports.size() == 3);  // one a second, none taken for an ok
  link.send("M105");           // its own report is the "ok T:..." reply, not an auto-report
  link.send("M155 S0");
  link.send("G4 P2000");
  CHECK(reports.size() == 3);
  const auto log = tunekit::formats::read_marlin_temperature_reports(reports[2], 1.0);
  CHECK(log.target_c.front() == 200);
}

TEST_CASE("line protocol re-sends a dropped line after the timeout", "[machine]") {
  InProcess ip({"fault=drop@2"});
  GcodeLink link(*ip.pair.first, nullptr, {std::chrono::milliseconds(200), 2, true});
  link.reset_line_numbers();
  link.send("M83");  // dropped once, then answered
  link.send("M400");
  CHECK(link.stats().retries == 1);
}

TEST_CASE("late ok within the timeout is waited for", "[machine]") {
  InProcess ip({"fault=late-ok@2:300"});
  GcodeLink link(*ip.pair.first, nullptr, {std::chrono::milliseconds(1500), 1, true});
  link.reset_line_numbers();
  const auto t0 = std::chrono::steady_clock::now();
  link.send("M83");
  CHECK(std::chrono::steady_clock::now() - t0 >= std::chrono::milliseconds(290));
  CHECK(link.stats().retries == 0);
}

TEST_CASE("firmware errors and silence are MachineErrors", "[machine]") {
  {
    InProcess ip({"fault=error@2"});
    GcodeLink link(*ip.pair.first, nullptr, {std::chrono::milliseconds(1000), 1, true});
    link.reset_line_numbers();
    try {
      link.send("M83");
      FAIL("no error");
    } catch (const tunekit::MachineError& e) {
      CHECK(std::string(e.message()).find("Thermal Runaway") != std::string::npos);
      CHECK(static_cast<int>(e.code()) == 3);
    }
  }
  {
    InProcess ip({"fault=drop@2", "fault=drop@3"});
    GcodeLink link(*ip.pair.first, nullptr, {std::chrono::milliseconds(100), 1, true});
    link.reset_line_numbers();
    CHECK_THROWS_AS(link.send("M83"), tunekit::MachineError);
  }
}

namespace {

std::vector<std::string> sweep_lines(int n) {
  std::vector<std::string> lines;
  for (int i = 0; i < n; ++i) lines.push_back("G1 X" + std::to_string(100 + i % 20) + " F6000");
  return lines;
}

/// The most lines the journal shows sent and not yet answered by an "ok".
int most_unanswered(const std::string& journal_path) {
  std::ifstream f(journal_path);
  std::string line;
  int in_flight = 0, most = 0;
  while (std::getline(f, line)) {
    const auto rec = nlohmann::json::parse(line);
    if (rec["kind"] == "tx") most = std::max(most, ++in_flight);
    if (rec["kind"] == "rx" && rec["line"] == "ok") --in_flight;
  }
  return most;
}

/// Sends 40 lines ahead (window 8) where the run must fail; returns the MachineError's message
/// (exit code 3 checked).
std::string pipelined_failure(GcodeLink& link) {
  link.reset_line_numbers();
  try {
    link.send_pipelined(sweep_lines(40), 8);
  } catch (const tunekit::MachineError& e) {
    CHECK(static_cast<int>(e.code()) == 3);
    return e.message();
  }
  FAIL("no error");
  return {};
}

}  // namespace

TEST_CASE("lines sent ahead to Klipper arrive once each and in order, never more than the window unanswered",
          "[machine]") {
  InProcess ip({"firmware=klipper"});
  const auto dir = tunekit::test::scratch_dir("machine_link_ahead");
  {
    Journal j(dir);
    GcodeLink link(*ip.pair.first, &j, {std::chrono::milliseconds(2000), 2, true});
    link.reset_line_numbers();  // N0, answered before the run below
    link.send_pipelined(sweep_lines(300), 8);
    CHECK(link.stats().lines_sent == 301);
  }
  const auto rx = ip.sim.received();
  REQUIRE(rx.size() == 301);
  for (std::size_t i = 1; i < rx.size(); ++i) CHECK(rx[i].rfind("N" + std::to_string(i) + " G1 X", 0) == 0);
  CHECK(most_unanswered(dir + "/journal.jsonl") == 8);  // sent ahead, and no further than the window
}

TEST_CASE("a Klipper that stops answering lines sent ahead ends the run and gets no line twice", "[machine]") {
  InProcess ip({"firmware=klipper", "fault=late-ok@6:2000"});
  GcodeLink link(*ip.pair.first, nullptr, {std::chrono::milliseconds(200), 3, true});
  CHECK(pipelined_failure(link).find("not sent again") != std::string::npos);
  CHECK(link.stats().retries == 0);
  const auto rx = ip.sim.received();
  CHECK(std::set<std::string>(rx.begin(), rx.end()).size() == rx.size());
}

TEST_CASE("a firmware error among lines sent ahead ends the run with that error", "[machine]") {
  InProcess ip({"firmware=klipper", "fault=error@5"});
  GcodeLink link(*ip.pair.first, nullptr, {std::chrono::milliseconds(1000), 1, true});
  const std::string why = pipelined_failure(link);
  CHECK(why.find("Thermal Runaway") != std::string::npos);
  CHECK(why.find("sent ahead") != std::string::npos);
}

TEST_CASE("simulated liquefier follows its first-order truth", "[machine]") {
  Simulator sim(
      SimConfig::from_options({"force_noise_N=0", "theta_s=0.05", "tau_s=0.3", "tau_flow_exponent=0", "K=2"}));
  std::vector<std::pair<double, double>> samples;  // (t, force)
  std::string out;
  const Simulator::Emit emit = [&](std::string_view s) { out += s; };
  for (const char* l : {"M83", "M204 S3000", "M4100 L1", "G1 E10 F120", "M400"}) sim.handle_line(l, emit);
  // Parse the stream: steady state K * 2 mm/s + offset after 5 tau.
  double last_force = 0, force_at_tau = -1;
  std::size_t pos = 0;
  while ((pos = out.find("echo:TKL ", pos)) != std::string::npos) {
    double t, u, f;
    REQUIRE(std::sscanf(out.c_str() + pos + 9, "%lf %lf %lf", &t, &u, &f) == 3);
    if (force_at_tau < 0 && t >= 0.05 + 0.3) force_at_tau = f;
    last_force = f;
    pos += 9;
  }
  CHECK(last_force == Approx(0.5 + 2 * 2).epsilon(0.01));
  // One time constant after the dead time: 63 % of the step.
  CHECK((force_at_tau - 0.5) / 4.0 == Approx(1 - std::exp(-1.0)).margin(0.03));
  CHECK(sim.load_cell_samples_sent() > 900);
}

TEST_CASE("the simulated Marlin answers M155 with temperature auto-reports on its own clock", "[machine]") {
  Simulator sim(SimConfig::from_options({}));
  std::string out;
  const Simulator::Emit emit = [&](std::string_view s) { out += s; };
  sim.handle_line("M115", emit);
  CHECK(out.find("Cap:AUTOREPORT_TEMP:1") != std::string::npos);
  const auto reports = [&] {
    std::size_t n = 0;
    for (std::size_t p = out.find("\n T:"); p != std::string::npos; p = out.find("\n T:", p + 1)) ++n;
    return n;
  };
  out.clear();
  for (const char* l : {"M104 S200", "M155 S1", "G4 P5500"}) sim.handle_line(l, emit);
  CHECK(reports() == 5);  // one a second of machine time, the first a second after M155
  const auto log = tunekit::formats::read_marlin_temperature_reports(out, 1.0);
  REQUIRE(log.t_s.size() == 5);
  for (std::size_t i = 0; i < 5; ++i) {
    CHECK(log.target_c[i] == 200);
    CHECK(log.duty[i] > 0);  // heating from the ambient
  }
  CHECK(log.temp_c.back() > log.temp_c.front());
  out.clear();
  for (const char* l : {"M155 S0", "G4 P3000"}) sim.handle_line(l, emit);
  CHECK(reports() == 0);
  for (const char* l : {"M155 S200", "G4 P61000"}) sim.handle_line(l, emit);
  CHECK(reports() == 1);  // at most 60 s apart

  Simulator without(SimConfig::from_options({"autoreport_temp=0"}));
  out.clear();
  for (const char* l : {"M115", "M155 S1", "G4 P3000"}) without.handle_line(l, emit);
  CHECK(out.find("Cap:AUTOREPORT_TEMP:0") != std::string::npos);
  CHECK(out.find("echo:Unknown command: \"M155 S1\"") != std::string::npos);
  CHECK(reports() == 0);
}

TEST_CASE("physics liquefier: gain and time constant depend on the flow", "[machine]") {
  const auto truth = SimConfig::from_options({"liquefier=physics"}).truth();
  const auto& pts = truth["liquefier"]["operating_points"];
  REQUIRE(pts.size() >= 3);
  CHECK(pts[0]["tau_local_s"].get<double>() > 1.2 * pts[3]["tau_local_s"].get<double>());
  CHECK(pts[0]["K_local"].get<double>() != Approx(pts[3]["K_local"].get<double>()));
  Simulator sim(SimConfig::from_options({"liquefier=physics", "force_noise_N=0"}));
  std::string out;
  const Simulator::Emit emit = [&](std::string_view s) { out += s; };
  for (const char* l : {"M83", "M4100 L1", "G1 E20 F120", "M400"}) sim.handle_line(l, emit);
  const auto last = out.rfind("echo:TKL ");
  double t, u, f;
  REQUIRE(std::sscanf(out.c_str() + last + 9, "%lf %lf %lf", &t, &u, &f) == 3);
  CHECK(f == Approx(pts[2]["force_N"].get<double>()).epsilon(0.02));  // 2 mm/s operating point
}

TEST_CASE("simulator options are validated", "[machine]") {
  CHECK_THROWS_AS(SimConfig::from_options({"nonsense=1"}), tunekit::InputError);
  CHECK_THROWS_AS(SimConfig::from_options({"fault=melt@3"}), tunekit::InputError);
  CHECK_THROWS_AS(SimConfig::from_options({"mode_x=48"}), tunekit::InputError);
  const auto c = SimConfig::from_options({"mode_x=48:0.08:0.7,95:0.05:0.3", "fault=late-ok@4:250"});
  REQUIRE(c.modes.at("x").size() == 2);
  CHECK(c.faults.at(0).delay_ms == Approx(250));
}

TEST_CASE("the built-in simulator profile is datasets/machines/sim.toml", "[machine]") {
  // The file tunekit-sim --profile and calibrate --machine sim name; built in at compile time.
  const std::string path = tunekit::test::dataset("machines/sim.toml");
  CHECK(builtin_sim_profile_toml() == tunekit::test::read_text(path));
  const auto a = builtin_sim_profile();
  auto b = load_machine_profile(path);
  CHECK(a.source_path == "<built-in simulated printer profile>");
  b.source_path = a.source_path;  // every value alike, only the file's name differs
  CHECK(machine_profile_toml(a) == machine_profile_toml(b));
  CHECK(a.name == b.name);
  CHECK(a.axes.at("x").max_accel_mm_s2 == b.axes.at("x").max_accel_mm_s2);
  CHECK(a.extruder.max_flow_mm3_s == b.extruder.max_flow_mm3_s);
  CHECK(a.temperature.hotend_max_c == b.temperature.hotend_max_c);
  CHECK(a.sensors.load_cell == b.sensors.load_cell);
}

TEST_CASE("every protocol has one entry in the protocol table, found by its id and by its name", "[machine]") {
  const Protocol all[] = {Protocol::liquefier_step,  Protocol::liquefier_flow_sweep, Protocol::liquefier_sine,
                          Protocol::liquefier_chirp, Protocol::ring_print,           Protocol::line_steps,
                          Protocol::axis_sweep,      Protocol::axis_rectangle,       Protocol::test_pattern,
                          Protocol::heater_identify};
  REQUIRE(protocol_specs().size() == std::size(all));
  for (const Protocol id : all) {
    const auto& spec = protocol_spec(id);
    CHECK(spec.id == id);
    CHECK(to_string(id) == spec.name);
    CHECK(protocol_spec(spec.name).id == id);
  }
  CHECK(to_string(Protocol::liquefier_flow_sweep) == "liquefier-flow-sweep");
}

TEST_CASE("a run's files are listed under their roles' names, in run.json's order", "[machine]") {
  RunFiles files{{RunFile::truth, "t.json"},
                 {RunFile::load_cell, "step.csv"},
                 {RunFile::accel, "a.csv"},
                 {RunFile::commanded_motion, "m.csv"}};
  const auto j = to_json(files);
  CHECK(j.dump() == R"({"accel":"a.csv","commanded_motion":"m.csv","load_cell":"step.csv","truth":"t.json"})");
  // The map's order is the names' order, as run.json (a sorted JSON object) lists them.
  for (const RunFile f : {RunFile::commanded_accel, RunFile::feed_track, RunFile::gcode, RunFile::journal,
                          RunFile::sim_received, RunFile::summary})
    files[f] = "x";
  REQUIRE(files.size() == 10);
  std::vector<std::string> names;
  for (const auto& [file, path] : files) names.emplace_back(to_string(file));
  CHECK(std::is_sorted(names.begin(), names.end()));
  CHECK(std::set<std::string>(names.begin(), names.end()).size() == names.size());
  CHECK(to_string(RunFile::commanded_accel) == "commanded_accel");
  CHECK(to_string(RunFile::sim_received) == "sim_received");
}

TEST_CASE("run_experiment (C++ API) runs protocols on the simulator over a pseudo-terminal", "[machine]") {
  const auto base = tunekit::test::scratch_dir("machine_api");
  RunOptions o;
  o.protocol = "liquefier-step";
  o.run_dir = base + "/step";
  tunekit::calibration::load_run_machine(o, "", {});
  const auto r = run_experiment(o);
  CHECK(r.status == "complete");
  const auto t = tunekit::formats::read_csv(r.files.at(tunekit::protocols::RunFile::load_cell), {{}, "time"});
  CHECK(t.rows == Approx(3000).epsilon(0.02));
  // The force settles at offset + K * feed on each plateau.
  const auto& f = t.column("force").values;
  const auto& u = t.column("feed").values;
  CHECK(u[590] == Approx(1.0));
  CHECK(f[590] == Approx(0.5 + 3.5 * 1.0).epsilon(0.02));
  CHECK(u[1180] == Approx(3.0));
  CHECK(f[1180] == Approx(0.5 + 3.5 * 3.0).epsilon(0.02));

  RunOptions s;
  s.protocol = "axis-sweep";
  s.axis = "x";
  s.run_dir = base + "/sweep";
  s.params = {{"freq_start_hz", 30}, {"freq_end_hz", 70}, {"hz_per_sec", 8}};
  tunekit::calibration::load_run_machine(s, "", {});
  const auto rs = run_experiment(s);
  const auto a = tunekit::formats::read_csv(rs.files.at(tunekit::protocols::RunFile::accel), {{}, "time"});
  CHECK(a.rows == Approx(3200 * (5 + 0.6)).epsilon(0.05));
  const auto c = tunekit::formats::read_csv(rs.files.at(tunekit::protocols::RunFile::commanded_accel), {{}, "time"});
  CHECK(c.rows == a.rows);
  double peak = 0;
  for (double v : c.column("accel_x").values) peak = std::max(peak, std::abs(v));
  CHECK(peak == Approx(60 * 70).epsilon(0.05));  // accel_per_hz * f at the end of the sweep
}

namespace {
std::string read_all(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}
}  // namespace

TEST_CASE("run_experiment: a disconnect is exit 3 and the journal keeps every sample", "[machine]") {
  RunOptions o;
  o.protocol = "liquefier-step";
  o.run_dir = tunekit::test::scratch_dir("machine_api_disconnect") + "/run";
  tunekit::calibration::load_run_machine(o, "",
                                         {"fault=disconnect@11"});  // N0 M110, M115, M493 (Marlin), then the protocol
  o.link.timeout = std::chrono::milliseconds(2000);
  try {
    run_experiment(o);
    FAIL("no error");
  } catch (const tunekit::MachineError& e) {
    CHECK(static_cast<int>(e.code()) == 3);
  }
  const auto stats = nlohmann::json::parse(read_all(o.run_dir + "/sim_stats.json"));
  const std::size_t sent = stats["load_cell_samples_sent"];
  CHECK(sent > 1000);
  CHECK(tunekit::formats::read_csv(o.run_dir + "/step.csv", {{}, "time"}).rows == sent);
  CHECK(nlohmann::json::parse(read_all(o.run_dir + "/run.json"))["status"] == "failed");
}

TEST_CASE("run_experiment: a firmware error is exit 3 after the safe-state commands", "[machine]") {
  RunOptions o;
  o.protocol = "liquefier-step";
  o.run_dir = tunekit::test::scratch_dir("machine_api_error") + "/run";
  tunekit::calibration::load_run_machine(o, "", {"fault=error@10"});
  CHECK_THROWS_AS(run_experiment(o), tunekit::MachineError);
  const std::string rx = read_all(o.run_dir + "/sim_received.gcode");
  const auto at = rx.find("N9 ");
  REQUIRE(at != std::string::npos);
  const auto after = rx.substr(at);
  CHECK(after.find("\nM410\n") != std::string::npos);
  CHECK(after.find("\nM104 S0\n") != std::string::npos);
  CHECK(after.find("\nM140 S0\n") != std::string::npos);
  const auto stats = nlohmann::json::parse(read_all(o.run_dir + "/sim_stats.json"));
  CHECK(tunekit::formats::read_csv(o.run_dir + "/step.csv", {{}, "time"}).rows ==
        stats["load_cell_samples_sent"].get<std::size_t>());
}

TEST_CASE("run_experiment: garbled and dropped lines are recovered", "[machine]") {
  RunOptions o;
  o.protocol = "liquefier-step";
  o.run_dir = tunekit::test::scratch_dir("machine_api_recover") + "/run";
  tunekit::calibration::load_run_machine(o, "", {"fault=garble@8", "fault=drop@11"});
  o.link.timeout = std::chrono::milliseconds(300);
  const auto r = run_experiment(o);
  CHECK(r.summary["link"]["resends"] == 1);
  CHECK(r.summary["link"]["retries"] == 1);
  CHECK(tunekit::formats::read_csv(r.files.at(tunekit::protocols::RunFile::load_cell), {{}, "time"}).rows ==
        Approx(3000).epsilon(0.02));
}

TEST_CASE("run_experiment: over-limit protocols are refused before the simulator hears anything", "[machine]") {
  SimPtyServer server(SimConfig{});
  RunOptions o;
  o.protocol = "liquefier-step";
  o.machine = tunekit::test::dataset("machines/sim.toml");
  o.port = server.path();
  o.run_dir = tunekit::test::scratch_dir("machine_api_refused") + "/run";
  tunekit::calibration::load_run_machine(o, "", {});
  o.params = {{"feed_high_mm_s", 100}, {"hotend_c", 350}};
  try {
    run_experiment(o);
    FAIL("not refused");
  } catch (const tunekit::InputError& e) {
    CHECK(e.message().find("filament feed 100") != std::string::npos);
    CHECK(e.message().find("hot-end temperature 350") != std::string::npos);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  CHECK(server.sim().received().empty());
  CHECK_FALSE(std::filesystem::exists(o.run_dir));
}

TEST_CASE("simulator presets: a desktop direct-drive default and the PEEK liquefier of the thesis by name",
          "[machine]") {
  const auto desktop = SimConfig{}.truth();
  CHECK(desktop.at("preset") == "desktop");
  // Tens of milliseconds, falling as the flow rises; a dead time; axis modes of a desktop machine.
  const auto& points = desktop.at("liquefier").at("operating_points");
  REQUIRE(points.size() >= 2);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double tau = points[i].at("tau_local_s").get<double>();
    CHECK(tau > 0.01);
    CHECK(tau < 0.1);
    if (i > 0) CHECK(tau < points[i - 1].at("tau_local_s").get<double>());
  }
  CHECK(desktop.at("liquefier").at("theta_s").get<double>() > 0);
  for (const char* axis : {"x", "y"}) {
    const auto& mode = desktop.at("axes").at(axis).at("modes")[0];
    CHECK(mode.at("freq_hz").get<double>() >= 40);
    CHECK(mode.at("freq_hz").get<double>() <= 70);
    CHECK(mode.at("zeta").get<double>() >= 0.05);
    CHECK(mode.at("zeta").get<double>() <= 0.1);
  }
  // The PEEK preset: Bellini's 0.45 s whatever the flow; later options change it, in any order.
  const auto peek = SimConfig::from_options({"theta_s=0.05", "preset=peek"});
  CHECK(peek.tau_at_feed(0.5) == 0.45);
  CHECK(peek.tau_at_feed(5) == 0.45);
  CHECK(peek.theta_s == 0.05);
  CHECK(peek.modes.at("y")[0].freq_hz == 37);
  CHECK_THROWS_AS(SimConfig::from_options({"preset=bowden"}), tunekit::InputError);
}
