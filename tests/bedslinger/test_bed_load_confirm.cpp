// The mass on a real printer's bed: the run asks the technician (on a terminal) before anything is
// sent, and stops when it is not confirmed.
#include <string>

#include <catch2/catch.hpp>

#include "tunekit/calibration/commands/run_command.hpp"
#include "tunekit/core/error.hpp"

using namespace tunekit;

TEST_CASE("a sweep with a mass on a real printer's bed asks first and stops when it is not confirmed", "[bedslinger]") {
  calibration::RunCommandOptions o;
  o.run.protocol = "axis-sweep";
  o.run.axis = "y";
  o.run.machine = TUNEKIT_DATASETS_DIR "/machines/sim.toml";
  o.run.port = "/nonexistent/tunekit-port";
  o.params = {"load_kg=0.3", "load_x_mm=100", "load_y_mm=120"};
  std::string asked;
  o.confirm_setup = [&asked](const std::string& instruction) {
    asked = instruction;
    return false;
  };
  CHECK_THROWS_WITH(calibration::compute_run(o), Catch::Contains("not confirmed: nothing was sent"));
  CHECK(asked == "place 0.3 kg on the bed (x 100 mm, y 120 mm), fixed so it cannot slide");

  // Confirmed: the run goes on to the printer (here a port that does not exist: a machine error).
  o.confirm_setup = [&asked](const std::string& instruction) {
    asked = instruction + " (confirmed)";
    return true;
  };
  CHECK_THROWS_AS(calibration::compute_run(o), MachineError);
  CHECK(asked.find("(confirmed)") != std::string::npos);

  // No load: nothing is asked.
  asked.clear();
  o.params = {};
  CHECK_THROWS_AS(calibration::compute_run(o), MachineError);
  CHECK(asked.empty());
}
