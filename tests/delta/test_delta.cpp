// Delta kinematics, the probe-height model, the calibration fit's interval coverage on the
// simulated delta, the firmware exports (byte-exact fixtures) and the CLI.
#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>
#include <sstream>

#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/ident/delta_calibration.hpp"
#include "tunekit/ident/delta_kinematics.hpp"
#include "tunekit/firmware/delta_export.hpp"
#include "tunekit/sim/delta_probe_sim.hpp"

using namespace tunekit;

namespace {

ident::DeltaGeometry nominal_delta() {
  ident::DeltaGeometry g;
  g.radius_mm = 105.0;
  g.rod_mm = {215.0, 215.0, 215.0};
  g.homed_height_mm = 250.0;
  return g;
}

// Known geometric errors: the truth of the simulated machine.
ident::DeltaGeometry true_delta() {
  auto g = nominal_delta();
  g.endstop_mm = {0.35, -0.20, 0.10};
  g.radius_mm = 104.2;
  g.angle_deg = {210.4, 329.7, 90.0};
  return g;
}

std::string fixture(const std::string& name) {
  return test::read_text(test::dataset("../tests/delta/fixtures/" + name));
}

}  // namespace

TEST_CASE("delta kinematics: forward inverts inverse over the bed") {
  auto g = true_delta();
  g.rod_mm = {214.0, 215.5, 216.0};
  g.tilt_x = 0.001;
  for (double x : {-80.0, 0.0, 37.5, 80.0})
    for (double y : {-80.0, 0.0, 61.0})
      for (double z : {0.0, 12.3, 150.0}) {
        std::array<double, 3> c{};
        REQUIRE(ident::delta_carriages(g, {x, y, z}, c));
        ident::DeltaPoint p;
        REQUIRE(ident::delta_position(g, c, p));
        CHECK(p.x == Approx(x).margin(1e-9));
        CHECK(p.y == Approx(y).margin(1e-9));
        CHECK(p.z == Approx(z).margin(1e-9));
      }
}

TEST_CASE("delta kinematics: carriage height at the centre is z + sqrt(L^2 - R^2)") {
  const auto g = nominal_delta();
  std::array<double, 3> c{};
  REQUIRE(ident::delta_carriages(g, {0, 0, 10}, c));
  for (double v : c) CHECK(v == Approx(10 + std::sqrt(215.0 * 215.0 - 105.0 * 105.0)));
  const auto h = ident::delta_homed_carriages(g);
  for (std::size_t i = 0; i < 3; ++i) CHECK(h[i] == Approx(c[i] + 240.0));
}

TEST_CASE("delta probe model: a correct geometry probes flat, a high endstop reads low towards its tower") {
  const auto g = nominal_delta();
  for (const auto& p : sim::delta_probe_pattern(80, 2, 6))
    CHECK(ident::delta_probe_height(g, g, p.x_mm, p.y_mm) == Approx(0).margin(1e-9));
  auto t = g;
  // Tower C (90 deg, +y) stops 0.3 mm higher: the nozzle stands higher than commanded, most
  // near tower C, so the probe triggers at a lower commanded height there.
  t.endstop_mm[2] = 0.3;
  const double near_c = ident::delta_probe_height(g, t, 0, 80);
  const double centre = ident::delta_probe_height(g, t, 0, 0);
  CHECK(centre == Approx(-0.1).margin(0.01));  // one third of a carriage shift at the centre
  CHECK(near_c < centre);
}

TEST_CASE("delta fit: noiseless probes give back the truth for 6 and 9 factors") {
  const auto n = nominal_delta();
  auto t = true_delta();
  const auto pts = sim::delta_probe_pattern(85, 2, 8);
  auto probes = sim::simulate_delta_probes(n, t, pts, 0.0, 1);
  const auto cal = ident::fit_delta_calibration(n, probes, 6);
  CHECK(cal.fit.value("endstop_a") == Approx(0.35).margin(1e-6));
  CHECK(cal.fit.value("delta_radius") == Approx(104.2).margin(1e-6));
  CHECK(cal.fit.value("angle_a") == Approx(210.4).margin(1e-5));
  CHECK(cal.fit.value("angle_b") == Approx(329.7).margin(1e-5));
  CHECK(cal.after.rms_mm < 1e-6);
  CHECK(cal.before.peak_to_peak_mm > 0.3);

  t.rod_mm = {216.0, 216.0, 216.0};
  t.tilt_x = 0.002;
  t.tilt_y = -0.001;
  const auto pts3 = sim::delta_probe_pattern(85, 3, 12);
  probes = sim::simulate_delta_probes(n, t, pts3, 0.0, 1);
  const auto cal9 = ident::fit_delta_calibration(n, probes, 9);
  CHECK(cal9.fit.value("diagonal_rod") == Approx(216.0).margin(1e-4));
  CHECK(cal9.fit.value("tilt_x") == Approx(0.2).margin(1e-5));
  CHECK(cal9.fit.value("tilt_y") == Approx(-0.1).margin(1e-5));
}

TEST_CASE("delta fit: 9-factor standard errors agree with a finite-difference Jacobian of the height model") {
  // The fit's Jacobian is analytic; the standard errors it gives must be those of the height
  // model differentiated numerically (central differences of delta_true_height).
  const auto n = nominal_delta();
  auto t = true_delta();
  t.rod_mm = {216.0, 216.0, 216.0};
  t.tilt_x = 0.002;
  t.tilt_y = -0.001;
  const auto probes = sim::simulate_delta_probes(n, t, sim::delta_probe_pattern(85, 3, 12), 0.02, 7);
  const auto cal = ident::fit_delta_calibration(n, probes, 9);
  const auto names = ident::delta_factor_names(9);
  const std::size_t k = names.size(), m = probes.size();
  std::vector<double> v;
  for (const auto& name : names) v.push_back(cal.fit.value(name));
  auto heights = [&](const std::vector<double>& x) {
    const auto g = ident::delta_apply_factors(n, 9, x);
    std::vector<double> h(m);
    for (std::size_t i = 0; i < m; ++i) REQUIRE(ident::delta_true_height(n, g, probes[i], h[i]));
    return h;
  };
  std::vector<std::vector<double>> jac(k);  // jac[j][i] = d height_i / d factor_j
  for (std::size_t j = 0; j < k; ++j) {
    constexpr double step = 1e-4;  // mm, degrees, percent
    auto up = v, down = v;
    up[j] += step;
    down[j] -= step;
    const auto hu = heights(up), hd = heights(down);
    for (std::size_t i = 0; i < m; ++i) jac[j].push_back((hu[i] - hd[i]) / (2 * step));
  }
  const auto diag = test::inverse_normal_diagonal(jac);
  const double s2 = cal.fit.diagnostics.rss / static_cast<double>(m - k);
  for (std::size_t j = 0; j < k; ++j) {
    INFO(names[j]);
    CHECK(cal.fit.param(names[j]).std_error == Approx(std::sqrt(s2 * diag[j])).epsilon(1e-5));
  }
}

TEST_CASE("delta fit: 6-factor 95 % intervals cover each true error in 90-99 % of 200 noise draws", "[repeats]") {
  const auto n = nominal_delta();
  const auto t = true_delta();
  const auto pts = sim::delta_probe_pattern(85, 2, 8);
  const std::vector<std::pair<std::string, double>> truth = {{"endstop_a", 0.35}, {"endstop_b", -0.20},
                                                             {"endstop_c", 0.10}, {"delta_radius", 104.2},
                                                             {"angle_a", 210.4},  {"angle_b", 329.7}};
  std::vector<int> covered(truth.size(), 0);
  constexpr int draws = 200;
  for (int d = 0; d < draws; ++d) {
    const auto probes = sim::simulate_delta_probes(n, t, pts, 0.02, 1000 + static_cast<std::uint64_t>(d));
    const auto cal = ident::fit_delta_calibration(n, probes, 6);
    for (std::size_t k = 0; k < truth.size(); ++k) {
      const auto& q = cal.fit.param(truth[k].first);
      if (q.ci95_lo <= truth[k].second && truth[k].second <= q.ci95_hi) ++covered[k];
    }
  }
  for (std::size_t k = 0; k < truth.size(); ++k) {
    INFO(truth[k].first << " covered in " << covered[k] << " of " << draws);
    CHECK(covered[k] >= 180);
    CHECK(covered[k] <= 198);
  }
}

TEST_CASE("delta fit: too few points and unsupported factor counts are input errors") {
  const auto n = nominal_delta();
  std::vector<ident::DeltaProbe> few = {{0, 0, 0.1}, {10, 0, 0.1}, {0, 10, 0.1}};
  CHECK_THROWS_AS(ident::fit_delta_calibration(n, few, 6), InputError);
  CHECK_THROWS_AS(ident::delta_factor_names(5), InputError);
}

TEST_CASE("delta export: Klipper, Marlin and RepRapFirmware text byte-exact against fixtures") {
  auto g = true_delta();
  g.rod_mm = {215.25, 215.25, 215.25};
  CHECK(firmware::delta_klipper_save_config(g) == fixture("klipper_save_config.txt"));
  CHECK(firmware::delta_marlin_gcode(g) == fixture("marlin.gcode"));
  CHECK(firmware::delta_rrf_gcode(g, 85.0) == fixture("rrf_config_override.g"));
}

TEST_CASE("delta export: values a firmware cannot hold are refused") {
  auto g = true_delta();
  g.tilt_x = 0.001;
  CHECK_THROWS_AS(firmware::delta_klipper_save_config(g), InputError);
  CHECK_THROWS_AS(firmware::delta_marlin_gcode(g), InputError);
  CHECK_NOTHROW(firmware::delta_rrf_gcode(g, 85.0));
  g.tilt_x = 0;
  g.rod_mm[1] = 216.0;
  CHECK_THROWS_AS(firmware::delta_marlin_gcode(g), InputError);
  g.radius_mm = std::nan("");
  CHECK_THROWS_AS(firmware::delta_rrf_gcode(g, 85.0), InputError);
  CHECK_THROWS_AS(firmware::delta_rrf_gcode(true_delta(), 0.0), InputError);
}

TEST_CASE("delta CLI: fits a probe CSV and exports, listed in --help") {
  const auto n = nominal_delta();
  const auto probes = sim::simulate_delta_probes(n, true_delta(), sim::delta_probe_pattern(85, 2, 8), 0.01, 7);
  std::ostringstream csv;
  csv << "x_mm,y_mm,z_mm\n";
  for (const auto& p : probes) csv << p.x_mm << "," << p.y_mm << "," << p.z_mm << "\n";
  const auto path = test::write_scratch("delta_probes.csv", csv.str());
  const auto out = test::scratch_dir("delta_cli") + "/printer.cfg.part";
  auto r = test::run_cli({"delta", path, "--radius", "105", "--rod", "215", "--height", "250", "--export", "klipper",
                          "--export-file", out, "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto j = nlohmann::json::parse(r.out);
  CHECK(j["results"]["params"]["delta_radius"]["value"].get<double>() == Approx(104.2).margin(0.1));
  CHECK(j["results"]["flatness_after"]["rms_mm"].get<double>() < 0.02);
  CHECK(test::read_text(out).starts_with("#*# <---------------------- SAVE_CONFIG"));

  r = test::run_cli({"delta", path, "--radius", "105", "--height", "250"});
  CHECK(r.code == 2);
  CHECK(r.err.find("--rod") != std::string::npos);
  const auto bad = test::write_scratch("delta_bad.csv", "x_mm,y_mm\n1,2\n");
  r = test::run_cli({"delta", bad, "--radius", "105", "--rod", "215", "--height", "250"});
  CHECK(r.code == 2);
  r = test::run_cli({"--help"});
  CHECK(r.out.find("delta") != std::string::npos);
}

TEST_CASE("delta probe model agrees with an independent solution of the rod equations") {
  // datasets/delta: heights computed by a separate Newton solution of the three rod
  // equations (see its README), truth and nominal as in true_delta() / nominal_delta().
  const auto t = formats::read_csv(test::dataset("delta/probes_simulated.csv"));
  const auto &x = t.column("x_mm"), &y = t.column("y_mm"), &z = t.column("z_exact_mm");
  REQUIRE(t.rows == 17);
  for (std::size_t i = 0; i < t.rows; ++i)
    CHECK(ident::delta_probe_height(nominal_delta(), true_delta(), x.values[i], y.values[i]) ==
          Approx(z.values[i]).margin(1e-8));
  const auto r = test::run_cli({"delta", test::dataset("delta/probes_simulated.csv"), "--radius", "105", "--rod", "215",
                                "--height", "250", "--json"});
  REQUIRE(r.code == 0);
  const auto j = nlohmann::json::parse(r.out)["results"]["params"];
  for (const auto& [name, truth] : std::vector<std::pair<std::string, double>>{{"endstop_a", 0.35},
                                                                               {"endstop_b", -0.20},
                                                                               {"endstop_c", 0.10},
                                                                               {"delta_radius", 104.2},
                                                                               {"angle_a", 210.4},
                                                                               {"angle_b", 329.7}}) {
    INFO(name);
    CHECK(std::abs(j[name]["value"].get<double>() - truth) < 4 * j[name]["stderr"].get<double>());
  }
}
