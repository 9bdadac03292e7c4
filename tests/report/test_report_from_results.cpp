// `tunekit report RUN_DIR` rebuilds a calibration's report from its results.json and
// plotdata.json alone: the run's record read back renders the report `tunekit calibrate` wrote
// from the record in memory, byte for byte (the report holds no generation time, so nothing is
// removed before comparing).
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>

#include "test_support.hpp"
#include "tunekit/calibration/results/calibration_record.hpp"
#include "tunekit/core/file_bytes.hpp"

namespace {

namespace fs = std::filesystem;
using tunekit::read_file_bytes;

// The report `tunekit report` writes into `dir`, which holds what it reads.
std::string rebuilt_report(const std::string& dir) {
  const auto r = tunekit::test::run_cli({"report", dir});
  INFO(r.err);
  REQUIRE(r.code == 0);
  REQUIRE(r.out == dir + "/report.html\n");
  return read_file_bytes(dir + "/report.html");
}

// Where two reports first differ, with the text around it there; "" when they are equal. (A
// report is megabytes: a failed comparison says where, not the whole of both.)
std::string first_difference(const std::string& a, const std::string& b) {
  if (a == b) return "";
  const auto at = static_cast<std::size_t>(
      std::mismatch(a.begin(), a.begin() + std::min(a.size(), b.size()), b.begin()).first - a.begin());
  const std::size_t from = at > 80 ? at - 80 : 0;
  return "byte " + std::to_string(at) + " (sizes " + std::to_string(a.size()) + ", " + std::to_string(b.size()) +
         "):\n" + a.substr(from, 160) + "\n---\n" + b.substr(from, 160);
}

}  // namespace

TEST_CASE("tunekit report rebuilds calibrate's report from results.json and plotdata.json, byte for byte") {
  // The shared default calibration is only read: its two files are copied into a directory of
  // their own, which holds nothing else (no plots, no report, no analyses).
  const auto& run = tunekit::test::default_calibration();
  INFO(run.cli.err);
  REQUIRE(run.cli.code == 0);
  const std::string dir = tunekit::test::scratch_dir("report_from_results");
  for (const char* f : {"results.json", "plotdata.json"}) fs::copy_file(run.dir + "/" + f, dir + "/" + f);
  const std::string written = read_file_bytes(run.dir + "/report.html");
  const std::string rebuilt = rebuilt_report(dir);
  REQUIRE(written.size() > 100000);  // the plots are embedded
  CHECK(first_difference(rebuilt, written) == "");
  // The plots drawn again are the ones calibrate drew.
  for (const char* id : {"step", "bode", "psd_x", "psd_y", "flow_advance"}) {
    INFO(id);
    CHECK(first_difference(read_file_bytes(dir + "/plots/" + std::string(id) + ".svg"),
                           read_file_bytes(run.dir + "/plots/" + std::string(id) + ".svg")) == "");
  }
  // The record read back holds the summary calibrate printed: each row's value with its interval.
  const auto record = tunekit::calibration::read_run_record(dir);
  REQUIRE(record.summary.size() >= 10);
  for (const auto& row : record.summary) {
    INFO(row.label);
    CHECK(row.estimate.has_value());
    CHECK(row.basis.empty() == row.estimate.has_interval());
    if (row.estimate.has_interval()) {
      CHECK(row.estimate.ci95_lo <= row.estimate.value);
      CHECK(row.estimate.value <= row.estimate.ci95_hi);
    }
  }
  REQUIRE(record.agreements.size() == 1);
  CHECK(record.agreements[0].id == "tau");
}

TEST_CASE("tunekit report rebuilds the camera path's report, ring prediction and photo overlay included",
          "[calibrate]") {
  const std::string dir = tunekit::test::scratch_dir("report_from_results_camera") + "/run";
  const auto r = tunekit::test::run_cli(
      {"calibrate", "--machine", "sim", "--liquefier", "camera", "--camera", "sim", "--skip-axes", "--out", dir});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const std::string written = read_file_bytes(dir + "/report.html");
  CHECK(written.find("id=\"plot-linewidth_overlay\"") != std::string::npos);
  CHECK(written.find("id=\"agreement-theta\"") != std::string::npos);  // the ring's dead time against the lines'
  CHECK(written.find("dead time from the ring's phase") != std::string::npos);
  CHECK(first_difference(rebuilt_report(dir), written) == "");
}
