// Writers stay in their directory and failures of the plot library do not take the results
// with them: `report` refuses to write through a symbolic link that leaves the run directory;
// a calibration under a memory cap that keeps the plot library from starting ends with its
// results and a report without the figures (one note each), never a crash; a solver that fails
// says why in plain words, without the solver's own report.
#include <filesystem>
#include <fstream>
#include <string>

#include <catch2/catch.hpp>

#include "test_support.hpp"

using tunekit::test::dataset;
using tunekit::test::read_text;
using tunekit::test::run_cli;
using tunekit::test::scratch_dir;
namespace fs = std::filesystem;

TEST_CASE("report does not write through a symbolic link out of the run directory", "[report]") {
  const auto& cal = tunekit::test::default_calibration();
  REQUIRE(cal.cli.code == 0);
  const std::string dir = scratch_dir("report_symlink");
  const std::string run = dir + "/RUN";
  fs::copy(cal.dir, run, fs::copy_options::recursive);
  std::ofstream(dir + "/victim.txt") << "precious";
  fs::remove(run + "/report.html");
  fs::create_symlink("../victim.txt", run + "/report.html");
  const auto r = run_cli({"report", run});
  INFO(r.err);
  CHECK(r.code == 2);
  CHECK(r.err.find("outside its directory") != std::string::npos);
  CHECK(read_text(dir + "/victim.txt") == "precious");
  // A plot: the same.
  fs::remove(run + "/report.html");
  fs::remove(run + "/plots/step.svg");
  fs::create_symlink("../../victim.txt", run + "/plots/step.svg");
  run_cli({"report", run});
  CHECK(read_text(dir + "/victim.txt") == "precious");
}

TEST_CASE("run does not append its journal through a symbolic link planted in the run directory", "[report]") {
  const std::string dir = scratch_dir("journal_symlink");
  fs::create_directories(dir + "/run");
  std::ofstream(dir + "/victim.txt") << "precious";
  fs::create_symlink("../victim.txt", dir + "/run/journal.jsonl");
  const auto r = run_cli({"run", "liquefier-step", "--machine", "sim", "--run-dir", dir + "/run"});
  INFO(r.err);
  CHECK(r.code == 2);
  CHECK(read_text(dir + "/victim.txt") == "precious");
}

TEST_CASE("calibrate under a memory cap ends with its results and a report without figures, not a crash", "[report]") {
  const std::string dir = scratch_dir("memory_cap");
  // 100 MB of address space: enough for the calibration, too little for the plot library's threads.
  const auto r = tunekit::test::run_exe_prefixed("prlimit --as=100000000 ",
                                                 "calibrate --machine sim --skip-axes --out " + dir + "/run");
  INFO(r.err);
  CHECK(r.code == 0);
  CHECK(r.err.find("GLib") == std::string::npos);
  CHECK(fs::exists(dir + "/run/results.json"));
  const std::string html = read_text(dir + "/run/report.html");
  CHECK(html.find("the figure was not drawn") != std::string::npos);
}

TEST_CASE("a fit the solver cannot evaluate says so in plain words, without the solver's report", "[rheology]") {
  const std::string src = read_text(dataset("rheology/nozzle_pressure_synthetic.csv"));
  std::string out;
  int row = 0;
  for (std::size_t b = 0, e; b < src.size(); b = e + 1) {
    e = src.find('\n', b);
    if (e == std::string::npos) e = src.size();
    std::string line = src.substr(b, e - b);
    if (!line.empty() && line[0] >= '0' && line[0] <= '9' && ++row % 7 == 0) {
      const auto c1 = line.find(','), c2 = line.find(',', c1 + 1);
      line = line.substr(0, c1 + 1) + "1e308" + line.substr(c2);
    }
    out += line + "\n";
  }
  const std::string csv = tunekit::test::write_scratch("nozzle_1e308.csv", out);
  const auto r = run_cli({"nozzle", "--fit", csv});
  INFO(r.err);
  CHECK(r.code != 0);
  CHECK(r.err.find("Ceres") == std::string::npos);
  CHECK(r.err.find("Residual and Jacobian") == std::string::npos);
  CHECK(r.err.find("tunekit: error: ") == 0);
}
