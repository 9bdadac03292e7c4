// What a user reads: an informational line never prints "nan" for a quantity that does not exist.
#include <string>

#include <catch2/catch.hpp>

#include "test_support.hpp"

using tunekit::test::run_cli;

TEST_CASE("export of a flow sweep whose K holds nowhere says so instead of 'nan to nan mm^3/s'", "[safety][export]") {
  const std::string cfg = tunekit::test::write_scratch("plain_messages_printer.cfg",
                                                       "[printer]\nkinematics: cartesian\n\n[extruder]\n"
                                                       "step_pin: PA1\npressure_advance: 0.02\n");
  const std::string sweep = tunekit::test::dataset("../tests/export/fixtures/step_sweep.json");
  // A design flow below the identified range: K is designed there, far from the need at 1.2 mm^3/s.
  const auto r = run_cli({"export", "-f", "klipper", "-c", cfg, sweep, "--design-flow", "0.02"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.err.find("nan") == std::string::npos);
  CHECK(r.err.find("no band of flows keeps it within 10 %") != std::string::npos);
  // With the design flow inside the range the band is given, as before.
  const auto inside = run_cli({"export", "-f", "klipper", "-c", cfg, sweep});
  CHECK(inside.err.find("stays within 10 % of the need from ") != std::string::npos);
  CHECK(inside.err.find("nan") == std::string::npos);
}
