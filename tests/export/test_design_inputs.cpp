// Export's design inputs: the typed values calibrate hands over from its analyses' outcomes and
// the ones read back from the results files a user names are the same, and so is the design.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "../liquefier/synth_flow_sweep.hpp"
#include "test_support.hpp"
#include "tunekit/calibration/commands/design_inputs.hpp"
#include "tunekit/calibration/commands/export_command.hpp"
#include "tunekit/calibration/analyses/step_command.hpp"
#include "tunekit/core/error.hpp"

using namespace tunekit;
using namespace tunekit::calibration;

namespace {

std::string design_sweep_log(const test::SynthFlowSweep& s, const std::string& name) {
  std::ostringstream os;
  os << "time_s,flow_mm3_s,force_N\n";
  for (std::size_t i = 0; i < s.t.size(); ++i) os << s.t[i] << "," << s.u[i] << "," << s.y[i] << "\n";
  return test::write_scratch(name, os.str());
}

void check_same(const EstimatedValue& a, const EstimatedValue& b) {
  CHECK(a.value == Approx(b.value).epsilon(1e-12));
  CHECK(a.std_error == Approx(b.std_error).epsilon(1e-12));
  CHECK(a.ci95_lo == Approx(b.ci95_lo).epsilon(1e-12));
  CHECK(a.ci95_hi == Approx(b.ci95_hi).epsilon(1e-12));
}

}  // namespace

TEST_CASE("design inputs: a step outcome and its results file give the same inputs and the same export") {
  test::SynthFlowSweepTruth tr;
  tr.b = -0.45;
  tr.rate_hz = 250;
  const auto s = test::synth_flow_sweep(tr, 5, 2, 12, 5.0, 3.0);
  StepOptions so;
  so.file = design_sweep_log(s, "design_inputs_sweep.csv");
  so.input_column = "flow_mm3_s";
  so.output_column = "force_N";
  const StepOutcome outcome = compute_step(so);
  const std::string dir = test::scratch_dir("design_inputs");
  const std::string results = dir + "/step.json";
  {
    std::ofstream f(results);
    f << to_envelope(outcome).dump();
  }

  const DesignInputs from_file = read_design_inputs({results});
  DesignInputs typed;
  typed.step = step_design_input(outcome, results);
  typed.origins = {results};
  REQUIRE(from_file.step);
  const StepDesignInput &a = *from_file.step, &b = *typed.step;
  check_same(a.tau_s, b.tau_s);
  check_same(a.theta_s, b.theta_s);
  check_same(a.K, b.K);
  CHECK(a.K_unit == b.K_unit);
  CHECK(a.levels_in_flow);
  CHECK(a.levels_in_flow == b.levels_in_flow);
  REQUIRE(a.trend);
  REQUIRE(b.trend);
  CHECK(a.trend->b == Approx(b.trend->b).epsilon(1e-12));
  CHECK(a.trend->b == Approx(tr.b).margin(0.05));
  REQUIRE(a.levels.size() == b.levels.size());
  REQUIRE(a.levels.size() >= 5);
  for (std::size_t i = 0; i < a.levels.size(); ++i) {
    CHECK(a.levels[i].u == Approx(b.levels[i].u).epsilon(1e-12));
    CHECK(a.levels[i].tau_s == Approx(b.levels[i].tau_s).epsilon(1e-12));
    CHECK(a.levels[i].tau_ci95_lo == Approx(b.levels[i].tau_ci95_lo).epsilon(1e-12));
  }

  // The same design from either: export's settings and flow design agree to the last digit.
  std::filesystem::copy_file(test::dataset("firmware/printer.cfg"), dir + "/printer.cfg",
                             std::filesystem::copy_options::overwrite_existing);
  ExportOptions eo;
  eo.firmware = "klipper";
  eo.config = dir + "/printer.cfg";
  eo.results = {results};
  const ExportOutcome by_file = compute_export(eo);
  const ExportOutcome by_type = compute_export(eo, typed);
  REQUIRE(by_file.settings.pa_k_s);
  REQUIRE(by_type.settings.pa_k_s);
  CHECK(*by_file.settings.pa_k_s == Approx(*by_type.settings.pa_k_s).epsilon(1e-12));
  REQUIRE(by_file.flow);
  REQUIRE(by_type.flow);
  CHECK(by_file.flow->k_design_s == Approx(by_type.flow->k_design_s).epsilon(1e-12));
  CHECK(by_file.change.updated == by_type.change.updated);
}

TEST_CASE("design inputs: a results file that is not step, freq, shaper or rheo is refused with its name") {
  const std::string path =
      test::write_scratch("resonance_results.json", R"({"command": "resonance", "results": {"axes": {}}})");
  try {
    (void)read_design_inputs({path});
    FAIL("no error");
  } catch (const Error& e) {
    CHECK(e.code() == ExitCode::bad_input);
    CHECK(e.formatted().find("resonance_results.json") != std::string::npos);
    CHECK(e.formatted().find("cannot be exported") != std::string::npos);
  }
}
