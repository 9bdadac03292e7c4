// Hostile export options: values checked as they will be written (after rounding), extruder
// names and drive numbers checked, and outputs that would replace an input refused.
#include <filesystem>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "test_support.hpp"

using tunekit::test::dataset;
using tunekit::test::read_text;
using tunekit::test::run_cli;
using tunekit::test::scratch_dir;
namespace fs = std::filesystem;

namespace {

/// A copy of the dataset's firmware configuration `name` in a fresh scratch directory.
std::string copy_config(const std::string& dir_name, const std::string& name) {
  const std::string dir = scratch_dir(dir_name);
  const std::string cfg = dir + "/" + name;
  fs::copy_file(dataset("firmware/" + name), cfg);
  return cfg;
}

std::size_t files_in(const std::string& dir) {
  return static_cast<std::size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator{}));
}

}  // namespace

TEST_CASE("export checks each value as written: a smoothing time or damping that rounds out of range is refused",
          "[export][hostile]") {
  struct Case {
    std::string firmware, config;
    std::vector<std::string> extra;
  };
  const std::vector<Case> cases = {
      {"klipper", "printer.cfg", {"--pa-k", "0.05", "--pa-smooth", "1e-9"}},
      {"marlin", "Configuration_adv.h", {"--shaper-x", "zv:50:0.999999"}},
      {"rrf", "config.g", {"--shaper-x", "mzv:50:0.9904"}},  // RepRapFirmware's limit 0.99 holds
  };
  for (const auto& c : cases) {
    const std::string cfg = copy_config("export_as_written_" + c.firmware, c.config);
    const std::string before = read_text(cfg);
    std::vector<std::string> args = {"export", "-f", c.firmware, "--config", cfg, "--write"};
    args.insert(args.end(), c.extra.begin(), c.extra.end());
    const auto r = run_cli(args);
    INFO(c.firmware << ": " << r.err);
    if (c.firmware == "rrf") {
      CHECK(r.code == 0);  // 0.9904 is written as 0.99, which RepRapFirmware accepts
      continue;
    }
    CHECK(r.code == 2);
    CHECK(r.err.find("as written") != std::string::npos);
    CHECK(read_text(cfg) == before);
  }
}

TEST_CASE("export refuses an --extruder that is no extruder section and a negative --drive", "[export][hostile]") {
  const std::string cfg = copy_config("export_extruder_names", "printer.cfg");
  const std::string before = read_text(cfg);
  for (const std::string bad :
       {"extruder\nfoo", "", "[x]", "-1", "99999999999999999999", "99", "extruder0", "extruder_stepper belt"}) {
    const auto r =
        run_cli({"export", "-f", "klipper", "--config", cfg, "--pa-k", "0.05", "--extruder", bad, "--write"});
    INFO("--extruder '" << bad << "': " << r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find("--extruder") != std::string::npos);
    CHECK(r.err.find("internal error") == std::string::npos);
  }
  CHECK(read_text(cfg) == before);
  const auto ok = run_cli({"export", "-f", "klipper", "--config", cfg, "--pa-k", "0.05", "--extruder", "extruder1"});
  CHECK(ok.code == 0);
  CHECK(ok.out.find("[extruder1]") != std::string::npos);

  const std::string g = copy_config("export_drive", "config.g");
  const auto neg = run_cli({"export", "-f", "rrf", "--config", g, "--pa-k", "0.05", "--drive", "-1"});
  CHECK(neg.code == 2);
  CHECK(neg.err.find("--drive") != std::string::npos);
  CHECK(neg.out.find("D-1") == std::string::npos);
}

TEST_CASE("export refuses an output that is one of its inputs, by file identity", "[export][hostile]") {
  const std::string cfg = copy_config("export_output_is_input", "printer.cfg");
  const std::string dir = fs::path(cfg).parent_path().string();
  const std::string before = read_text(cfg);
  const std::string other_spelling = dir + "/./printer.cfg";
  const std::string link = dir + "/link.cfg";
  fs::create_symlink(cfg, link);
  const std::vector<std::vector<std::string>> cases = {
      {"--gcode", cfg}, {"--gcode", other_spelling}, {"--gcode", link}, {"-o", cfg}, {"--json-file", link}};
  for (const auto& extra : cases) {
    std::vector<std::string> args = {"export", "-f", "klipper", "--config", cfg, "--pa-k", "0.05"};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = run_cli(args);
    INFO(extra.front() << " " << extra.back() << ": " << r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find("input") != std::string::npos);
    CHECK(read_text(cfg) == before);
  }
  CHECK(files_in(dir) == 2);  // the configuration and the link: nothing written
}

TEST_CASE("a shaper frequency too small for a double is called implausible, not 'not a number'", "[export][hostile]") {
  const std::string cfg = copy_config("export_denormal_shaper", "printer.cfg");
  const auto r = run_cli({"export", "-f", "klipper", "--config", cfg, "--shaper-x", "mzv:5e-324"});
  INFO(r.err);
  CHECK(r.code == 2);
  CHECK(r.err.find("not a number") == std::string::npos);
  CHECK(r.err.find("implausibly small") != std::string::npos);
}

TEST_CASE("an implausibly small --design-flow is named, not blamed on the advance K", "[export][hostile]") {
  const std::string cfg = copy_config("export_tiny_design_flow", "printer.cfg");
  const std::string step = tunekit::test::dataset("../tests/export/fixtures/step_sweep.json");
  const auto r = run_cli({"export", "-f", "klipper", "--config", cfg, step, "--design-flow", "1e-300"});
  INFO(r.err);
  CHECK(r.code == 2);
  CHECK(r.err.find("--design-flow") != std::string::npos);
  CHECK(r.err.find("advance K") == std::string::npos);
}
