// RepRapFirmware's accelerometer files (M956), written here in the layout RepRapFirmware's
// src/Accelerometers/Accelerometers.cpp produces: a "Sample,X,Y,Z" header (only the axes asked
// for), rows "%u" then ",%.*f" per axis in g (decimals by resolution: 3 for a 10-bit LIS3DH),
// and a last line "Rate %u, overflows %u"; a failed run writes "Failed to collect data from
// accelerometer" instead (also quoted in the Duet3D forum's reports of failed runs).
#include <cstdio>
#include <string>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "synth_sweep.hpp"
#include "test_support.hpp"

using tunekit::test::run_cli;
using tunekit::test::write_scratch;

namespace {

std::string to_rrf_m956(const tunekit::test::SynthRecord& r, unsigned rate_hz, unsigned overflows,
                        const char* axes = "XYZ") {
  std::string out = "Sample";
  for (const char* a = axes; *a != 0; ++a) out += std::string(",") + *a;
  out += "\n";
  char buf[96];
  for (std::size_t i = 0; i < r.t.size(); ++i) {
    out += std::to_string(i);
    for (const char* a = axes; *a != 0; ++a) {
      const double v = (*a == 'X' ? r.ax[i] : *a == 'Y' ? r.ay[i] : r.az[i]) / 9806.65;
      std::snprintf(buf, sizeof buf, ",%.3f", v);
      out += buf;
    }
    out += "\n";
  }
  std::snprintf(buf, sizeof buf, "Rate %u, overflows %u\n", rate_hz, overflows);
  return out + buf;
}

// The resonance tests' sweep (20 -> 100 Hz at 2 Hz/s), sampled at the accelerometer's rate.
tunekit::test::SynthRecord rrf_sweep(double f_mode, unsigned rate) {
  tunekit::test::SweepSpec s;
  s.sample_rate_hz = rate;
  s.f_start_hz = 20;
  s.f_end_hz = 100;
  s.hz_per_sec = 2;
  s.t0_s = 0;
  return tunekit::test::synth_sweep({{f_mode, 0.06, 1.0}}, s);
}

}  // namespace

TEST_CASE("an RRF M956 file gives the mode within 1 %", "[resonance][cli]") {
  const double f_mode = 46.3;
  const unsigned rate = 1344;  // the LIS3DH's rate RepRapFirmware's documentation recommends
  const auto path = write_scratch("raw_data_x_m956.csv", to_rrf_m956(rrf_sweep(f_mode, rate), rate, 0));
  const auto r = run_cli({"resonance", path, "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto env = nlohmann::json::parse(r.out);
  const auto& x = env["results"]["axes"]["x"];
  REQUIRE(!x["modes"].empty());
  CHECK(x["modes"][0]["freq_hz"].get<double>() == Approx(f_mode).epsilon(0.01));
  // The shaper command reads the same file (axis from the name given with M956 F"...").
  const auto s = run_cli({"shaper", path, "--json"});
  INFO(s.err);
  REQUIRE(s.code == 0);
  CHECK(nlohmann::json::parse(s.out)["results"]["axes"]["x"]["recommended"]["freq_hz"].get<double>() > 0);
}

TEST_CASE("an RRF M956 file of one axis, with overflows, named by RRF's date pattern", "[resonance][cli]") {
  const double f_mode = 58.0;
  const unsigned rate = 1600;
  const auto path = write_scratch("0_2024-10-23_11.28.34.csv", to_rrf_m956(rrf_sweep(f_mode, rate), rate, 2, "X"));
  // No axis in RRF's default name: the record is analysed under its file stem (an axis is
  // needed only where one must be named, e.g. for export).
  const auto no_axis = run_cli({"resonance", path, "--json"});
  INFO(no_axis.err);
  REQUIRE(no_axis.code == 0);
  const auto stem = nlohmann::json::parse(no_axis.out)["results"]["axes"]["0_2024-10-23_11.28.34"];
  REQUIRE(stem.is_object());
  CHECK(stem["modes"][0]["freq_hz"].get<double>() == Approx(f_mode).epsilon(0.01));
  const auto r = run_cli({"resonance", path, "--axis", "x", "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto env = nlohmann::json::parse(r.out);
  CHECK(env["results"]["axes"]["x"]["modes"][0]["freq_hz"].get<double>() == Approx(f_mode).epsilon(0.01));
  CHECK(env.dump().find("overflowed 2 time(s)") != std::string::npos);
}

TEST_CASE("a failed or unfinished RRF M956 run exits 2 with the file and line", "[resonance][cli]") {
  const auto failed =
      write_scratch("raw_data_x_failed.csv", "Sample,X,Y,Z\nFailed to collect data from accelerometer\n");
  const auto a = run_cli({"resonance", failed});
  CHECK(a.code == 2);
  CHECK(a.err.find("raw_data_x_failed.csv:2:") != std::string::npos);
  CHECK(a.err.find("Failed to collect data") != std::string::npos);
  std::string text = to_rrf_m956(rrf_sweep(50, 1344), 1344, 0);
  text = text.substr(0, text.find("Rate "));
  const auto unfinished = write_scratch("raw_data_x_unfinished.csv", text);
  const auto b = run_cli({"resonance", unfinished});
  CHECK(b.code == 2);
  CHECK(b.err.find("'Rate <Hz>, overflows <n>'") != std::string::npos);
  CHECK(std::count(b.err.begin(), b.err.end(), '\n') == 1);
}
