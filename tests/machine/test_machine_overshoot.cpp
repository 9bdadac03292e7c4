// Axis overshoot and settling (tunekit overshoot) against the simulated printer: the simulator's
// axis mode is known, so the true deviation of the toolhead after each corner is computed here in
// closed form from the mode's frequency and damping and the commanded trapezoidal move, and held
// against what tunekit measured from the accelerometer.
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>
#include <numbers>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "test_support.hpp"

using tunekit::test::run_cli;

namespace {

struct TrueResponse {
  double overshoot_mm = 0, settling_s = 0;
};

// A base-excited mode z'' + 2 zeta w z' + w^2 z = -a(t) (z: toolhead minus commanded position)
// under the piecewise-constant acceleration of a trapezoidal move of length L at speed v and
// acceleration A, by superposing the closed-form responses to acceleration steps.
// The deviation z(t) itself (t from the start of the move), and the move's duration.
struct TrueDeviation {
  double T = 0;
  std::function<double(double)> z;
};

TrueDeviation true_deviation(double f_hz, double zeta, double L, double v, double A) {
  const double w = 2 * std::numbers::pi * f_hz, wd = w * std::sqrt(1 - zeta * zeta);
  double ta = v / A, tc = (L - v * v / A) / v;
  if (tc < 0) {
    ta = std::sqrt(L / A);
    tc = 0;
  }
  const double T = 2 * ta + tc;
  const std::vector<std::pair<double, double>> steps{{0, A}, {ta, -A}, {ta + tc, -A}, {T, A}};
  return {T, [=](double t) {
            double s = 0;
            for (const auto& [tk, ak] : steps) {
              const double tau = t - tk;
              if (tau <= 0) continue;
              s += -ak / (w * w) *
                   (1 - std::exp(-zeta * w * tau) *
                            (std::cos(wd * tau) + zeta / std::sqrt(1 - zeta * zeta) * std::sin(wd * tau)));
            }
            return s;
          }};
}

TrueResponse true_corner_response(double f_hz, double zeta, double L, double v, double A, double band_mm,
                                  double pause_s) {
  const double w = 2 * std::numbers::pi * f_hz, wd = w * std::sqrt(1 - zeta * zeta);
  double ta = v / A, tc = (L - v * v / A) / v;
  if (tc < 0) {
    ta = std::sqrt(L / A);
    tc = 0;
  }
  const double T = 2 * ta + tc;
  const std::pair<double, double> steps[] = {{0, A}, {ta, -A}, {ta + tc, -A}, {T, A}};
  auto z = [&](double t) {
    double s = 0;
    for (const auto& [tk, ak] : steps) {
      const double tau = t - tk;
      if (tau <= 0) continue;
      s += -ak / (w * w) *
           (1 -
            std::exp(-zeta * w * tau) * (std::cos(wd * tau) + zeta / std::sqrt(1 - zeta * zeta) * std::sin(wd * tau)));
    }
    return s;
  };
  TrueResponse r;
  double last_out = T;
  for (double t = T; t <= T + pause_s; t += 1e-5) {
    const double d = z(t);
    r.overshoot_mm = std::max(r.overshoot_mm, d);
    if (std::abs(d) > band_mm) last_out = t;
  }
  r.settling_s = last_out - T;
  return r;
}

}  // namespace

// Runs axis-rectangle on the simulator with known modes and returns the overshoot results.
nlohmann::json overshoot_sim_run(const std::string& name, const std::vector<std::string>& extra_sim) {
  const auto dir = tunekit::test::scratch_dir(name) + "/run";
  std::vector<std::string> args{"run",       "axis-rectangle",
                                "--machine", "sim",
                                "--run-dir", dir,
                                "--sim",     "mode_x=40:0.05",
                                "--sim",     "mode_y=31:0.07",
                                "-p",        "speed_mm_s=150",
                                "-p",        "accel_mm_s2=5000",
                                "-p",        "pause_s=0.6",
                                "-p",        "repeats=2",
                                "--json"};
  for (const auto& e : extra_sim) {
    args.push_back("--sim");
    args.push_back(e);
  }
  const auto run = run_cli(args);
  INFO(run.err);
  REQUIRE(run.code == 0);
  const auto os = run_cli({"overshoot", dir, "--band-mm", "0.01", "--json"});
  INFO(os.err);
  REQUIRE(os.code == 0);
  auto res = nlohmann::json::parse(os.out)["results"];
  res["truth"] = tunekit::test::read_json(dir + "/truth.json")["axes"];
  return res;
}

constexpr double kOsV = 150, kOsA = 5000, kOsL = 40, kOsPause = 0.6, kOsBand = 0.01;

TEST_CASE("overshoot and settling time per corner agree with the mode's true response within 10 % (noise-free sensor)",
          "[machine][e2e][overshoot]") {
  const auto res = overshoot_sim_run("machine_overshoot_clean", {"accel_noise_mm_s2=0", "cross_coupling=0"});
  const auto& corners = res["corners"];
  REQUIRE(corners.size() == 8);  // 4 corners x 2 rectangles, one axis moving into each
  for (const auto& c : corners) {
    const std::string axis = c["axis"];
    const auto& m = res["truth"][axis]["modes"][0];
    const auto tr =
        true_corner_response(m["freq_hz"].get<double>(), m["zeta"].get<double>(), kOsL, kOsV, kOsA, kOsBand, kOsPause);
    INFO("corner " << c["index"].get<int>() << " axis " << axis << ": true overshoot " << tr.overshoot_mm
                   << " mm, settling " << tr.settling_s << " s");
    CHECK(std::abs(c["move_mm"].get<double>()) == Approx(kOsL).epsilon(0.01));
    CHECK(c["overshoot_mm"].get<double>() == Approx(tr.overshoot_mm).epsilon(0.10));
    CHECK(c["settling_time_s"].get<double>() == Approx(tr.settling_s).epsilon(0.10));
    CHECK(c["overshoot_pct"].get<double>() == Approx(100 * tr.overshoot_mm / kOsL).epsilon(0.10));
    // The residual vibration rings at the mode's frequency.
    CHECK(c["residual_freq_hz"].get<double>() == Approx(m["freq_hz"].get<double>()).epsilon(0.03));
  }
}

TEST_CASE(
    "overshoot and settling time averaged over the repeats agree with the true response within 10 % (noisy sensor)",
    "[machine][e2e][overshoot]") {
  // The simulator's default accelerometer: 20 mm/s^2 noise per sample, 5 % cross-coupling.
  // Single corners scatter by up to ~15 % (integrated noise); the rectangle's repeats are
  // averaged, as the thesis averages its five.
  const auto res = overshoot_sim_run("machine_overshoot_noisy", {});
  for (const char* axis : {"x", "y"}) {
    const auto& m = res["truth"][axis]["modes"][0];
    const auto tr =
        true_corner_response(m["freq_hz"].get<double>(), m["zeta"].get<double>(), kOsL, kOsV, kOsA, kOsBand, kOsPause);
    const auto& s = res["axes"][axis];
    INFO("axis " << axis << ": true overshoot " << tr.overshoot_mm << " mm, settling " << tr.settling_s << " s");
    CHECK(s["corners"].get<int>() == 4);
    CHECK(s["mean_overshoot_mm"].get<double>() == Approx(tr.overshoot_mm).epsilon(0.10));
    CHECK(s["mean_settling_time_s"].get<double>() == Approx(tr.settling_s).epsilon(0.10));
    CHECK(s["median_residual_freq_hz"].get<double>() == Approx(m["freq_hz"].get<double>()).epsilon(0.03));
  }
}

TEST_CASE("overshoot of a run without pauses is a bad-input error naming the file", "[machine][overshoot]") {
  const auto csv = tunekit::test::write_scratch("overshoot_flat.csv", [] {
    std::string s = "time,ax,ay,cx,cy\n";
    for (int i = 0; i < 100; ++i) s += std::to_string(i * 0.001) + ",0,0,0,0\n";
    return s;
  }());
  const auto r = run_cli({"overshoot", csv, "--accel-x", "ax", "--accel-y", "ay", "--cmd-x", "cx", "--cmd-y", "cy"});
  CHECK(r.code == 2);
  CHECK(r.err.find("no corner found") != std::string::npos);
}

TEST_CASE(
    "overshoot grid mode maps overshoot and the figure of merit, compares input shaping on/off, and puts the map in "
    "the report",
    "[machine][e2e][overshoot]") {
  const auto out = tunekit::test::scratch_dir("machine_overshoot_grid") + "/grid";
  const auto r = run_cli({"overshoot",
                          "-p",
                          "speed_mm_s=100,200",
                          "-p",
                          "accel_mm_s2=1000,8000",
                          "-p",
                          "repeats=1",
                          "--sim",
                          "mode_x=40:0.05",
                          "--sim",
                          "mode_y=31:0.07",
                          "--shaper",
                          "x=zv:40:0.05",
                          "--shaper",
                          "y=zv:31:0.07",
                          "--tolerance-mm",
                          "0.03",
                          "--out",
                          out,
                          "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto res = nlohmann::json::parse(r.out)["results"];
  REQUIRE(res["grid"].size() == 8);  // 2 speeds x 2 accelerations, shaping off and on
  double os_low = 0, os_high = 0;
  std::map<std::pair<double, double>, double> off;
  for (const auto& c : res["grid"]) {
    // Zero exactly where the tolerance is exceeded.
    CHECK((c["figure_of_merit"].get<double>() > 0) == (c["overshoot_mm"].get<double>() <= 0.03));
    if (c["input_shaping"].get<bool>()) continue;
    off[{c["speed_mm_s"].get<double>(), c["accel_mm_s2"].get<double>()}] = c["overshoot_mm"].get<double>();
    if (c["accel_mm_s2"].get<double>() == 1000) os_low = std::max(os_low, c["overshoot_mm"].get<double>());
    else os_high = std::max(os_high, c["overshoot_mm"].get<double>());
  }
  CHECK(os_high > 2 * os_low);  // the overshoot grows with the acceleration
  // A ZV shaper tuned to the simulated modes removes most of the residual vibration at every point.
  for (const auto& c : res["grid"])
    if (c["input_shaping"].get<bool>())
      CHECK(c["overshoot_mm"].get<double>() <
            0.25 * off.at({c["speed_mm_s"].get<double>(), c["accel_mm_s2"].get<double>()}));
  REQUIRE(res.contains("best"));
  REQUIRE(res.contains("best_shaped"));
  CHECK(res["best_shaped"]["accel_mm_s2"].get<double>() ==
        8000);  // shaped, the highest acceleration is within tolerance
  for (const auto& c : res["grid"]) {
    const auto& b = c["input_shaping"].get<bool>() ? res["best_shaped"] : res["best"];
    CHECK(c["figure_of_merit"].get<double>() <= b["figure_of_merit"].get<double>());
  }
  const auto html = tunekit::test::read_text(out + "/report.html");
  CHECK(tunekit::test::embedded_image_base64_length(html, "overshoot_grid") > 1000);
  CHECK(html.find("fastest speed within tolerance") != std::string::npos);
  // The report was rendered from the grid's record in memory; `tunekit report` renders the same
  // from results.json and plotdata.json, byte for byte (the report holds no generation time).
  const auto again = run_cli({"report", out});
  INFO(again.err);
  REQUIRE(again.code == 0);
  CHECK((tunekit::test::read_text(out + "/report.html") == html));  // not decomposed: no report text on failure
}

TEST_CASE("overshoot from an encoder column agrees with the closed-form response within 10 %", "[machine][overshoot]") {
  // An encoder log (position in mm) of one 40 mm move between two rests: commanded trapezoid plus
  // the 35 Hz / 0.06 mode's deviation, sampled at 5 kHz with 1 um quantization.
  const double f = 35, zeta = 0.06, L = 40, v = 120, A = 4000, rest = 0.3, pause = 0.7, band = 0.01;
  const auto dev = true_deviation(f, zeta, L, v, A);
  const double ta = v / A, tc = (L - v * v / A) / v;
  auto cmd = [&](double t) {
    if (t <= 0) return 0.0;
    if (t < ta) return 0.5 * A * t * t;
    if (t < ta + tc) return 0.5 * A * ta * ta + v * (t - ta);
    if (t < dev.T) return L - 0.5 * A * (dev.T - t) * (dev.T - t);
    return L;
  };
  std::string csv = "t_s,x_mm\n";
  for (double t = 0; t < rest + dev.T + pause; t += 2e-4) {
    const double x = 10 + cmd(t - rest) + dev.z(t - rest);
    csv += std::to_string(t) + "," + std::to_string(std::round(x * 1000) / 1000) + "\n";
  }
  const auto path = tunekit::test::write_scratch("overshoot_encoder.csv", csv);
  const auto tr = true_corner_response(f, zeta, L, v, A, band, pause);
  const auto r = run_cli({"overshoot", path, "--time", "t_s", "--position-x", "x_mm", "--band-mm", "0.01", "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto c = nlohmann::json::parse(r.out)["results"]["corners"];
  REQUIRE(c.size() == 1);
  INFO("true overshoot " << tr.overshoot_mm << " mm, settling " << tr.settling_s << " s");
  CHECK(c[0]["move_mm"].get<double>() == Approx(L).epsilon(0.001));
  CHECK(c[0]["overshoot_mm"].get<double>() == Approx(tr.overshoot_mm).epsilon(0.10));
  CHECK(c[0]["settling_time_s"].get<double>() == Approx(tr.settling_s).epsilon(0.10));
  CHECK(c[0]["residual_freq_hz"].get<double>() == Approx(f).epsilon(0.03));
}
