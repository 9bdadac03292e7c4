// `tunekit shaper --klipper-compatible` on spectrum files real Klipper printers wrote
// (datasets/klipper_spectra, TEST_RESONANCES output of two printers), against the answer of
// Klipper's own scripts/calibrate_shaper.py on the same files (klipper_reference.csv, produced
// as its PROVENANCE.md says), and tunekit's Klipper-layout spectrum files read back.
#include <catch2/catch.hpp>

#include <cmath>
#include <map>
#include <tuple>
#include <sstream>

#include <nlohmann/json.hpp>

#include "test_support.hpp"

using tunekit::test::dataset;
using tunekit::test::read_text;
using tunekit::test::run_cli;
using tunekit::test::scratch_dir;
using tunekit::test::write_scratch;

namespace {

struct KlipperShaper {
  std::string type;
  double freq_hz = 0;
  double max_accel = 0;        // unrounded
  double suggested_accel = 0;  // as calibrate_shaper.py prints it
  bool recommended = false;
};

// klipper_reference.csv: file -> Klipper's shapers in its order.
std::map<std::string, std::vector<KlipperShaper>> klipper_reference() {
  std::map<std::string, std::vector<KlipperShaper>> ref;
  std::istringstream in(read_text(dataset("klipper_spectra/klipper_reference.csv")));
  std::string line;
  bool header = true;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (header) {
      header = false;
      continue;
    }
    std::vector<std::string> f;
    std::stringstream ls(line);
    for (std::string cell; std::getline(ls, cell, ',');) f.push_back(cell);
    REQUIRE(f.size() == 8);
    ref[f[0]].push_back({f[1], std::stod(f[2]), std::stod(f[5]), std::stod(f[6]), f[7] == "1"});
  }
  return ref;
}

// Checks one axis of `tunekit shaper --json` against Klipper's shapers.
void check_against_klipper(const nlohmann::json& axis, const std::vector<KlipperShaper>& klipper) {
  const auto& cands = axis["candidates"];
  REQUIRE(cands.size() == klipper.size());
  for (std::size_t k = 0; k < klipper.size(); ++k) {
    const auto& c = cands[k];
    INFO("Klipper: " << klipper[k].type << " @ " << klipper[k].freq_hz << " Hz; tunekit: " << c.dump());
    CHECK(c["type"] == klipper[k].type);
    CHECK(std::abs(c["freq_hz"].get<double>() - klipper[k].freq_hz) <= 0.2 + 1e-9);  // one search step
    CHECK(std::abs(c["max_accel_mm_s2"].get<double>() / klipper[k].max_accel - 1) < 0.01);
    CHECK(std::abs(c["suggested_max_accel_mm_s2"].get<double>() / klipper[k].suggested_accel - 1) < 0.01);
    if (klipper[k].recommended) {
      CHECK(axis["recommended"]["type"] == klipper[k].type);
      CHECK(std::abs(axis["recommended"]["freq_hz"].get<double>() - klipper[k].freq_hz) <= 0.2 + 1e-9);
    }
  }
}

// The text output: one line per shaper "  <type> <freq> Hz ... suggested max_accel <= <a> mm/s^2",
// then "recommended: shaper_type_<axis> = <type>  shaper_freq_<axis> = <freq>".
void check_text_against_klipper(const std::string& out, const std::vector<KlipperShaper>& klipper) {
  std::istringstream in(out);
  std::string line;
  std::size_t k = 0;
  bool saw_recommendation = false;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string first;
    ls >> first;
    if (first == "recommended:") {
      std::string key, eq, type, key2, eq2;
      double freq = 0;
      ls >> key >> eq >> type >> key2 >> eq2 >> freq;
      for (const auto& s : klipper)
        if (s.recommended) {
          CHECK(type == s.type);
          CHECK(std::abs(freq - s.freq_hz) <= 0.2 + 1e-9);
        }
      saw_recommendation = true;
      continue;
    }
    if (k >= klipper.size() || first != klipper[k].type) continue;
    double freq = 0;
    ls >> freq;
    INFO(line);
    CHECK(std::abs(freq - klipper[k].freq_hz) <= 0.2 + 1e-9);
    const auto at = line.find("suggested max_accel <= ");
    REQUIRE(at != std::string::npos);
    const double accel = std::stod(line.substr(at + 23));
    CHECK(std::abs(accel / klipper[k].suggested_accel - 1) < 0.01);
    ++k;
  }
  CHECK(k == klipper.size());
  CHECK(saw_recommendation);
}

void check_file(const std::string& name, const std::string& axis) {
  static const auto ref = klipper_reference();
  const auto it = ref.find(name);
  REQUIRE(it != ref.end());
  const std::string path = dataset("klipper_spectra/" + name);
  INFO(name);
  const auto j = run_cli({"shaper", path, "--axis", axis, "--klipper-compatible", "--json"});
  INFO(j.err);
  REQUIRE(j.code == 0);
  const auto doc = nlohmann::json::parse(j.out);
  const auto& a = doc["results"]["axes"][axis];
  check_against_klipper(a, it->second);
  // The file has no shaper columns: its PSD was as measured and got Klipper's normalization.
  CHECK(a["selection"]["psd_normalization"].get<std::string>().find("by tunekit") != std::string::npos);
  CHECK(a["selection"]["max_shaper_freq_hz"].get<double>() == 150.0);

  const auto t = run_cli({"shaper", path, "--axis", axis, "--klipper-compatible"});
  REQUIRE(t.code == 0);
  check_text_against_klipper(t.out, it->second);
}

}  // namespace

TEST_CASE("klipper-compatible shaper on Zippy's TEST_RESONANCES files gives calibrate_shaper.py's answer",
          "[resonance][shaper][klipper]") {
  // Klipper: 3hump_ei @ 100.4 Hz on x (mzv 56.6 Hz), 2hump_ei @ 60.0 Hz on y.
  check_file("resonances_x_20220317_143228.csv", "x");
  check_file("resonances_y_20220317_143943.csv", "y");
}

TEST_CASE("klipper-compatible shaper on a Neptune 4 Pro's spectra gives calibrate_shaper.py's answer",
          "[resonance][shaper][klipper]") {
  // A second printer (spectra Klipper computed from the printer's licensed raw sweeps, as its
  // TEST_RESONANCES writes them): ei @ 89.4 Hz on x, ei @ 92.2 Hz on y.
  check_file("resonances_x_20250509_131744.csv", "x");
  check_file("resonances_y_20250509_125633.csv", "y");
}

TEST_CASE("klipper-compatible shaper with a smoothing limit stops each scan where Klipper stops it",
          "[resonance][shaper][klipper]") {
  // calibrate_shaper.py --max_smoothing 0.08: every type keeps its fewest-vibrations frequency
  // found before the limit (3hump_ei @ 106.4 Hz instead of 100.4 Hz without the limit).
  const auto r = run_cli({"shaper", dataset("klipper_spectra/resonances_x_20220317_143228.csv"), "--axis", "x",
                          "--klipper-compatible", "--max-smoothing", "0.08", "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  check_against_klipper(nlohmann::json::parse(r.out)["results"]["axes"]["x"],
                        klipper_reference().at("resonances_x_20220317_143228.csv@max_smoothing=0.08"));
}

TEST_CASE("klipper-compatible shaper with a vibrations limit prefers fewer vibrations where Klipper does",
          "[resonance][shaper][klipper]") {
  // calibrate_shaper.py -v <per cent> (Klipper 2026, shaper_calibrate.py max_vibrations): Zippy y
  // ei @ 50.0 Hz (2hump_ei @ 60.0 Hz without), Neptune x 3hump_ei @ 123.6 Hz (ei @ 89.4 Hz), Neptune
  // y ei @ 82.8 Hz (ei @ 92.2 Hz).
  const auto ref = klipper_reference();
  const std::vector<std::tuple<std::string, std::string, std::string>> cases = {
      {"resonances_y_20220317_143943.csv", "y", "1"},
      {"resonances_x_20250509_131744.csv", "x", "1"},
      {"resonances_y_20250509_125633.csv", "y", "0.5"}};
  for (const auto& [name, axis, pct] : cases) {
    INFO(name << " --max-vibrations " << pct);
    const auto r = run_cli({"shaper", dataset("klipper_spectra/" + name), "--axis", axis, "--klipper-compatible",
                            "--max-vibrations", pct, "--json"});
    INFO(r.err);
    REQUIRE(r.code == 0);
    const auto doc = nlohmann::json::parse(r.out);
    CHECK(doc["options"]["max_vibrations_pct"].get<double>() == Approx(std::stod(pct)));
    check_against_klipper(doc["results"]["axes"][axis], ref.at(name + "@max_vibrations_pct=" + pct));
  }
  const auto bad = run_cli({"shaper", dataset("klipper_spectra/resonances_y_20250509_125633.csv"), "--axis", "y",
                            "--klipper-compatible", "--max-vibrations", "0.05"});
  CHECK(bad.code == 2);
  CHECK(bad.err.find("--max-vibrations") != std::string::npos);
}

TEST_CASE("a spectrum file tunekit writes in Klipper's layout reads back to the same recommendation",
          "[resonance][shaper][klipper]") {
  const auto ref = klipper_reference();
  const std::string dir = scratch_dir("klipper_csv_roundtrip");
  for (const std::string name : {"resonances_x_20220317_143228.csv", "resonances_x_20250509_131744.csv"}) {
    INFO(name);
    const std::string out = dir + "/calibration_data_x_" + name;
    const auto w =
        run_cli({"shaper", dataset("klipper_spectra/" + name), "--klipper-compatible", "--klipper-csv", out, "--json"});
    INFO(w.err);
    REQUIRE(w.code == 0);
    const auto first = nlohmann::json::parse(w.out)["results"]["axes"]["x"];
    CHECK(first["klipper_csv"] == out);
    const std::string text = read_text(out);
    // Klipper's layout: the dataset columns, then the shaper columns after `shapers:`.
    std::string expect_header = "freq,psd_x,psd_y,psd_z,psd_xyz,shapers:";
    for (const auto& c : first["candidates"]) {
      char buf[64];
      std::snprintf(buf, sizeof buf, ",%s(%.1f)", c["type"].get<std::string>().c_str(), c["freq_hz"].get<double>());
      expect_header += buf;
    }
    CHECK(text.substr(0, text.find('\n')) == expect_header);

    // Read back: with shaper columns the PSD is taken as already normalized (not normalized twice).
    const auto r = run_cli({"shaper", out, "--klipper-compatible", "--json"});
    INFO(r.err);
    REQUIRE(r.code == 0);
    const auto again = nlohmann::json::parse(r.out)["results"]["axes"]["x"];
    CHECK(again["selection"]["psd_normalization"].get<std::string>().find("none applied") != std::string::npos);
    check_against_klipper(again, ref.at(name));
  }
}

TEST_CASE("several recordings of one axis count separately and round-trip through Klipper's several-dataset layout",
          "[resonance][shaper][klipper]") {
  const std::string a = dataset("klipper_spectra/resonances_x_20220317_143228.csv");
  const std::string b = dataset("klipper_spectra/resonances_x_20250509_131744.csv");
  const std::string out = scratch_dir("klipper_csv_multi") + "/two_x.csv";
  const auto w = run_cli({"shaper", a, b, "--klipper-compatible", "--klipper-csv", out, "--json"});
  INFO(w.err);
  REQUIRE(w.code == 0);
  const auto both = nlohmann::json::parse(w.out)["results"]["axes"]["x"];
  CHECK(both["selection"]["datasets"] == 2);
  // Klipper's calibrate_shaper.py given both files: vibrations are the worst over the two.
  check_against_klipper(both,
                        klipper_reference().at("resonances_x_20220317_143228.csv+resonances_x_20250509_131744.csv"));
  const std::string text = read_text(out);
  // One column per recording, named as given (Klipper names them by the file name it was given).
  CHECK(text.rfind("freq," + a + "," + b + ",shapers:", 0) == 0);
  // Every row is on Klipper's 0.2 Hz grid.
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);
  std::getline(in, line);
  CHECK(line.rfind("0.0,", 0) == 0);
  std::getline(in, line);
  CHECK(line.rfind("0.2,", 0) == 0);

  const auto r = run_cli({"shaper", out, "--axis", "x", "--klipper-compatible", "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto again = nlohmann::json::parse(r.out)["results"]["axes"]["x"];
  CHECK(again["selection"]["datasets"] == 2);
  CHECK(again["recommended"]["type"] == both["recommended"]["type"]);
  CHECK(std::abs(again["recommended"]["freq_hz"].get<double>() - both["recommended"]["freq_hz"].get<double>()) <=
        0.2 + 1e-9);
}

TEST_CASE("a normalized file and a measured one of the same axis combine as in calibrate_shaper.py",
          "[resonance][shaper][klipper]") {
  // calibration_data layout (normalized, with shaper columns) written from Zippy's x file, plus
  // the Neptune's measured x file: Klipper normalizes the second only, then scores both.
  const std::string written = scratch_dir("klipper_csv_mixed") + "/calibration_data_x_zippy.csv";
  const auto w = run_cli({"shaper", dataset("klipper_spectra/resonances_x_20220317_143228.csv"), "--klipper-compatible",
                          "--klipper-csv", written});
  REQUIRE(w.code == 0);
  const auto r = run_cli({"shaper", written, dataset("klipper_spectra/resonances_x_20250509_131744.csv"),
                          "--klipper-compatible", "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto a = nlohmann::json::parse(r.out)["results"]["axes"]["x"];
  CHECK(a["selection"]["datasets"] == 2);
  const auto norm = a["selection"]["psd_normalization"].get<std::string>();
  CHECK(norm.find("applied by tunekit to the measured spectra") != std::string::npos);
  CHECK(norm.find("already normalized") != std::string::npos);
  check_against_klipper(a, klipper_reference().at("resonances_x_20220317_143228.csv+resonances_x_20250509_131744.csv"));
}

TEST_CASE("tunekit's own mode on a measured spectrum file states the normalization it applied",
          "[resonance][shaper][klipper]") {
  const auto r = run_cli({"shaper", dataset("klipper_spectra/resonances_x_20220317_143228.csv"), "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto a = nlohmann::json::parse(r.out)["results"]["axes"]["x"];
  CHECK(a["selection"]["method"] == "identified");
  CHECK(a["selection"]["psd_normalization"].get<std::string>().find("f + 0.1") != std::string::npos);
  CHECK(a["psd"]["klipper_normalized"] == false);
  CHECK(a["selection"]["max_shaper_freq_hz"].get<double>() == 200.0);
}

TEST_CASE("bad Klipper spectrum files exit 2 with the reason", "[resonance][shaper][klipper]") {
  std::string good;
  for (int b = 0; b < 20; ++b) good += std::to_string(1.5 * b) + ",1,1,1,3\n";
  SECTION("negative PSD") {
    const auto p =
        write_scratch("resonances_x_negative.csv", "freq,psd_x,psd_y,psd_z,psd_xyz\n" + good + "31.0,1,1,1,-3\n");
    const auto r = run_cli({"shaper", p, "--klipper-compatible"});
    CHECK(r.code == 2);
    CHECK(r.err.find("negative PSD") != std::string::npos);
  }
  SECTION("frequencies out of order") {
    const auto p = write_scratch("resonances_x_order.csv", "freq,psd_x,psd_y,psd_z,psd_xyz\n" + good + "3.0,1,1,1,3\n");
    const auto r = run_cli({"shaper", p, "--klipper-compatible"});
    CHECK(r.code == 2);
    CHECK(r.err.find("resonances_x_order.csv:22") != std::string::npos);
  }
  SECTION("a missing column") {
    const auto p = write_scratch("resonances_x_cols.csv", "freq,psd_x,psd_y,psd_z,psd_xyz\n1.0,1,1,1\n");
    const auto r = run_cli({"shaper", p, "--klipper-compatible"});
    CHECK(r.code == 2);
  }
  SECTION("silent accelerometer") {
    std::string zeros;
    for (int b = 0; b < 20; ++b) zeros += std::to_string(1.5 * b) + ",0,0,0,0\n";
    const auto p = write_scratch("resonances_x_zero.csv", "freq,psd_x,psd_y,psd_z,psd_xyz\n" + zeros);
    const auto r = run_cli({"shaper", p, "--klipper-compatible"});
    CHECK(r.code == 2);
    CHECK(r.err.find("zero everywhere") != std::string::npos);
  }
  SECTION("two axes into one --klipper-csv name") {
    const auto r = run_cli({"shaper", dataset("klipper_spectra/resonances_x_20220317_143228.csv"),
                            dataset("klipper_spectra/resonances_y_20220317_143943.csv"), "--klipper-csv",
                            scratch_dir("klipper_csv_axes") + "/one.csv"});
    CHECK(r.code == 2);
    CHECK(r.err.find("{axis}") != std::string::npos);
  }
}

TEST_CASE("shaper --max-vibrations: 0, -0, empty, nan, inf and out-of-range values are one clear error, exit 2") {
  // Klipper's calibrate_shaper.py takes -v 0 as a limit of 0 %; tunekit refuses what Klipper's
  // own check (below 0.1 %) refuses, and never reads a value it cannot use as "no limit".
  const std::string f = tunekit::test::dataset("klipper_spectra/resonances_x_20220317_143228.csv");
  for (const std::string v : {"0", "-0", "", "nan", "inf", "-5", "1e308", "0.05"}) {
    INFO("--max-vibrations '" << v << "'");
    const auto r = tunekit::test::run_cli({"shaper", f, "--klipper-compatible", "--max-vibrations", v});
    CHECK(r.code == 2);
    CHECK(r.err.find("--max-vibrations") != std::string::npos);
    CHECK(r.out.empty());
  }
}
