// A bed slinger on the simulated printer: its Y axis carries a bed of known effective moving mass
// on a known stiffness, and masses placed on it for each sweep (tunekit run axis-sweep -p load_kg);
// tunekit resonance --load-kg fits f(m) = sqrt(k / (m0 + m)) / (2 pi) to two sweeps and predicts a
// third it did not see.
#include <cmath>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "test_support.hpp"

using tunekit::test::run_cli;

namespace {

// The simulated bed: 0.8 kg moving on a Y mode of 38 Hz (damping ratio 0.07) with the bed empty,
// accelerometer noise well above the default so that the intervals are not all of a few ppm.
const std::vector<std::string> kBed = {"--sim", "bed_moving_mass_kg=0.8", "--sim", "mode_y=38:0.07",
                                       "--sim", "accel_noise_mm_s2=400"};

struct Sweep {
  std::string accel;
  nlohmann::json truth;
};

/// One sweep of Y with `load_kg` on the bed, placed as the protocol asks (the simulator carries it).
Sweep sweep_with_load(const std::string& dir, double load_kg, int seed) {
  std::vector<std::string> args = {"run",       "axis-sweep",
                                   "--axis",    "y",
                                   "--machine", "sim",
                                   "--run-dir", dir,
                                   "-p",        "load_kg=" + std::to_string(load_kg),
                                   "--sim",     "seed=" + std::to_string(seed),
                                   "--json"};
  args.insert(args.end(), kBed.begin(), kBed.end());
  const auto run = run_cli(args);
  INFO(run.err);
  REQUIRE(run.code == 0);
  const auto res = nlohmann::json::parse(run.out)["results"];
  return {res["files"]["accel"].get<std::string>(), res["truth"]};
}

}  // namespace

TEST_CASE("three sweeps of a simulated bed slinger recover its moving mass and stiffness and predict a held-out mass",
          "[bedslinger][e2e]") {
  const std::string dir = tunekit::test::scratch_dir("bed_mass_sim");
  const Sweep empty = sweep_with_load(dir + "/m0", 0.0, 11);
  const Sweep heavy = sweep_with_load(dir + "/m600", 0.6, 12);
  const Sweep held = sweep_with_load(dir + "/m300", 0.3, 13);

  // The run recorded the mass and its place; the simulator carried it.
  const auto run_json = tunekit::test::read_json(dir + "/m600/run.json");
  CHECK(run_json["experiment"]["params"]["load_kg"].get<double>() == Approx(0.6));
  CHECK(run_json["experiment"]["excitation"]["bed_load"]["instruction"].get<std::string>().rfind("place 0.6 kg", 0) ==
        0);
  const auto bed = heavy.truth["axes"]["y"]["bed"];
  CHECK(bed["load_kg"].get<double>() == Approx(0.6));
  const double m0_true = bed["moving_mass_kg"].get<double>();
  const double k_true = bed["stiffness_N_per_m"].get<double>() / 1000;  // N/mm
  CHECK(m0_true == Approx(0.8));

  const auto fit = run_cli({"resonance", empty.accel, heavy.accel, "--axis", "y", "--load-kg", "0", "--load-kg", "0.6",
                            "--held-out", held.accel, "--held-out-load-kg", "0.3", "--json"});
  INFO(fit.err);
  REQUIRE(fit.code == 0);
  const auto r = nlohmann::json::parse(fit.out)["results"]["bed_mass"];
  const auto m0 = r["fit"]["params"]["moving_mass_kg"];
  const auto k = r["fit"]["params"]["stiffness_N_per_mm"];
  INFO(r.dump(1));
  // Both recovered within their 95 % intervals (and the intervals are of a useful width).
  CHECK(m0["ci95"][0].get<double>() <= m0_true);
  CHECK(m0_true <= m0["ci95"][1].get<double>());
  CHECK(k["ci95"][0].get<double>() <= k_true);
  CHECK(k_true <= k["ci95"][1].get<double>());
  CHECK(m0["stderr"].get<double>() < 0.05 * m0_true);
  // m0 and k are strongly correlated (both scale the same frequency ratio).
  CHECK(r["correlation"].get<double>() > 0.5);

  // The held-out mass: predicted within 1 % of what its sweep measured and of the truth.
  const auto& h = r["held_out"][0];
  const double f_held_true = held.truth["axes"]["y"]["modes"][0]["freq_hz"].get<double>();
  CHECK(std::abs(h["relative_error"].get<double>()) < 0.01);
  CHECK(std::abs(h["predicted"]["freq_hz"].get<double>() / f_held_true - 1) < 0.01);
  CHECK(f_held_true == Approx(38 * std::sqrt(0.8 / 1.1)).epsilon(1e-9));

  // The damping ratio falls with the mass, as a fixed viscous damper makes it.
  CHECK(r["damping"]["slope_per_kg"].get<double>() < 0);

  // A sliced 500 g print (PLA, 1.75 mm: 2.98 mg per mm of filament) scheduled from that fit.
  std::string sliced = "M83\nG28\n";
  const double e_layer = 500.0 / (1.24e-3 * M_PI / 4 * 1.75 * 1.75) / 50;
  for (int l = 0; l < 50; ++l)
    sliced += ";LAYER_CHANGE\nG1 Z" + std::to_string(0.2 * (l + 1)) + "\nG1 X50 Y50 E" + std::to_string(e_layer) + "\n";
  const std::string in = tunekit::test::write_scratch("bed_mass_print.gcode", sliced);
  const std::string out = dir + "/bed_mass_print.scheduled.gcode";
  const auto sched = run_cli({"resonance",  empty.accel, heavy.accel,
                              "--axis",     "y",         "--load-kg",
                              "0",          "--load-kg", "0.6",
                              "--gcode-in", in,          "--gcode-out",
                              out,          "--step-hz", "0.25",
                              "--held-out", held.accel,  "--held-out-load-kg",
                              "0.3",        "--plot",    dir + "/bed_mass.svg",
                              "--json"});
  INFO(sched.err);
  REQUIRE(sched.code == 0);
  const auto s = nlohmann::json::parse(sched.out)["results"]["bed_mass"];
  CHECK(s["gcode_post"]["print_mass_g"].get<double>() == Approx(500).epsilon(1e-4));
  const double m0_fit = m0["value"].get<double>(), k_fit = k["value"].get<double>();
  const auto& changes = s["gcode_post"]["changes"];
  REQUIRE(changes.size() >= 10);
  for (const auto& c : changes) {
    const double f = std::sqrt(k_fit * 1000 / (m0_fit + c["mass_g"].get<double>() / 1000)) / (2 * M_PI);
    CHECK(c["freq_hz"].get<double>() == Approx(f).margin(0.005));
  }
  std::ifstream scheduled(out);
  const std::string text((std::istreambuf_iterator<char>(scheduled)), std::istreambuf_iterator<char>());
  CHECK(text.find("SET_INPUT_SHAPER SHAPER_FREQ_Y=") != std::string::npos);
  // The figure: f(m) with its band, the sweeps, the print's mass over its layers.
  std::ifstream svg(dir + "/bed_mass.svg");
  const std::string figure((std::istreambuf_iterator<char>(svg)), std::istreambuf_iterator<char>());
  CHECK(figure.find("<svg") != std::string::npos);
  // Marlin's and Prusa's lines over the file's 500 g.
  CHECK(s["schedule"]["marlin"]["gcode"][1] == "M493 D2");
  CHECK(s["schedule"]["prusa"]["gcode"][1].get<std::string>().rfind("M593 A-", 0) == 0);
}

TEST_CASE("a sweep with a load says what to place and where before the homing move", "[bedslinger]") {
  // The dry run prints what to place, and where, at the top of the protocol; nothing is sent.
  const auto run =
      run_cli({"run", "axis-sweep", "--axis", "y", "--dry-run", "-p", "load_kg=0.25", "-p", "load_x_mm=100"});
  INFO(run.err);
  REQUIRE(run.code == 0);
  const auto at = run.out.find("; bed load: place 0.25 kg on the bed, centred at X100 Y110 (mm)");
  CHECK(at != std::string::npos);
  CHECK(at < run.out.find("G28"));
}

TEST_CASE("the bed mass fit refuses a mass per record that does not match, with exit 2", "[bedslinger]") {
  const auto r = run_cli({"resonance", "a.csv", "b.csv", "--axis", "y", "--load-kg", "0"});
  CHECK(r.code == 2);
  CHECK(r.err.find("--load-kg: 1 masses for 2 records") != std::string::npos);
}
