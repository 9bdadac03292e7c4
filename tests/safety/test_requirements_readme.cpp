// --require name resolution: a bare name means the fitted parameter (in `rheo`, `n` is the flow
// index), never a fit's diagnostic count; and every --require example of the README that can
// run from the repository's own files is run and must pass.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/calibration/results/requirements.hpp"
#include "tunekit/core/error.hpp"

using tunekit::test::run_cli;
using tunekit::test::shell_words;
namespace fs = std::filesystem;

namespace {

/// The README's shell examples that call tunekit with --require (continuation lines joined,
/// trailing comments removed).
std::vector<std::string> readme_require_examples(const std::string& readme) {
  std::vector<std::string> out;
  std::istringstream in(readme);
  std::string line, cmd;
  bool in_sh = false;
  while (std::getline(in, line)) {
    if (line.rfind("```", 0) == 0) {
      in_sh = !in_sh && line.find("sh") != std::string::npos;
      continue;
    }
    if (!in_sh) continue;
    if (const auto hash = line.find("  #"); hash != std::string::npos) line.resize(hash);
    while (!line.empty() && line.back() == ' ') line.pop_back();
    const bool continued = !line.empty() && line.back() == '\\';
    if (continued) line.pop_back();
    cmd += line + " ";
    if (continued) continue;
    if (cmd.find("build/apps/tunekit ") != std::string::npos && cmd.find("--require") != std::string::npos)
      out.push_back(cmd);
    cmd.clear();
  }
  return out;
}

}  // namespace

TEST_CASE("requirements: a bare name resolves to the fitted parameter, not to a diagnostic", "[safety]") {
  const auto results = nlohmann::json::parse(R"({
    "params": {"n": {"value": 0.43, "stderr": 0.01}, "K": {"value": 5}},
    "diagnostics": {"n": 120, "rms": 0.2},
    "power_law": {"fits": [{"params": {"n": {"value": 0.52}}}, {"params": {"n": {"value": 0.58}}}]}
  })");
  using tunekit::calibration::evaluate_requirement;
  using tunekit::calibration::parse_requirement;
  const auto o = evaluate_requirement(parse_requirement("n<0.5"), results);
  CHECK(o.resolved_path == "params.n.value");
  CHECK(o.value == Approx(0.43));
  CHECK(o.met);
  // The diagnostic is compared when named.
  CHECK(evaluate_requirement(parse_requirement("diagnostics.n>=100"), results).value == 120);
  // Only a diagnostic of that name: refused, naming the path to write.
  const auto step_like =
      nlohmann::json::parse(R"({"pooled": {"params": {"tau_s": {"value": 0.4}}, "diagnostics": {"n": 3000}}})");
  try {
    evaluate_requirement(parse_requirement("n>10"), step_like);
    FAIL("a bare n compared the sample count");
  } catch (const tunekit::InputError& e) {
    CHECK(e.message().find("pooled.diagnostics.n") != std::string::npos);
  }
}

TEST_CASE("requirements: rheo --require 'n<0.5' compares the flow index", "[safety]") {
  const auto r = run_cli({"rheo", tunekit::test::dataset("rheology/peek_cross_wlf_synthetic.csv"), "--model",
                          "cross-wlf", "--require", "n<0.5", "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto j = nlohmann::json::parse(r.out);
  CHECK(j["requirements"][0]["path"] == "params.n.value");
  CHECK(j["requirements"][0]["value"].get<double>() == Approx(j["results"]["params"]["n"]["value"].get<double>()));
  const auto step = run_cli({"step", tunekit::test::dataset("liquefier/synthetic_steps.csv"), "--time", "time",
                             "--input", "feed", "--output", "force", "--require", "n>10"});
  CHECK(step.code == 2);
  CHECK(step.err.find("diagnostics.n") != std::string::npos);
}

TEST_CASE("the README's --require examples run and pass", "[safety]") {
  const std::string root = fs::path(tunekit::test::dataset("")).parent_path().parent_path().string();
  const auto examples = readme_require_examples(tunekit::test::read_text(root + "/README.md"));
  REQUIRE(examples.size() >= 4);
  const auto scratch = tunekit::test::scratch_dir("readme_require_examples");
  const auto old_cwd = fs::current_path();
  std::size_t ran = 0;
  bool ran_rheo_n = false;
  for (const auto& ex : examples) {
    std::vector<std::string> words;
    {
      const auto all = shell_words(ex.substr(ex.find("build/apps/tunekit ") + 19));
      for (std::size_t i = 0; i < all.size(); ++i) {
        if (all[i] == ">") ++i;  // a shell redirection and its file
        else if (all[i].front() != '>') words.push_back(all[i]);
      }
    }
    // Files of the repository are used from the repository; examples that need a printer's own
    // files (/tmp/raw_data_*.csv, an archive folder, printer.cfg) cannot run here.
    bool runnable = true;
    for (auto& w : words) {
      if (w.rfind("datasets/", 0) == 0) w = root + "/" + w;
      else if (w.find('/') != std::string::npos && w.rfind("--", 0) != 0 && !fs::exists(w)) runnable = false;
    }
    if (!runnable) continue;
    INFO(ex);
    fs::current_path(scratch);  // calibrate writes its run directory into the working directory
    const auto r = run_cli(words);
    fs::current_path(old_cwd);
    INFO(r.err);
    CHECK(r.code == 0);
    ++ran;
    if (ex.find("'n<0.5'") != std::string::npos) ran_rheo_n = true;
  }
  CHECK(ran >= 2);
  CHECK(ran_rheo_n);
}
