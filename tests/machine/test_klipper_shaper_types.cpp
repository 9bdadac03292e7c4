// Klipper's parameterized input shapers, "mzv(n=4,t=0.9)" or "ei(v_tol=0.1)" (D. Butyugin,
// klippy/extras/shaper_defs.py get_shaper_cfg/init_shaper, Klipper 2026: a name, then
// parameters in parentheses): the shaper in force that Klipper reports is kept verbatim and
// restored after a test as Klipper's G-code parser reads it back (klippy/gcode.py
// _get_extended_params: shell words, each split at its first '=').
#include <algorithm>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "fake_klipper.hpp"
#include "test_support.hpp"
#include "tunekit/calibration/analyses/simulated_machine.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/firmware/dialect.hpp"
#include "tunekit/machine/klipper_settings.hpp"
#include "tunekit/protocols/runner.hpp"

using tunekit::test::FakeKlipper;
using tunekit::test::FakeKlipperConfig;
using tunekit::test::scratch_dir;
namespace tprot = tunekit::protocols;

TEST_CASE("a Klipper extended parameter's value is quoted only where Klipper's parser needs it", "[machine][klipper]") {
  using tunekit::firmware::klipper_param_value;
  CHECK(klipper_param_value("mzv") == "mzv");
  CHECK(klipper_param_value("mzv(n=4,t=0.9)") == "mzv(n=4,t=0.9)");
  CHECK(klipper_param_value("mzv(n=4, t=0.9)") == "\"mzv(n=4, t=0.9)\"");
  CHECK(klipper_param_value("a#b") == "\"a#b\"");
  CHECK(klipper_param_value("say \"hi\"\\") == "\"say \\\"hi\\\"\\\\\"");
  CHECK(klipper_param_value("") == "\"\"");
  // A line break would start another command on the machine: refused, never quoted and sent.
  CHECK_THROWS_AS(klipper_param_value("mzv\nG28"), tunekit::InputError);
  CHECK_THROWS_AS(klipper_param_value(std::string("zv\0x", 4)), tunekit::InputError);
}

TEST_CASE("Klipper's settings keep a parameterized shaper type verbatim", "[machine][klipper]") {
  const nlohmann::json info{{"state", "ready"}, {"software_version", "v0.13.0-800"}};
  const nlohmann::json query{{"status",
                              {{"configfile",
                                {{"settings",
                                  {{"input_shaper",
                                    {{"shaper_type", "ei(v_tol=0.1)"},
                                     {"shaper_type_x", "mzv(n=4,t=0.9)"},
                                     {"shaper_freq_x", 61.5},
                                     {"shaper_freq_y", 47.25},
                                     {"damping_ratio_y", 0.15}}}}}}}}}};
  const auto k = tunekit::machine::parse_klipper_settings(info, query);
  CHECK(k.shaper.at("x") == "mzv(n=4,t=0.9):61.5:0.1");
  CHECK(k.shaper.at("y") == "ei(v_tol=0.1):47.25:0.15");  // shaper_type applies to y
}

TEST_CASE("a sweep restores the parameterized shapers Klipper reports, verbatim", "[machine][klipper]") {
  const auto dir = scratch_dir("klipper_param_shaper_sweep");
  FakeKlipperConfig fake;
  fake.shaper_freq_x = 61.5;
  fake.shaper_freq_y = 47.25;
  fake.shaper_type_x = "mzv(n=4,t=0.9)";
  fake.shaper_type_y = "ei(v_tol = 0.1)";  // the whitespace shaper_defs.py's pattern allows
  FakeKlipper server(dir + "/klippy_uds", tunekit::sim::SimConfig::from_options({"firmware=klipper"}), fake);
  tprot::RunOptions o;
  o.protocol = "axis-sweep";
  o.axis = "x";
  o.machine = tunekit::test::dataset("machines/sim.toml");
  o.port = "unix:" + dir + "/klippy_uds";
  o.run_dir = dir + "/run";
  o.params = {{"freq_start_hz", 35}, {"freq_end_hz", 45}, {"hz_per_sec", 5}};
  tunekit::calibration::load_run_machine(o, "", {});
  const auto res = tprot::run_experiment(o);
  REQUIRE(res.status == "complete");
  const std::string restore =
      "SET_INPUT_SHAPER SHAPER_TYPE_X=mzv(n=4,t=0.9) SHAPER_FREQ_X=61.5 DAMPING_RATIO_X=0.1 "
      "SHAPER_TYPE_Y=\"ei(v_tol = 0.1)\" SHAPER_FREQ_Y=47.25 DAMPING_RATIO_Y=0.1";
  CHECK(std::find(res.gcode.begin(), res.gcode.end(), restore) != res.gcode.end());
  // What Klipper's parser makes of the line that reached it: the types as its configuration has them.
  const auto last = server.last_input_shaper();
  CHECK(last.at("SHAPER_TYPE_X") == "mzv(n=4,t=0.9)");
  CHECK(last.at("SHAPER_TYPE_Y") == "ei(v_tol = 0.1)");
  CHECK(last.at("SHAPER_FREQ_X") == "61.5");
  CHECK(server.unknown_commands().empty());
}
