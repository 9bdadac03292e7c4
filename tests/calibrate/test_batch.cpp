// tunekit batch: every dataset of a folder, analyzed in parallel, one summary, worst exit code.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/core/file_bytes.hpp"

namespace fs = std::filesystem;

TEST_CASE("batch analyzes each recognized file, applies requirements where they apply, and exits with the worst code") {
  const auto dir = tunekit::test::scratch_dir("batch_in");
  fs::copy_file(tunekit::test::dataset("liquefier/synthetic_steps.csv"), dir + "/steps.csv");
  fs::copy_file(tunekit::test::dataset("rheology/peek_cross_wlf_synthetic.csv"), dir + "/rheometer.csv");
  fs::copy_file(tunekit::test::dataset("liquefier/holtrup_table_4_3.csv"), dir + "/table.csv");
  const std::string out = tunekit::test::scratch_dir("batch_out") + "/summary.json";

  auto r = tunekit::test::run_cli({"batch", dir, "--jobs", "2", "--require", "tau_s<10", "-o", out});
  INFO(r.err);
  CHECK(r.code == 0);
  auto j = nlohmann::json::parse(tunekit::read_file_bytes(out));
  const auto& ds = j["results"]["datasets"];
  REQUIRE(ds.size() == 3);
  CHECK(ds[0]["file"] == dir + "/rheometer.csv");
  CHECK(ds[0]["command"][0] == "rheo");
  CHECK(ds[0]["requirements"][0]["applicable"] == false);
  CHECK(ds[1]["command"][0] == "step");
  CHECK(ds[1]["requirements"][0]["met"] == true);
  CHECK(ds[2]["status"] == "skipped");
  CHECK(j["results"]["counts"]["ok"] == 2);

  r = tunekit::test::run_cli({"batch", dir, "--require", "tau_s<0.01"});
  CHECK(r.code == 1);
  CHECK(r.err.find("steps.csv: requirement not met: tau_s<0.01") != std::string::npos);

  fs::copy_file(tunekit::test::dataset("liquefier/synthetic_steps.csv"), dir + "/zz_broken.csv");
  {
    std::ofstream f(dir + "/zz_broken.csv", std::ios::app);
    f << "1e9,abc,1\n";
  }
  r = tunekit::test::run_cli({"batch", dir});
  CHECK(r.code == 2);
}

TEST_CASE("batch refuses a requirement that names nothing in any dataset, as a single command does") {
  const auto dir = tunekit::test::scratch_dir("batch_typo");
  fs::copy_file(tunekit::test::dataset("liquefier/synthetic_steps.csv"), dir + "/steps.csv");
  fs::copy_file(tunekit::test::dataset("rheology/peek_cross_wlf_synthetic.csv"), dir + "/rheometer.csv");
  const std::string out = tunekit::test::scratch_dir("batch_typo_out") + "/summary.json";

  // The single command's verdict on the same typo, for comparison.
  const auto single = tunekit::test::run_cli({"step", dir + "/steps.csv", "--time", "time", "--input", "feed",
                                              "--output", "force", "--require", "x.freqhz>=35"});
  CHECK(single.code == 2);

  const auto r = tunekit::test::run_cli({"batch", dir, "--require", "x.freqhz>=35", "-o", out});
  CHECK(r.code == 2);
  CHECK(r.err.find("tunekit: error:") != std::string::npos);
  CHECK(r.err.find("x.freqhz>=35") != std::string::npos);
  CHECK(r.err.find("it applies to no dataset (2 analyzed)") != std::string::npos);
  CHECK_FALSE(fs::exists(out));  // all or nothing, as a single command

  // A requirement that one kind of dataset names still applies (the other kind: not applicable).
  const auto ok = tunekit::test::run_cli({"batch", dir, "--require", "tau_s<10"});
  INFO(ok.err);
  CHECK(ok.code == 0);
}
