// Numeric options of run out of range (an infinite timeout, negative counts that would wrap)
// and a rheology fit missing a parameter: refused with exit 2 and a message, never run or an
// internal error.
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/fitting/viscosity.hpp"

using tunekit::test::run_cli;

TEST_CASE("run range-checks its numeric options and names the accepted range", "[safety][run]") {
  const std::vector<std::vector<std::string>> cases = {
      {"--timeout", "inf"}, {"--timeout", "1e-9"}, {"--timeout", "-1"},  {"--retries", "-1"},       {"--baud", "-1"},
      {"--baud", "0"},      {"--max-lines", "-1"}, {"--max-lines", "0"}, {"--max-duration", "inf"},
  };
  for (const auto& extra : cases) {
    std::vector<std::string> args = {"run", "liquefier-step", "--dry-run"};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = run_cli(args);
    INFO(extra.front() << " " << extra.back() << ": " << r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find(extra.front()) != std::string::npos);
    CHECK(r.err.find("accepted") != std::string::npos);
  }
  const auto ok =
      run_cli({"run", "liquefier-step", "--dry-run", "--timeout", "5", "--retries", "0", "--max-lines", "100000"});
  CHECK(ok.code == 0);
}

TEST_CASE("nozzle --rheology with a fit missing a parameter names the parameter", "[safety][nozzle]") {
  tunekit::fitting::ViscositySpec spec;
  spec.model = tunekit::fitting::ViscosityModel::power_law;
  const auto names = tunekit::fitting::viscosity_param_names(spec.model);
  REQUIRE(names.size() >= 2);
  nlohmann::json params = nlohmann::json::object();
  for (std::size_t i = 0; i + 1 < names.size(); ++i) params[names[i]] = {{"value", 1000.0}};
  const nlohmann::json fit = {
      {"command", "rheo"}, {"schema_version", 1}, {"results", {{"model", spec.name()}, {"params", params}}}};
  const std::string path = tunekit::test::write_scratch("rheo_missing_param.json", fit.dump(2));
  const auto r = run_cli({"nozzle", "--rheology", path, "--temperature", "210", "--flow", "5"});
  INFO(r.err);
  CHECK(r.code == 2);
  CHECK(r.err.find("'" + names.back() + "'") != std::string::npos);
  CHECK(r.err.find(path) != std::string::npos);
  CHECK(r.err.find("internal error") == std::string::npos);
}

TEST_CASE("a protocol hot-end temperature that rounds to 0 is refused, never written as M109 R0",
          "[safety][temperature]") {
  for (const std::string t : {"0.4", "3"}) {
    const auto r = run_cli({"run", "liquefier-step", "--dry-run", "-p", "hotend_c=" + t});
    INFO("hotend_c=" << t << ": " << r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find("M109") != std::string::npos);
    CHECK(r.out.find("M109 R0") == std::string::npos);
    CHECK(r.out.find("M109 S0") == std::string::npos);
  }
  const auto off = run_cli({"run", "liquefier-step", "--dry-run", "-p", "hotend_c=0"});
  CHECK(off.code == 0);  // 0: the heater is left alone, no M109 at all
  CHECK(off.out.find("M109") == std::string::npos);
}

TEST_CASE("a protocol parameter must be a plain decimal: 0x10 is refused, not read as 16", "[safety][run]") {
  for (const std::string v : {"0x10", "0X1p4", "nan", "inf", " 5", "5 ", "1e", "."}) {
    const auto r = run_cli({"run", "liquefier-flow-sweep", "--dry-run", "-p", "cycles=" + v});
    INFO("cycles=" << v << ": " << r.err);
    CHECK(r.code == 2);
    CHECK(r.err.rfind("tunekit: error: -p cycles=", 0) == 0);
  }
  const auto hex = run_cli({"run", "liquefier-flow-sweep", "--dry-run", "-p", "cycles=0x10"});
  CHECK(hex.err.find("not a decimal number") != std::string::npos);
  for (const std::string v : {"2", "+2", "2.0", "2e0", ".2e1"}) {
    const auto ok = run_cli({"run", "liquefier-flow-sweep", "--dry-run", "-p", "cycles=" + v});
    INFO("cycles=" << v << ": " << ok.err);
    CHECK(ok.code == 0);
  }
  // The same rule for a shaper's frequency in export.
  const std::string cfg =
      tunekit::test::write_scratch("hex_shaper_printer.cfg", "[printer]\nkinematics: cartesian\n\n[input_shaper]\n");
  const auto shaper = run_cli({"export", "-f", "klipper", "-c", cfg, "--shaper-x", "mzv:0x2A"});
  INFO(shaper.err);
  CHECK(shaper.code == 2);
  CHECK(shaper.err.find("not a number") != std::string::npos);
}
