// CLI conventions: help lists every subcommand, exit codes, deterministic JSON envelope.
#include <sys/stat.h>

#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/calibration/results/envelope.hpp"

using tunekit::test::run_cli;
using tunekit::test::run_exe;
using tunekit::test::write_scratch;

TEST_CASE("tunekit --help lists every subcommand with one line each") {
  const auto r = run_cli({"--help"});
  CHECK(r.code == 0);
  for (const char* name : {"step", "freq", "rheo", "nozzle", "resonance", "shaper", "linewidth", "run", "export",
                           "calibrate", "report", "batch", "ports", "inspect"}) {
    INFO(name);
    CHECK(r.out.find(std::string("\n  ") + name + " ") != std::string::npos);
  }
}

TEST_CASE("usage errors exit 2, no subcommand exits 2") {
  CHECK(run_cli({}).code == 2);
  CHECK(run_cli({"no-such-command"}).code == 2);
  CHECK(run_cli({"inspect"}).code == 2);
}

TEST_CASE("the executable separates results (stdout) from errors (stderr) and sets its exit status") {
  const auto bad = run_exe("inspect /nonexistent.csv");
  CHECK(bad.code == 2);
  CHECK(bad.out.empty());
  CHECK(bad.err.rfind("tunekit: error: /nonexistent.csv: cannot open", 0) == 0);
  const auto path = write_scratch("exe_ok.csv", "time,y\n0,1\n1,2\n");
  const auto ok = run_exe("inspect " + path + " --json");
  CHECK(ok.code == 0);
  CHECK(nlohmann::json::parse(ok.out)["results"]["rows"] == 2);
}

TEST_CASE("the JSON envelope carries schema, tool, command, options and input hashes, byte-identical across runs") {
  const auto path = write_scratch("envelope.csv", "time,y\n0,1\n1,2\n");
  const auto a = run_cli({"inspect", path, "--time", "time", "--json"});
  const auto b = run_cli({"inspect", path, "--time", "time", "--json"});
  REQUIRE(a.code == 0);
  CHECK(a.out == b.out);
  const auto j = nlohmann::json::parse(a.out);
  CHECK(j["schema_version"] == 1);
  CHECK(j["tool"]["name"] == "tunekit");
  CHECK(j["command"] == "inspect");
  CHECK(j["options"]["time_column"] == "time");
  CHECK(j["inputs"][0]["path"] == path);
  CHECK(j["inputs"][0]["sha256"] == tunekit::calibration::sha256_hex("time,y\n0,1\n1,2\n"));
  CHECK(j["results"]["time"]["sample_rate_hz"] == 1.0);
}

TEST_CASE("SHA-256 matches the FIPS 180-2 test vector") {
  CHECK(tunekit::calibration::sha256_hex("abc") == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

TEST_CASE("the output option writes the same envelope to a file") {
  const auto path = write_scratch("out_src.csv", "time,y\n0,1\n1,2\n");
  const auto out = tunekit::test::scratch_dir("output") + "/r.json";
  const auto r = run_cli({"inspect", path, "--json", "-o", out});
  REQUIRE(r.code == 0);
  std::ifstream f(out);
  std::stringstream ss;
  ss << f.rdbuf();
  CHECK(ss.str() == r.out);
}

namespace {

// The permission bits of `path`.
mode_t file_mode(const std::string& path) {
  struct stat st {};
  REQUIRE(::stat(path.c_str(), &st) == 0);
  return st.st_mode & 07777;
}

// Sets the process umask for one scope.
struct ScopedUmask {
  explicit ScopedUmask(mode_t m) : saved(::umask(m)) {}
  ~ScopedUmask() { ::umask(saved); }
  ScopedUmask(const ScopedUmask&) = delete;
  ScopedUmask& operator=(const ScopedUmask&) = delete;
  mode_t saved;
};

}  // namespace

TEST_CASE("outputs honour the umask, a replaced file keeps its mode and a backup its original's") {
  const ScopedUmask umask022(022);
  const auto dir = tunekit::test::scratch_dir("modes");
  const auto src = write_scratch("modes_src.csv", "time,y\n0,1\n1,2\n");
  const auto r = run_cli({"inspect", src, "--json", "-o", dir + "/r.json"});
  REQUIRE(r.code == 0);
  CHECK(file_mode(dir + "/r.json") == 0644);
  {
    const ScopedUmask umask077(077);  // a stricter umask is honoured as well
    REQUIRE(run_cli({"inspect", src, "--json", "-o", dir + "/private.json"}).code == 0);
    CHECK(file_mode(dir + "/private.json") == 0600);
  }
  const std::string cfg = dir + "/printer.cfg";
  std::ofstream(cfg) << "[printer]\nkinematics: cartesian\n\n[extruder]\nstep_pin: PA1\npressure_advance: 0.02\n";
  REQUIRE(::chmod(cfg.c_str(), 0640) == 0);
  const auto w = run_cli({"export", "-f", "klipper", "-c", cfg, "--pa-k", "0.05", "--write"});
  INFO(w.err);
  REQUIRE(w.code == 0);
  CHECK(file_mode(cfg) == 0640);
  int backups = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().extension() == ".bak") {
      ++backups;
      CHECK(file_mode(e.path().string()) == 0640);
    }
  CHECK(backups == 1);
}

TEST_CASE("an unknown command or option gets one error line with 'did you mean'") {
  const auto c = tunekit::test::run_cli({"stpe", "log.csv"});
  CHECK(c.code == 2);
  CHECK(c.err == "tunekit: error: unknown command 'stpe'; did you mean 'step'?; 'tunekit --help' lists the commands\n");
  const auto far = tunekit::test::run_cli({"frobnicate"});
  CHECK(far.code == 2);
  CHECK(far.err.find("unknown command 'frobnicate'") != std::string::npos);
  CHECK(far.err.find("did you mean") == std::string::npos);
  const auto o = tunekit::test::run_cli({"step", "log.csv", "--ouput", "force", "--inptu", "feed"});
  CHECK(o.code == 2);
  CHECK(o.err.find("unknown option '--ouput' for 'tunekit step'; did you mean '--output'?") != std::string::npos);
  const auto v = tunekit::test::run_cli({"rheo", "data.csv", "--shear-rat=Scherrate"});
  CHECK(v.code == 2);
  CHECK(v.err.find("did you mean '--shear-rate'?") != std::string::npos);
}

namespace {

// A usage error as the tool prints every error: one line, the tool's prefix, exit 2, with a
// pointer to the command's help and none of the argument library's own lines.
void check_one_line_usage_error(const tunekit::test::CliRun& r, const std::string& help_hint) {
  INFO(r.err);
  CHECK(r.code == 2);
  CHECK(r.err.rfind("tunekit: error: ", 0) == 0);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  CHECK(r.err.back() == '\n');
  CHECK(r.err.find(help_hint) != std::string::npos);
  CHECK(r.err.find("Run with --help") == std::string::npos);
  CHECK(r.out.empty());
}

}  // namespace

TEST_CASE("argument errors are one line with the tool's prefix and a pointer to the command's help") {
  SECTION("an unknown short option") {
    const auto r = run_cli({"step", "log.csv", "--time", "t", "--input", "u", "--output", "y", "-Z"});
    check_one_line_usage_error(r, "run 'tunekit step --help'");
    CHECK(r.err.find("'-Z'") != std::string::npos);
  }
  SECTION("an unknown option of a nested command") {
    const auto r = run_cli({"history", "list", "--frobnicate"});
    check_one_line_usage_error(r, "'tunekit history list --help'");
    CHECK(r.err.find("unknown option '--frobnicate' for 'tunekit history list'") != std::string::npos);
  }
  SECTION("a nested command's own option with a bad value is not called unknown") {
    const auto r = run_cli({"history", "trend", "--coverage", "nan"});
    check_one_line_usage_error(r, "'tunekit history trend --help'");
    CHECK(r.err.find("unknown option") == std::string::npos);
    CHECK(r.err.find("--coverage") != std::string::npos);
  }
  SECTION("a missing required argument") {
    const auto r = run_cli({"step"});
    check_one_line_usage_error(r, "run 'tunekit step --help'");
    CHECK(r.err.find("FILE") != std::string::npos);
  }
  SECTION("a number that is not one") {
    const auto r = run_cli({"batch", ".", "--jobs", "many"});
    check_one_line_usage_error(r, "run 'tunekit batch --help'");
    CHECK(r.err.find("--jobs: 'many' is not a whole number") != std::string::npos);
  }
  SECTION("an option without its value") {
    const auto r = run_cli({"batch", ".", "--jobs"});
    check_one_line_usage_error(r, "run 'tunekit batch --help'");
    CHECK(r.err.find("--jobs") != std::string::npos);
  }
}
