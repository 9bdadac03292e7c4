// `tunekit resonance` and `tunekit shaper` end to end on synthetic Klipper files, and their
// refusals (exit 2) or warnings for bad input.
#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>
#include <iterator>

#include <nlohmann/json.hpp>

#include "synth_sweep.hpp"
#include "test_support.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/firmware/firmware_limits.hpp"

using tunekit::test::run_cli;
using tunekit::test::SweepSpec;
using tunekit::test::SynthMode;
using tunekit::test::write_scratch;

namespace {

// A shorter sweep (20 -> 100 Hz at 2 Hz/s, 40 s) keeps the CLI tests fast.
SweepSpec short_sweep(unsigned seed) {
  SweepSpec s;
  s.f_start_hz = 20;
  s.f_end_hz = 100;
  s.hz_per_sec = 2;
  s.seed = seed;
  return s;
}

const std::vector<SynthMode> kTruthX = {{44.0, 0.06, 1.0}};
const std::vector<SynthMode> kTruthY = {{37.0, 0.05, 1.0}, {71.0, 0.07, 0.5}};

const std::string& x_file() {
  static const std::string p = write_scratch(
      "raw_data_x_test.csv", tunekit::test::to_klipper_csv(tunekit::test::synth_sweep(kTruthX, short_sweep(1))));
  return p;
}
const std::string& y_file() {
  static const std::string p = write_scratch(
      "raw_data_y_test.csv", tunekit::test::to_klipper_csv(tunekit::test::synth_sweep(kTruthY, short_sweep(2))));
  return p;
}

std::string numeric_rows(double t0, double dt, int n, const char* extra = "") {
  std::string s;
  for (int i = 0; i < n; ++i)
    s += std::to_string(t0 + dt * i) + "," + std::to_string(100.0 * std::sin(0.3 * i)) + ",1.0,9806.0" + extra + "\n";
  return s;
}

}  // namespace

TEST_CASE("resonance --json reports modes with intervals and the PSD for each axis", "[resonance][cli]") {
  const auto r = run_cli({"resonance", x_file(), y_file(), "--json", "--fit-min", "20", "--fit-max", "100"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto j = nlohmann::json::parse(r.out);
  const auto& axes = j["results"]["axes"];
  REQUIRE(axes.contains("x"));
  REQUIRE(axes.contains("y"));
  for (const auto& [ax, truth] : {std::pair{std::string("x"), kTruthX}, std::pair{std::string("y"), kTruthY}}) {
    const auto& modes = axes[ax]["modes"];
    REQUIRE(modes.size() == truth.size());
    for (std::size_t k = 0; k < truth.size(); ++k) {
      INFO(ax << " mode " << k << ": " << modes[k].dump());
      CHECK(std::abs(modes[k]["freq_hz"].get<double>() / truth[k].freq_hz - 1) < 0.01);
      CHECK(std::abs(modes[k]["zeta"].get<double>() / truth[k].zeta - 1) < 0.2);
      // Interval coverage is asserted at Klipper's 1 Hz/s in test_modes.cpp; this 2 Hz/s sweep is
      // fast enough for the quasi-stationary model to be off by ~0.05 %, more than its (statistical)
      // interval at this signal-to-noise ratio, so here only the interval's shape is checked.
      CHECK(modes[k]["freq_ci95"][0].get<double>() < modes[k]["freq_hz"].get<double>());
      CHECK(modes[k]["freq_ci95"][1].get<double>() > modes[k]["freq_hz"].get<double>());
      CHECK(modes[k]["zeta_ci95"][0].get<double>() < modes[k]["zeta"].get<double>());
      CHECK(modes[k]["zeta_ci95"][1].get<double>() > modes[k]["zeta"].get<double>());
    }
    const auto& psd = axes[ax]["psd"];
    CHECK(psd["freq_hz"].size() == psd["psd"].size());
    CHECK(psd["freq_hz"].back().get<double>() <= 200.0);
    CHECK(psd["window"] == "kaiser");
  }
  // The dominant mode is exposed for CI thresholds.
  const auto req =
      run_cli({"resonance", x_file(), "--fit-min", "20", "--fit-max", "100", "--require", "x.freq_hz>=50"});
  CHECK(req.code == 1);
  CHECK(req.err.find("requirement not met") != std::string::npos);
}

TEST_CASE("shaper --json gives recommended and every candidate with the contract's fields", "[resonance][cli]") {
  for (bool klipper : {false, true}) {
    std::vector<std::string> args = {"shaper", x_file(), y_file(), "--json", "--fit-min", "20", "--fit-max", "100"};
    if (klipper) args.push_back("--klipper-compatible");
    const auto r = run_cli(args);
    INFO(r.err);
    REQUIRE(r.code == 0);
    const auto j = nlohmann::json::parse(r.out);
    for (const char* ax : {"x", "y"}) {
      const auto& a = j["results"]["axes"][ax];
      INFO(ax << " klipper " << klipper << " " << a["recommended"].dump());
      for (const char* k : {"type", "freq_hz", "damping", "vibrations_pct", "smoothing", "max_accel_mm_s2"})
        CHECK(a["recommended"].contains(k));
      // Without --firmware, Klipper is assumed: its shapers (all seven types but zvdd) are compared.
      CHECK(a["candidates"].size() == (klipper ? 5u : std::size(tunekit::firmware::limits::kKlipperShapers)));
      for (const auto& c : a["candidates"])
        for (const char* k : {"type", "freq_hz", "damping", "vibrations_pct", "smoothing", "max_accel_mm_s2"})
          CHECK(c.contains(k));
      CHECK(a["recommended"]["vibrations_pct"].get<double>() < 20.0);
      CHECK(a["selection"]["method"] == (klipper ? "klipper" : "identified"));
      if (klipper) {
        CHECK(a["recommended"]["damping"].get<double>() == 0.1);
      } else {
        // Designed for the identified damping ratio of the dominant mode.
        const double z = a["zeta"].get<double>();
        const double dz = a["recommended"]["damping"].get<double>();
        CHECK(dz == Approx(z).epsilon(1e-12));
      }
    }
  }
}

TEST_CASE("resonance and shaper --help explain how to feed Klipper's files", "[resonance][cli]") {
  for (const char* cmd : {"resonance", "shaper"}) {
    const auto r = run_cli({cmd, "--help"});
    CHECK(r.code == 0);
    CHECK(r.out.find("raw_data_x_") != std::string::npos);
    CHECK(r.out.find("calibration_data_") != std::string::npos);
    CHECK(r.out.find("Examples:") != std::string::npos);
  }
}

TEST_CASE("Klipper calibration data is accepted", "[resonance][cli]") {
  // Lorentzian-like normalized PSD as SHAPER_CALIBRATE saves it (0.1 Hz-rounded bins, shaper
  // response columns after `shapers:`, which tell that the PSD is already normalized).
  std::string csv = "freq,psd_x,psd_y,psd_z,psd_xyz,shapers:,mzv(48.0)\n";
  for (int b = 0; b < 128; ++b) {
    const double f = 1.5625 * b, r = f / 48.0;
    const double p = f * 1e3 / ((1 - r * r) * (1 - r * r) + (0.1 * r) * (0.1 * r)) / (f + 0.1) + 1.0;
    char line[200];
    std::snprintf(line, sizeof line, "%.1f,%.3e,%.3e,%.3e,%.3e,,0.500\n", f, p, 1.0, 1.0, p + 2.0);
    csv += line;
  }
  const auto path = write_scratch("calibration_data_x_test.csv", csv);
  const auto r = run_cli({"shaper", path, "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto j = nlohmann::json::parse(r.out);
  const auto& x = j["results"]["axes"]["x"];
  REQUIRE(x["modes"].size() >= 1);
  CHECK(std::abs(x["modes"][0]["freq_hz"].get<double>() - 48.0) < 1.5);
  CHECK(x["psd"]["klipper_normalized"] == true);
}

TEST_CASE("bad accelerometer input exits 2 with the reason", "[resonance][cli]") {
  const std::string header = "#time,accel_x,accel_y,accel_z\n";
  SECTION("wrong columns") {
    const auto r = run_cli({"resonance", x_file(), "--accel", "acc_x"});
    CHECK(r.code == 2);
    CHECK(r.err.find("acc_x") != std::string::npos);
  }
  SECTION("fewer than two PSD segments") {
    // shaper needs a spectrum; resonance would analyse such a record as a ring-down.
    const auto p = write_scratch("raw_data_x_short.csv", header + numeric_rows(0, 1.0 / 3200, 2500));
    const auto r = run_cli({"shaper", p});
    CHECK(r.code == 2);
    CHECK(r.err.find("two segments") != std::string::npos);
  }
  SECTION("non-monotonic time") {
    std::string rows = numeric_rows(0, 1.0 / 3200, 5000);
    rows += "0.5,1,1,1\n";
    const auto p = write_scratch("raw_data_x_backwards.csv", header + rows);
    const auto r = run_cli({"resonance", p});
    CHECK(r.code == 2);
    CHECK(r.err.find("backwards") != std::string::npos);
  }
  SECTION("all-zero data") {
    std::string rows;
    for (int i = 0; i < 8000; ++i) rows += std::to_string(i / 3200.0) + ",0,0,0\n";
    const auto p = write_scratch("raw_data_x_zero.csv", header + rows);
    const auto r = run_cli({"resonance", p});
    CHECK(r.code == 2);
    CHECK(r.err.find("all zero") != std::string::npos);
  }
  SECTION("clipped data") {
    auto spec = short_sweep(3);
    spec.clip_mm_s2 = 6000;  // well below the resonance peak
    const auto p = write_scratch("raw_data_x_clipped.csv",
                                 tunekit::test::to_klipper_csv(tunekit::test::synth_sweep(kTruthX, spec)));
    const auto r = run_cli({"shaper", p});
    CHECK(r.code == 2);
    CHECK(r.err.find("clipped") != std::string::npos);
  }
  SECTION("large gap in the time column") {
    std::string rows = numeric_rows(0, 1.0 / 3200, 6000) + numeric_rows(6000.0 / 3200 + 0.5, 1.0 / 3200, 6000);
    const auto p = write_scratch("raw_data_x_gap.csv", header + rows);
    const auto r = run_cli({"resonance", p});
    CHECK(r.code == 2);
    CHECK(r.err.find("irregular sampling") != std::string::npos);
  }
}

TEST_CASE("a file whose name names no axis is analysed under its file stem, and needs --axis only to be exported",
          "[resonance][cli]") {
  const std::string csv = tunekit::test::to_klipper_csv(tunekit::test::synth_sweep(kTruthX, short_sweep(4)));
  const auto p = write_scratch("accel_log.csv", csv);
  const auto r = run_cli({"resonance", p, "--json", "--fit-min", "20", "--fit-max", "100"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto j = nlohmann::json::parse(r.out);
  const auto& axes = j["results"]["axes"];
  REQUIRE(axes.contains("accel_log"));
  CHECK(axes["accel_log"]["freq_hz"].get<double>() == Approx(44.0).epsilon(0.02));
  // The same file with --axis is the x axis.
  const auto named = run_cli({"resonance", p, "--axis", "x", "--json", "--fit-min", "20", "--fit-max", "100"});
  REQUIRE(named.code == 0);
  CHECK(nlohmann::json::parse(named.out)["results"]["axes"].contains("x"));
  // A shaper result under a file stem is not exported, and the warning says how to name the axis.
  const std::string dir = tunekit::test::scratch_dir("stem_export");
  const auto sh = run_cli({"shaper", p, "--json", "-o", dir + "/shaper.json"});
  INFO(sh.err);
  REQUIRE(sh.code == 0);
  const std::string cfg = tunekit::test::write_scratch("stem_printer.cfg", "[printer]\nkinematics: cartesian\n");
  const auto e = run_cli({"export", "-f", "klipper", "-c", cfg, dir + "/shaper.json"});
  INFO(e.out << e.err);
  CHECK(e.code == 2);
  CHECK(e.err.find("names no axis") != std::string::npos);
  CHECK(e.err.find("--axis x") != std::string::npos);
  CHECK(e.out.find("shaper_freq") == std::string::npos);
}

TEST_CASE("a few clipped samples or a few dropped samples give a warning, not an error", "[resonance][cli]") {
  SECTION("clipping") {
    auto spec = short_sweep(4);
    spec.clip_mm_s2 = 20000;  // the resonance peak reaches about 22000
    const auto p = write_scratch("raw_data_x_lightclip.csv",
                                 tunekit::test::to_klipper_csv(tunekit::test::synth_sweep(kTruthX, spec)));
    const auto r = run_cli({"resonance", p, "--json", "--fit-min", "20", "--fit-max", "100"});
    INFO(r.err);
    REQUIRE(r.code == 0);
    CHECK(r.err.find("clipped samples") != std::string::npos);
  }
  SECTION("dropped samples are resampled") {
    auto rec = tunekit::test::synth_sweep(kTruthX, short_sweep(5));
    for (std::size_t i = 10000; i < rec.t.size(); i += 20000) {  // drop a few single samples
      rec.t.erase(rec.t.begin() + static_cast<std::ptrdiff_t>(i));
      rec.ax.erase(rec.ax.begin() + static_cast<std::ptrdiff_t>(i));
      rec.ay.erase(rec.ay.begin() + static_cast<std::ptrdiff_t>(i));
      rec.az.erase(rec.az.begin() + static_cast<std::ptrdiff_t>(i));
    }
    const auto p = write_scratch("raw_data_x_dropped.csv", tunekit::test::to_klipper_csv(rec));
    const auto r = run_cli({"resonance", p, "--json", "--fit-min", "20", "--fit-max", "100"});
    INFO(r.err);
    REQUIRE(r.code == 0);
    CHECK(r.err.find("resampled") != std::string::npos);
    const auto j = nlohmann::json::parse(r.out);
    CHECK(std::abs(j["results"]["axes"]["x"]["modes"][0]["freq_hz"].get<double>() / 44.0 - 1) < 0.01);
  }
}

TEST_CASE("shaper: the input's SHA-256 is in every envelope that leaves the process, --json and the results file",
          "[resonance][cli]") {
  const std::string digest = tunekit::calibration::sha256_hex(tunekit::test::read_text(x_file()));
  REQUIRE(digest.size() == 64);
  const auto r = run_cli({"shaper", x_file(), "--json"});
  REQUIRE(r.code == 0);
  CHECK(nlohmann::json::parse(r.out)["inputs"][0]["sha256"] == digest);
  const std::string results = write_scratch("shaper_digest_results.json", "");
  const auto t = run_cli({"shaper", x_file(), "-o", results});
  REQUIRE(t.code == 0);
  CHECK(t.out.find("shaper") != std::string::npos);  // the terminal summary, without the envelope
  CHECK(nlohmann::json::parse(tunekit::test::read_text(results))["inputs"][0]["sha256"] == digest);
}
