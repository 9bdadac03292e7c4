// The liquefier chirp of `tunekit calibrate` and `tunekit freq`: freq with nothing but the file
// and its columns analyses the chirp as calibrate does, and the frequency-response tau it
// reports is the one every reader shows: the report, the history, export's design and batch.
#include <unistd.h>

#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/calibration/analyses/freq_command.hpp"
#include "tunekit/calibration/results/json_access.hpp"
#include "tunekit/history/store.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/core/file_bytes.hpp"

namespace {

namespace fs = std::filesystem;

constexpr const char* kFreqTauPath = "liquefier.freq.fit.params.tau_s.value";
constexpr const char* kMachineId = "freq-sim";

struct ChirpRun {
  std::string dir, db;
  tunekit::test::CliRun cli;
  nlohmann::json results;
  std::string chirp_csv() const { return dir + "/liquefier-chirp/feed_force.csv"; }
  double freq_tau() const { return tunekit::calibration::json_at(results, kFreqTauPath)->get<double>(); }
};

// One calibration of the simulated liquefier (axes left out), recorded in a history database;
// shared by the cases below within one process (ctest runs each case as its own process, at the
// same time: the directory is the process's own).
const ChirpRun& chirp_run() {
  static const ChirpRun run = [] {
    ChirpRun r;
    const std::string base = tunekit::test::scratch_dir("calibrate_freq_" + std::to_string(::getpid()));
    r.dir = base + "/run";
    r.db = base + "/history.sqlite";
    r.cli = tunekit::test::run_cli({"calibrate", "--machine", "sim", "--skip-axes", "--out", r.dir, "--record",
                                    "--machine-id", kMachineId, "--db", r.db});
    if (r.cli.code == 0) r.results = tunekit::test::read_json(r.dir + "/results.json").at("results");
    return r;
  }();
  return run;
}

}  // namespace

TEST_CASE("freq with only the file and its columns gives calibrate's frequency-response tau on its chirp") {
  const auto& run = chirp_run();
  INFO(run.cli.err);
  REQUIRE(run.cli.code == 0);
  REQUIRE(tunekit::calibration::json_at(run.results, kFreqTauPath) != nullptr);
  REQUIRE(fs::exists(run.chirp_csv()));
  tunekit::calibration::FreqOptions o;
  o.file = run.chirp_csv();
  o.input_column = "feed";
  o.output_column = "force";
  const auto own = tunekit::calibration::compute_freq(o);
  REQUIRE(own.reported_fit() != nullptr);
  const double tau = own.reported_fit()->value("tau_s");
  INFO("freq's own tau " << tau << " s, calibrate's " << run.freq_tau() << " s");
  CHECK(tau == Approx(run.freq_tau()).epsilon(0.01));
  // The same analysis: the same start, band and segments as calibrate's.
  const auto& h1 = run.results.at("liquefier").at("freq").at("h1");
  CHECK(own.broadband->start_s == h1.at("start_s").get<double>());
  CHECK(own.broadband->fmax_hz == h1.at("fmax_hz").get<double>());
  CHECK(own.broadband->segment_length == h1.at("segment_length").get<std::size_t>());
  // As a user types it: the command results.json names for this analysis.
  std::string command;
  for (const auto& e : run.results.at("reproduce"))
    if (e.at("analysis") == "freq") command = e.at("command").get<std::string>();
  CHECK(command ==
        "tunekit freq liquefier-chirp/feed_force.csv --input feed --output force --feed-track "
        "liquefier-chirp/feed_track.csv");
  const auto cli = tunekit::test::run_reproduce_command(run.dir, command, {"--json"});
  INFO(cli.err);
  REQUIRE(cli.code == 0);
  const auto j = nlohmann::json::parse(cli.out).at("results");
  CHECK(j.at("fit").at("params").at("tau_s").at("value").get<double>() == Approx(run.freq_tau()).epsilon(0.01));
  CHECK(j.at("fit").at("source") == "tf_oe_fit");
}

TEST_CASE("one frequency-response tau: the report, the history, export's design and batch show the same") {
  const auto& run = chirp_run();
  INFO(run.cli.err);
  REQUIRE(run.cli.code == 0);
  const double tau = run.freq_tau();
  const auto& freq = run.results.at("liquefier").at("freq");
  // The reported fit is the output-error fit, named as such.
  CHECK(freq.at("fit").at("source") == "tf_oe_fit");
  CHECK(freq.at("tf_oe_fit").at("params").at("tau_s").at("value").get<double>() == tau);

  // The report: its summary lists the chirp's whole-record model (tau at its reference feed, a
  // quantity of its own), not the transfer function's tau; its cell shows results.json's value.
  const std::string wr_tau = "liquefier.freq.whole_record.tau_ref_s.value";
  int rows = 0, tf_rows = 0;
  for (const auto& r : run.results.at("summary")) {
    rows += r.at("path") == wr_tau;
    tf_rows += r.at("path") == kFreqTauPath;
  }
  CHECK(rows == 1);
  CHECK(tf_rows == 0);
  int cells = 0;
  for (const auto& c : tunekit::test::summary_cells(tunekit::read_file_bytes(run.dir + "/report.html"))) {
    if (c.path != wr_tau) continue;
    CHECK(nlohmann::json::parse(c.value).get<double>() ==
          tunekit::calibration::json_at(run.results, wr_tau)->get<double>());
    ++cells;
  }
  CHECK(cells == 1);
  // The agreement check compares that tau with the step's.
  REQUIRE(run.results.at("agreement").size() == 1);
  CHECK(run.results.at("agreement")[0].at("estimates")[1].at("value").get<double>() == tau);

  // The history.
  tunekit::history::Store store(run.db);
  const auto series = store.series(kMachineId, "freq.tau_s");
  REQUIRE(series.size() == 1);
  CHECK(series[0].value == Approx(tau).epsilon(1e-12));

  // Export: designed from the frequency response alone, K is that tau; with the step results
  // too, the agreement it states holds that tau.
  const std::string cfg = run.dir + "/config/printer.cfg";
  const std::string freq_json = run.dir + "/analysis/freq.json";
  auto ex = tunekit::test::run_cli({"export", "-f", "klipper", "-c", cfg, freq_json, "--json"});
  INFO(ex.err);
  REQUIRE(ex.code == 0);
  auto ej = nlohmann::json::parse(ex.out).at("results");
  CHECK(ej.at("design").at("K_source") == "freq");
  CHECK(ej.at("design").at("K_s").get<double>() == Approx(tau).epsilon(1e-12));
  ex = tunekit::test::run_cli(
      {"export", "-f", "klipper", "-c", cfg, run.dir + "/analysis/step.json", freq_json, "--json"});
  INFO(ex.err);
  REQUIRE(ex.code == 0);
  ej = nlohmann::json::parse(ex.out).at("results");
  REQUIRE(ej.at("agreement").size() == 1);
  CHECK(ej.at("agreement")[0].at("estimates")[1].at("value").get<double>() == Approx(tau).epsilon(1e-12));
  CHECK(ej.at("agreement")[0].at("agree") == run.results.at("agreement")[0].at("agree"));

  // Batch: the chirp's CSV is recognised as a chirp and analysed by freq.
  const std::string in = tunekit::test::scratch_dir("calibrate_freq_batch");
  fs::copy_file(run.chirp_csv(), in + "/chirp.csv", fs::copy_options::overwrite_existing);
  const auto b = tunekit::test::run_cli({"batch", in, "-j", "1", "--json"});
  INFO(b.err);
  REQUIRE(b.code == 0);
  const auto summary = nlohmann::json::parse(b.out);
  const auto& ds = summary.at("results").at("datasets");
  REQUIRE(ds.size() == 1);
  CHECK(ds[0].at("command")[0] == "freq");
  CHECK(ds[0].at("results").at("fit").at("params").at("tau_s").at("value").get<double>() == Approx(tau).epsilon(1e-12));
}

TEST_CASE("freq's whole-record model on calibrate's chirp: its tau at the mean feed is the simulator's there") {
  // The simulated liquefier's tau falls with the feed (tau = tau_s (u / u_ref)^exponent) and its
  // load cell reads K u: a flow-like sensor despite the force unit, which the two fits of the
  // record (either sensor) find. The chirp swings the feed by about half its mean, so freq's one
  // linear model is an average over the swing and differs from tau at the mean feed by more than
  // their (very narrow) combined interval; both are held to the simulator's tau at the mean feed.
  const auto& run = chirp_run();
  INFO(run.cli.err);
  REQUIRE(run.cli.code == 0);
  tunekit::calibration::FreqOptions o;
  o.file = run.chirp_csv();
  o.input_column = "feed";
  o.output_column = "force";
  o.feed_track = run.dir + "/liquefier-chirp/feed_track.csv";  // as calibrate analyses it
  const auto own = tunekit::calibration::compute_freq(o);
  REQUIRE(own.whole_record.model);
  REQUIRE(own.reported_fit() != nullptr);
  const auto& m = *own.whole_record.model;
  CHECK(m.model.sensor == tunekit::fitting::LiquefierSensor::flow);
  CHECK(m.sensor_basis == "residuals");
  const auto truth = tunekit::test::read_json(run.dir + "/liquefier-chirp/truth.json").at("liquefier");
  const double u = own.input_mean;
  const double tau_true = truth.at("tau_s").get<double>() * std::pow(u / truth.at("tau_ref_feed_mm_s").get<double>(),
                                                                     truth.at("tau_flow_exponent").get<double>());
  const double tau_model = m.tau_at(u), tau_freq = own.reported_fit()->value("tau_s");
  INFO("at " << u << " mm/s: simulator " << tau_true << " s, model " << tau_model << " +- " << m.tau_stderr_at(u)
             << " s, freq " << tau_freq << " s");
  CHECK(tau_model == Approx(tau_true).epsilon(0.03));
  CHECK(tau_freq == Approx(tau_true).epsilon(0.03));
  CHECK(m.model.fit.value("b") == Approx(truth.at("tau_flow_exponent").get<double>()).margin(0.1));
  // In the results calibrate keeps, as freq puts them.
  const auto& wr = run.results.at("liquefier").at("freq").at("whole_record");
  CHECK(wr.at("b").at("value").get<double>() == Approx(m.model.fit.value("b")).epsilon(1e-9));
}
