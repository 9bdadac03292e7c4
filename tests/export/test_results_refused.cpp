// Results files are validated before anything is designed from them: a zero, negative or
// non-finite estimate, or an interval of zero width on a fitted parameter, is refused (a
// compensator is turned off only by --no-pa or --pa-k 0, never by a file of zeros); Marlin's
// smoothing time follows Klipper's rule (a value written as 0 is refused); rheology results
// say what they need to reach a configuration, and do reach it beside a step result.
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "test_support.hpp"

using tunekit::test::dataset;
using tunekit::test::read_json;
using tunekit::test::read_text;
using tunekit::test::run_cli;
using tunekit::test::scratch_dir;

// The whole file in a namespace of its own: the test areas are unity builds, and other files
// have helpers of the same names.
namespace test_results_refused {

const std::string kKlipper = "[printer]\nkinematics: cartesian\n\n[extruder]\nstep_pin: PA1\npressure_advance: 0.02\n";

std::string fixture(const std::string& name) { return dataset("../tests/export/fixtures/" + name); }

/// Every number of `j` set to `v`.
void set_numbers(nlohmann::json& j, double v) {
  if (j.is_number()) j = v;
  else if (j.is_structured())
    for (auto& x : j) set_numbers(x, v);
}

/// A copy of the step fixture changed by `edit`, in `dir`.
std::string edited_step(const std::string& dir, const std::string& name,
                        const std::function<void(nlohmann::json&)>& edit) {
  nlohmann::json j = read_json(fixture("step.json"));
  edit(j);
  const std::string path = dir + "/" + name;
  std::ofstream(path) << j.dump(2);
  return path;
}

TEST_CASE("an all-zero step results file is refused and the configuration keeps its advance", "[export]") {
  const std::string dir = scratch_dir("results_zero");
  const std::string cfg = dir + "/printer.cfg";
  std::ofstream(cfg) << kKlipper;
  const std::string zero = edited_step(dir, "zero.json", [](nlohmann::json& j) { set_numbers(j["results"], 0); });
  const auto r = run_cli({"export", "-f", "klipper", "-c", cfg, zero, "--write"});
  INFO(r.err);
  CHECK(r.code == 2);
  CHECK(r.err.find("refused before designing anything") != std::string::npos);
  CHECK(read_text(cfg) == kKlipper);
}

TEST_CASE("a negative time constant or a zero-width interval in a results file is refused", "[export]") {
  const std::string dir = scratch_dir("results_invalid");
  const std::string cfg = dir + "/printer.cfg";
  std::ofstream(cfg) << kKlipper;
  const std::string negative = edited_step(
      dir, "negative.json", [](nlohmann::json& j) { j["results"]["pooled"]["params"]["tau_s"]["value"] = -0.045; });
  const std::string flat = edited_step(dir, "flat.json", [](nlohmann::json& j) {
    j["results"]["pooled"]["params"]["tau_s"]["ci95"] = {0.045, 0.045};
  });
  for (const auto& f : {negative, flat}) {
    const auto r = run_cli({"export", "-f", "klipper", "-c", cfg, f});
    INFO(f << ": " << r.err);
    CHECK(r.code == 2);
  }
  // The fixture itself still exports, and disabling stays explicit.
  CHECK(run_cli({"export", "-f", "klipper", "-c", cfg, fixture("step.json")}).code == 0);
  const auto off = run_cli({"export", "-f", "klipper", "-c", cfg, "--pa-k", "0", "--write"});
  INFO(off.err);
  CHECK(off.code == 0);
  CHECK(read_text(cfg).find("pressure_advance: 0\n") != std::string::npos);
}

TEST_CASE("Marlin's smoothing time written as 0 is refused, as Klipper's is", "[export]") {
  const std::string dir = scratch_dir("marlin_smooth_zero");
  const std::string cfg = dir + "/Configuration_adv.h";
  std::ofstream(cfg) << "#define LIN_ADVANCE\n#define ADVANCE_K 0.02\n#define SMOOTH_LIN_ADVANCE\n"
                        "#define ADVANCE_TAU 0.02\n";
  const std::string before = read_text(cfg);
  for (const std::string fw : {"marlin", "klipper"}) {
    const std::string c = fw == "marlin" ? cfg : dir + "/printer.cfg";
    if (fw == "klipper") std::ofstream(c) << kKlipper;
    const auto r = run_cli({"export", "-f", fw, "-c", c, "--pa-k", "0.05", "--pa-smooth", "1e-9", "--write"});
    INFO(fw << ": " << r.err);
    CHECK(r.code == 2);
  }
  CHECK(read_text(cfg) == before);
}

TEST_CASE("rheo results reach a configuration beside a step result, and alone say what they need", "[export]") {
  const std::string dir = scratch_dir("rheo_export");
  const std::string cfg = dir + "/config.g";
  std::ofstream(cfg) << "; RepRapFirmware\nM572 D0 S0.02\n";
  const std::string rh = dir + "/rh.json";
  const auto rheo = run_cli({"rheo", dataset("rheology/peek_cross_wlf_synthetic.csv"), "--model", "cross-wlf",
                             "--nozzle-d", "0.6", "--nozzle-l", "4", "--cone-angle", "30", "--entrance-D", "5",
                             "--predict-at", "405", "--reference-flow", "3", "--json", "-o", rh});
  INFO(rheo.err);
  REQUIRE(rheo.code == 0);
  REQUIRE(read_json(rh)["results"].contains("prediction"));

  const auto alone = run_cli({"export", "--firmware", "rrf", "--config", cfg, rh});
  INFO(alone.err);
  CHECK(alone.code == 2);
  CHECK(alone.err.find("give results of 'tunekit step', 'freq' or 'shaper'") == std::string::npos);
  CHECK(alone.err.find("beside the results of 'tunekit step' or 'freq'") != std::string::npos);

  const auto both = run_cli({"export", "--firmware", "rrf", "--config", cfg, fixture("step_sweep.json"), rh, "--json"});
  INFO(both.err);
  REQUIRE(both.code == 0);
  const auto res = nlohmann::json::parse(both.out)["results"];
  CHECK(res["settings"]["pa_k_s"].is_number());
  CHECK(res["flow_advance"].contains("rheology"));
}

}  // namespace test_results_refused
