// A machine profile whose dotted table header nests tens of thousands of levels is refused
// before toml++ parses it (the parser recurses per level and overflows the stack).
#include <string>

#include <catch2/catch.hpp>

#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/machine/machine_profile.hpp"

using tunekit::test::dataset;
using tunekit::test::read_text;

namespace {

/// `[a.a. ... .a]` with `levels` parts.
std::string dotted_header(std::size_t levels) {
  std::string h = "[a";
  for (std::size_t i = 1; i < levels; ++i) h += ".a";
  return h + "]\n";
}

}  // namespace

TEST_CASE("a machine profile with a 40,000-level dotted header is refused, not a crash", "[machine][profile]") {
  const std::string base = read_text(dataset("machines/sim.toml"));
  REQUIRE_FALSE(base.empty());
  const std::string deep = base + "\n" + dotted_header(40000);
  try {
    tunekit::machine::parse_machine_profile(deep, "deep.toml");
    FAIL("a 40,000-level header was accepted");
  } catch (const tunekit::InputError& e) {
    CHECK(std::string(e.what()).find("256") != std::string::npos);
    CHECK(std::string(e.what()).find("levels") != std::string::npos);
  }
  const std::string path = tunekit::test::write_scratch("deep_profile.toml", deep);
  const std::string cfg = tunekit::test::write_scratch("deep_profile_printer.cfg", "[extruder]\nstep_pin: PA0\n");
  const auto r =
      tunekit::test::run_cli({"export", "-f", "klipper", "--config", cfg, "--pa-k", "0.05", "--profile", path});
  CHECK(r.code == 2);
  CHECK(r.err.find("256") != std::string::npos);
}

TEST_CASE("dotted keys and headers up to the nesting limit still load", "[machine][profile]") {
  const std::string base = read_text(dataset("machines/sim.toml"));
  const std::string at_limit = base + "\n" + dotted_header(256);
  CHECK_NOTHROW(tunekit::machine::parse_machine_profile(at_limit, "limit.toml"));
  CHECK_THROWS_AS(tunekit::machine::parse_machine_profile(base + "\n" + dotted_header(257), "over.toml"),
                  tunekit::InputError);
  // Dots inside strings, comments and numbers are not key nesting.
  std::string dots;
  for (int i = 0; i < 2000; ++i) dots += "a.";
  const std::string quoted = base + "\n[notes]\ntext = \"" + dots + "\"\n# " + dots + "\nx = 1.5\n";
  CHECK_NOTHROW(tunekit::machine::parse_machine_profile(quoted, "quoted.toml"));
}
