// End-to-end tests of `tunekit run` against the simulated printer on a real pseudo-terminal:
// refusal before any byte, fault injection with exit code 3 and the partial journal kept,
// dry runs and help, and a fake Klipper API server (fake_klipper.hpp) streaming accelerometer data.
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <atomic>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "fake_klipper.hpp"
#include "test_support.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/sim/simulator.hpp"
#include "tunekit/machine/transport.hpp"

using tunekit::test::run_cli;
using tunekit::test::scratch_dir;
namespace fs = std::filesystem;

namespace {

std::size_t csv_rows(const std::string& path) {
  std::ifstream f(path);
  std::string line;
  std::size_t n = 0;
  while (std::getline(f, line))
    if (!line.empty() && line[0] != '#' && line[0] != 't') ++n;
  return n;
}

}  // namespace

TEST_CASE("run --help lists the protocols with parameters and units", "[machine]") {
  const auto r = run_cli({"run", "--help"});
  CHECK(r.code == 0);
  for (const char* s :
       {"liquefier-step", "liquefier-sine", "liquefier-chirp", "ring-print", "axis-sweep", "axis-rectangle",
        "feed_high_mm_s", "[mm/s]", "hz_per_sec", "[Hz/s]", "accel_per_hz", "[mm/s^2/Hz]", "--dry-run"})
    CHECK(r.out.find(s) != std::string::npos);
}

TEST_CASE("run --dry-run prints the checked G-code and sends nothing", "[machine]") {
  const auto dir = scratch_dir("machine_dry");
  const auto r = run_cli({"run", "liquefier-step", "--dry-run", "-p", "feed_high_mm_s=4", "--runs-root", dir});
  REQUIRE(r.code == 0);
  CHECK(r.out.find("G1 E12 F240") != std::string::npos);  // 4 mm/s for 3 s
  CHECK(r.out.find("M109 R210") != std::string::npos);    // waits from either side (Marlin M104_M109.cpp)
  CHECK(fs::is_empty(dir));
  const auto j = run_cli({"run", "axis-sweep", "--axis", "y", "--dry-run", "--json"});
  REQUIRE(j.code == 0);
  const auto env = nlohmann::json::parse(j.out);
  CHECK(env["results"]["gcode"].size() > 1000);
  CHECK(env["results"]["experiment"]["axis"] == "y");
}

TEST_CASE("the line test's lines all start alike: every prime follows a retraction", "[machine]") {
  const auto r = run_cli({"run", "line-steps", "--dry-run", "--json"});
  REQUIRE(r.code == 0);
  const auto env = nlohmann::json::parse(r.out);
  double e_net = 0;  // filament pushed by retractions and primes so far (mm)
  int primes = 0;
  for (const auto& line : env["results"]["gcode"]) {
    const std::string l = line.get<std::string>();
    const bool retract = l.find("; retract") != std::string::npos, prime = l.find("; prime") != std::string::npos;
    if (!retract && !prime) continue;
    const auto e = l.find(" E");
    REQUIRE(e != std::string::npos);
    e_net += std::stod(l.substr(e + 2));
    INFO(l);
    CHECK(e_net <= 1e-9);  // never more primed than retracted
    primes += prime;
  }
  CHECK(primes == 3);
}

TEST_CASE("a protocol over the profile's limits is refused before any byte is sent", "[machine]") {
  tunekit::sim::SimPtyServer server(tunekit::sim::SimConfig{});
  const auto dir = scratch_dir("machine_refused");
  const auto r = run_cli({"run", "liquefier-step", "--machine", tunekit::test::dataset("machines/sim.toml"), "--port",
                          server.path(), "-p", "feed_high_mm_s=100", "-p", "hotend_c=350", "-p", "accel_mm_s2=9000",
                          "--runs-root", dir});
  CHECK(r.code == 2);
  // All violations in one message.
  CHECK(r.err.find("filament feed 100") != std::string::npos);
  CHECK(r.err.find("volumetric flow") != std::string::npos);
  CHECK(r.err.find("hot-end temperature 350") != std::string::npos);
  CHECK(r.err.find("filament acceleration 9000") != std::string::npos);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  CHECK(server.sim().received().empty());
  CHECK(fs::is_empty(dir));
}

TEST_CASE("liquefier-step on the simulator writes a complete run directory", "[machine]") {
  const auto dir = scratch_dir("machine_step_run") + "/run";
  const auto r = run_cli({"run", "liquefier-step", "--machine", "sim", "--run-dir", dir, "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto env = nlohmann::json::parse(r.out);
  const auto& res = env["results"];
  CHECK(res["status"] == "complete");
  const std::string csv = res["files"]["load_cell"];
  CHECK(fs::path(csv).filename() == "step.csv");
  const auto table = tunekit::formats::read_csv(csv, {{}, "time"});
  CHECK(table.column("feed").values.size() == res["samples"]["load_cell"].get<std::size_t>());
  // 3 s settle + 2 cycles of 2 x 3 s at 200 Hz.
  CHECK(table.rows == Approx(15 * 200).epsilon(0.02));
  const auto stats = tunekit::test::read_json(dir + "/sim_stats.json");
  CHECK(stats["load_cell_samples_sent"].get<std::size_t>() == table.rows);
  // truth.json holds the truth the simulator ran with: the default (desktop) preset here.
  CHECK(tunekit::test::read_json(dir + "/truth.json")["liquefier"]["tau_s"] == tunekit::sim::SimConfig{}.tau_s);
  CHECK(tunekit::test::read_json(dir + "/truth.json")["preset"] == "desktop");
  CHECK(tunekit::test::read_json(dir + "/run.json")["status"] == "complete");
  const std::string journal = tunekit::test::read_text(dir + "/journal.jsonl");
  CHECK(journal.find("\"kind\":\"tx\"") != std::string::npos);
  CHECK(journal.find("FIRMWARE_NAME:Marlin") != std::string::npos);
}

TEST_CASE("garbled, dropped and late lines are recovered", "[machine]") {
  const auto base = scratch_dir("machine_recover");
  SECTION("garbled line: resend") {
    const auto r =
        run_cli({"run", "liquefier-step", "--run-dir", base + "/garble", "--sim", "fault=garble@8", "--json"});
    INFO(r.err);
    REQUIRE(r.code == 0);
    CHECK(nlohmann::json::parse(r.out)["results"]["link"]["resends"] == 1);
    CHECK(tunekit::test::read_text(base + "/garble/journal.jsonl").find("Resend: 7") != std::string::npos);
  }
  SECTION("dropped line: retry after the timeout") {
    const auto r = run_cli(
        {"run", "liquefier-step", "--run-dir", base + "/drop", "--sim", "fault=drop@9", "--timeout", "0.3", "--json"});
    INFO(r.err);
    REQUIRE(r.code == 0);
    CHECK(nlohmann::json::parse(r.out)["results"]["link"]["retries"] == 1);
  }
  SECTION("late ok: waited for") {
    const auto t0 = std::chrono::steady_clock::now();
    const auto r = run_cli({"run", "liquefier-step", "--run-dir", base + "/late", "--sim", "fault=late-ok@8:400",
                            "--timeout", "2", "--json"});
    REQUIRE(r.code == 0);
    CHECK(std::chrono::steady_clock::now() - t0 >= std::chrono::milliseconds(400));
    CHECK(nlohmann::json::parse(r.out)["results"]["link"]["retries"] == 0);
  }
}

TEST_CASE("a disconnect ends with exit 3 and keeps every sample received", "[machine]") {
  const auto dir = scratch_dir("machine_disconnect") + "/run";
  const auto r = run_cli({"run", "liquefier-step", "--run-dir", dir, "--sim", "fault=disconnect@11", "--timeout",
                          "2"});  // line 3 is M493 on Marlin
  CHECK(r.code == 3);
  CHECK(r.err.find("partial run is kept in") != std::string::npos);
  const auto stats = tunekit::test::read_json(dir + "/sim_stats.json");
  CHECK(stats["disconnected"] == true);
  const std::size_t sent = stats["load_cell_samples_sent"];
  CHECK(sent > 1000);  // the first two moves (6 s) ran before the fault
  CHECK(csv_rows(dir + "/step.csv") == sent);
  const auto run = tunekit::test::read_json(dir + "/run.json");
  CHECK(run["status"] == "failed");
  // The partial file is analyzable: the reader accepts it.
  CHECK(tunekit::formats::read_csv(dir + "/step.csv", {{}, "time"}).rows == sent);
}

TEST_CASE("a firmware error ends with exit 3 after the safe-state commands", "[machine]") {
  const auto dir = scratch_dir("machine_fw_error") + "/run";
  const auto r = run_cli({"run", "liquefier-step", "--run-dir", dir, "--sim", "fault=error@10"});
  CHECK(r.code == 3);
  CHECK(r.err.find("Thermal Runaway") != std::string::npos);
  const std::string rx = tunekit::test::read_text(dir + "/sim_received.gcode");
  const auto fault_at = rx.find("N9 ");  // the tenth line received carries N9 (N0 is M110)
  REQUIRE(fault_at != std::string::npos);
  const auto after = rx.substr(fault_at);
  CHECK(after.find("\nM410\n") != std::string::npos);
  CHECK(after.find("\nM104 S0\n") != std::string::npos);
  CHECK(after.find("\nM140 S0\n") != std::string::npos);
  CHECK(csv_rows(dir + "/step.csv") ==
        tunekit::test::read_json(dir + "/sim_stats.json")["load_cell_samples_sent"].get<std::size_t>());
}

using tunekit::test::FakeKlipper;

TEST_CASE("a Klipper API server's accelerometer stream is recorded and analyzed", "[machine]") {
  const auto dir = scratch_dir("machine_klipper");
  const std::string sock = dir + "/klippy_uds";
  // The fake server synthesises one x mode that is not the simulator's default (48 Hz, 0.08).
  const double f_mode = 52.5, zeta_mode = 0.06;
  FakeKlipper server(sock, tunekit::sim::SimConfig::from_options(
                               {"mode_x=" + std::to_string(f_mode) + ":" + std::to_string(zeta_mode)}));
  const auto r = run_cli({"run", "axis-sweep", "--axis", "x", "--machine", tunekit::test::dataset("machines/sim.toml"),
                          "--port", "unix:" + sock, "--run-dir", dir + "/run", "-p", "freq_start_hz=35", "-p",
                          "freq_end_hz=70", "-p", "hz_per_sec=3", "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto env = nlohmann::json::parse(r.out);
  const std::string accel = env["results"]["files"]["accel"];
  CHECK(fs::path(accel).filename().string().rfind("raw_data_x_", 0) == 0);
  CHECK(tunekit::test::read_text(accel).rfind("#time,accel_x,accel_y,accel_z\n", 0) == 0);
  CHECK(static_cast<long>(csv_rows(accel)) == server.samples_sent());
  CHECK(server.samples_sent() > 3200 * 4);
  // The profile names Marlin, the machine is Klipper: the sweep is built for Klipper.
  bool saw_sweep = false;
  for (const auto& s : server.scripts()) saw_sweep |= s.find("SET_VELOCITY_LIMIT ACCEL=") != std::string::npos;
  CHECK(saw_sweep);
  CHECK(server.unknown_commands().empty());
  // What was recorded is analyzed like a Klipper raw_data file: the mode the server synthesised.
  // (The sweep is slow, 3 Hz/s: a fast one drags the apparent peak upwards, ~0.9 % at 8 Hz/s.)
  const auto fit = run_cli({"resonance", accel, "--axis", "x", "--json"});
  INFO(fit.err);
  REQUIRE(fit.code == 0);
  const auto modes = nlohmann::json::parse(fit.out)["results"]["axes"]["x"]["modes"];
  REQUIRE(!modes.empty());
  CHECK(modes[0]["freq_hz"].get<double>() == Approx(f_mode).epsilon(0.01));
  CHECK(modes[0]["zeta"].get<double>() == Approx(zeta_mode).epsilon(0.20));
  // The toolhead's trapq was recorded beside the samples, and the modes were fitted against it.
  REQUIRE(env["results"]["files"].contains("commanded_motion"));
  const std::string motion = env["results"]["files"]["commanded_motion"];
  CHECK(fs::path(motion).parent_path() == fs::path(accel).parent_path());
  CHECK(csv_rows(motion) > 100);
  const auto res = nlohmann::json::parse(fit.out)["results"]["axes"]["x"];
  CHECK(res["fit"]["method"] == "output_error");
  INFO(res["modes"].dump());
  // The fake cuts each move into 1 ms pieces of mean acceleration, which moves a switch of the
  // acceleration by up to half a millisecond: f and zeta within 0.3 % and 3 %, not exactly.
  CHECK(modes[0]["freq_hz"].get<double>() == Approx(f_mode).epsilon(0.003));
  CHECK(modes[0]["zeta"].get<double>() == Approx(zeta_mode).epsilon(0.03));
}
