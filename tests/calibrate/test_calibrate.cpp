// End to end: the README's main job, `tunekit calibrate --machine sim`, on the built-in
// simulated printer: run directory, report, summary numbers, determinism, --require.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/cli/report.hpp"
#include "tunekit/ident/csv.hpp"

namespace {

using tunekit::ident::read_file_bytes;

struct Run {
  std::string dir;
  tunekit::test::CliRun cli;
};

Run calibrate(const std::string& name, std::vector<std::string> extra = {}) {
  Run r;
  r.dir = tunekit::test::scratch_dir(name) + "/run";
  std::vector<std::string> args{"calibrate", "--machine", "sim", "--out", r.dir};
  args.insert(args.end(), extra.begin(), extra.end());
  r.cli = tunekit::test::run_cli(args);
  return r;
}

}  // namespace

TEST_CASE("calibrate on the simulated printer writes a report whose plots and numbers come from results.json") {
  const auto run = calibrate("calibrate_report");
  INFO(run.cli.err);
  REQUIRE(run.cli.code == 0);
  CHECK(run.cli.out.find("report: " + run.dir + "/report.html") != std::string::npos);
  for (const char* f : {"results.json", "plotdata.json", "report.html", "config/changes.diff"}) {
    INFO(f);
    CHECK(std::filesystem::exists(run.dir + "/" + f));
  }
  const auto env = nlohmann::json::parse(read_file_bytes(run.dir + "/results.json"));
  const auto& results = env.at("results");
  const std::string html = read_file_bytes(run.dir + "/report.html");

  for (const char* id : {"step", "bode", "psd_x", "psd_y"}) {
    INFO(id);
    CHECK(tunekit::test::embedded_png_base64_length(html, id) > 2000);
  }
  std::size_t cells = 0;
  for (const auto& c : tunekit::test::summary_cells(html)) {
    INFO(c.path);
    const auto* v = tunekit::cli::json_at(results, c.path);
    REQUIRE(v != nullptr);
    CHECK(nlohmann::json::parse(c.value).get<double>() == v->get<double>());
    CHECK(c.display == tunekit::cli::display_number(v->get<double>()));
    ++cells;
  }
  CHECK(cells == results.at("summary").size());
  CHECK(cells >= 8);
  // The configuration preview changes pressure advance and both shapers.
  const std::string diff = results.at("config_diff").get<std::string>();
  CHECK(diff.find("+pressure_advance") != std::string::npos);
  CHECK(diff.find("shaper_freq_x") != std::string::npos);
}

TEST_CASE("two calibrations of the simulated printer give byte-identical results.json") {
  const auto a = calibrate("calibrate_det_a");
  const auto b = calibrate("calibrate_det_b");
  INFO(a.cli.err << b.cli.err);
  REQUIRE(a.cli.code == 0);
  REQUIRE(b.cli.code == 0);
  CHECK(read_file_bytes(a.dir + "/results.json") == read_file_bytes(b.dir + "/results.json"));
}

TEST_CASE("calibrate --require exits 1 naming each unmet requirement") {
  const auto r = calibrate("calibrate_require", {"--skip-liquefier", "--require", "x.freq_hz<1", "--require",
                                                 "y.freq_hz>0", "--require", "y.zeta>5"});
  CHECK(r.cli.code == 1);
  CHECK(r.cli.err.find("requirement not met: x.freq_hz<1") != std::string::npos);
  CHECK(r.cli.err.find("requirement not met: y.zeta>5") != std::string::npos);
  CHECK(r.cli.err.find("y.freq_hz>0") == std::string::npos);
}

TEST_CASE("calibrate never writes into a used run directory") {
  const auto dir = tunekit::test::scratch_dir("calibrate_used");
  std::ofstream(dir + "/results.json") << "{}";
  const auto r = tunekit::test::run_cli({"calibrate", "--machine", "sim", "--out", dir});
  CHECK(r.code == 2);
  CHECK(r.err == "tunekit: error: " + dir + ": the run directory already exists; give a new --out (or leave it out for "
                 "runs/calibrate-UTCSTAMP)\n");
  CHECK(tunekit::ident::read_file_bytes(dir + "/results.json") == "{}");
}

TEST_CASE("calibrate refuses a real machine without a profile before touching it") {
  const auto r = tunekit::test::run_cli({"calibrate", "--machine", "/dev/ttyNONEXISTENT"});
  CHECK(r.code == 2);
  CHECK(r.err.find("needs its profile") != std::string::npos);
}
