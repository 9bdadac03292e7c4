// Conditions a user can bring about from input, each answered with one plain line: a read-only
// output directory, a configuration whose name is near the file system's limit (its backup's
// name is shortened), a profile whose limits are not physical, an unknown command asked for
// its help; and text from a file (a profile's name, file names) never reaching G-code as live
// lines, for hostile strings of every kind.
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "test_support.hpp"

using tunekit::test::dataset;
using tunekit::test::read_text;
using tunekit::test::run_cli;
using tunekit::test::scratch_dir;
namespace fs = std::filesystem;

// The whole file in a namespace of its own: the test areas are unity builds, and other files
// have helpers of the same names.
namespace test_reliability_round3 {

/// Runs the tunekit executable as user nobody when the tests run as root (root writes anywhere).
tunekit::test::CliRun run_as_nobody(const std::string& args) {
  const std::string prefix = ::geteuid() == 0 ? "setpriv --reuid=65534 --regid=65534 --clear-groups " : "";
  return tunekit::test::run_exe_prefixed(prefix, args);
}

/// The error lines of stderr.
int error_lines(const std::string& err) {
  int n = 0;
  for (std::size_t p = 0; (p = err.find("tunekit: error: ", p)) != std::string::npos; ++p) ++n;
  return n;
}

/// The simulator's profile with the first line "KEY = ..." set to "KEY = VALUE".
std::string profile_with(const std::string& name, const std::string& key, const std::string& value) {
  std::string text = read_text(dataset("machines/sim.toml"));
  auto at = text.find("\n" + key + " = ");
  REQUIRE(at != std::string::npos);
  ++at;
  const auto end = text.find('\n', at);
  text.replace(at, end - at, key + " = " + value);
  return tunekit::test::write_scratch(name, text);
}

/// No line of `gcode` carries one of the hostile commands as a command: whatever a profile's or a
/// file's text holds stays after a comment marker (';') on its own line.
void check_no_live_injection(const std::string& gcode) {
  for (std::size_t b = 0, e; b < gcode.size(); b = e + 1) {
    e = gcode.find('\n', b);
    if (e == std::string::npos) e = gcode.size();
    const std::string line = gcode.substr(b, e - b);
    const std::string command = line.substr(0, line.find(';'));
    INFO(line);
    CHECK(command.find("M104 S300") == std::string::npos);
    CHECK(command.find("M140 S150") == std::string::npos);
    CHECK(command.find("M112") == std::string::npos);
  }
}

TEST_CASE("calibrate --out in a read-only directory is one plain line, not an internal error", "[safety]") {
  const std::string dir = scratch_dir("readonly_out");
  fs::create_directories(dir + "/ro");
  fs::permissions(dir + "/ro", fs::perms::owner_read | fs::perms::owner_exec | fs::perms::others_read |
                                   fs::perms::others_exec | fs::perms::group_read | fs::perms::group_exec);
  fs::permissions(dir, fs::perms::all);
  const auto r = run_as_nobody("calibrate --machine sim --skip-axes --out " + dir + "/ro/run");
  INFO(r.err);
  CHECK(r.code == 2);
  CHECK(error_lines(r.err) == 1);
  CHECK(r.err.find("internal error") == std::string::npos);
  CHECK(r.err.find("filesystem error") == std::string::npos);
  CHECK(r.err.find("Permission denied") != std::string::npos);
}

TEST_CASE("a configuration named near the file system's limit is written with a shortened backup name", "[safety]") {
  const std::string dir = scratch_dir("long_config_name");
  const std::string cfg = dir + "/" + std::string(250, 'c') + ".cfg";
  std::ofstream(cfg) << "[printer]\nkinematics: cartesian\n\n[extruder]\nstep_pin: PA1\npressure_advance: 0.02\n";
  const auto r = run_cli({"export", "-f", "klipper", "-c", cfg, "--pa-k", "0.031", "--write"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.err.find("internal error") == std::string::npos);
  CHECK(read_text(cfg).find("pressure_advance: 0.031") != std::string::npos);
  int backups = 0;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".bak") {
      ++backups;
      CHECK(e.path().filename().string().size() <= 255);
      CHECK(read_text(e.path().string()).find("pressure_advance: 0.02") != std::string::npos);
    }
  CHECK(backups == 1);
}

TEST_CASE("a filesystem error from input is told in plain words, never as an internal error", "[safety]") {
  const std::string dir = scratch_dir("missing_dir_out");
  // A run directory below a regular file: it cannot be created.
  std::ofstream(dir + "/file") << "x";
  const auto r = run_cli({"calibrate", "--machine", "sim", "--skip-axes", "--out", dir + "/file/run"});
  INFO(r.err);
  CHECK(r.code == 2);
  CHECK(error_lines(r.err) == 1);
  CHECK(r.err.find("internal error") == std::string::npos);
  CHECK(r.err.find("filesystem error") == std::string::npos);
}

TEST_CASE("profiles are range-checked at load: an infinite travel or a 1e9 degC hot end is refused", "[safety]") {
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"hotend_max_c", "1e9"}, {"max_mm", "inf"}, {"max_velocity_mm_s", "1e12"}}) {
    const std::string p = profile_with("range_profile.toml", from, to);
    for (const std::vector<std::string>& args :
         {std::vector<std::string>{"run", "liquefier-step", "--machine", p, "--dry-run"},
          std::vector<std::string>{"calibrate", "--machine", "sim", "--profile", p, "--out",
                                   scratch_dir("range_calibrate") + "/run"}}) {
      const auto r = run_cli(args);
      INFO(to << ": " << r.err);
      CHECK(r.code == 2);
      CHECK(error_lines(r.err) == 1);
    }
  }
}

TEST_CASE("'tunekit thermals --help' names an unknown command (exit 2), not the main help", "[safety]") {
  const auto r = run_cli({"thermals", "--help"});
  CHECK(r.code == 2);
  CHECK(r.err.find("unknown command 'thermals'") != std::string::npos);
  CHECK(r.out.empty());
  CHECK(run_cli({"step", "--help"}).code == 0);
  CHECK(run_cli({"--help"}).code == 0);
}

TEST_CASE("a profile's name never reaches the G-code as live lines, for hostile strings of every kind", "[safety]") {
  // The reproducer, then generated names: line breaks of each kind, other control characters,
  // G-code separators and comment markers around commands beyond the profile's limits.
  std::vector<std::string> names = {"x\nM104 S300\nM140 S150", "x\rM104 S300", "x\r\nM112"};
  std::mt19937 rng(63);
  const std::vector<std::string> pieces = {"\n", "\r", "\x0b", "\x0c",      "\x1b",      ";",    "(",
                                           ")",  "*",  "N5 ",  "M104 S300", "M140 S150", "M112", "\\n",
                                           "\"", "'",  "#",    "\x7f",      " "};
  for (int i = 0; i < 40; ++i) {
    std::string n = "p";
    for (int k = 0; k < 6; ++k) n += pieces[rng() % pieces.size()];
    names.push_back(n);
  }
  for (const auto& name : names) {
    std::string escaped;
    for (char c : name) {
      if (c == '"' || c == '\\') escaped += '\\';
      if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
        char buf[8];
        std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned char>(c));
        escaped += buf;
      } else {
        escaped += c;
      }
    }
    const std::string p = profile_with("hostile_name.toml", "name", "\"" + escaped + "\"");
    const auto r = run_cli({"run", "liquefier-step", "--machine", p, "--dry-run"});
    INFO("name: " << escaped << "\n" << r.err);
    if (r.code != 0) {
      CHECK(r.code == 2);  // refused as a whole: nothing printed
      CHECK(r.out.empty());
      continue;
    }
    check_no_live_injection(r.out);
  }
}

TEST_CASE("file names reach a configuration's comments only in a comment-safe form", "[safety][export]") {
  const std::string dir = scratch_dir("hostile_file_names");
  const std::string cfg = dir + "/config.g";
  // The line's trailing comment is where export puts its change note, naming the results file.
  std::ofstream(cfg) << "; RepRapFirmware\nM572 D0 S0.02 ; pressure advance\n";
  const std::string step = dir + "/x\nM104 S300\n.json";
  fs::copy_file(dataset("../tests/export/fixtures/step.json"), step);
  const auto r = run_cli({"export", "-f", "rrf", "-c", cfg, step, "--write"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  check_no_live_injection(read_text(cfg));
  CHECK(read_text(cfg).find("set by tunekit export from x?M104 S300?.json") != std::string::npos);
}

}  // namespace test_reliability_round3
