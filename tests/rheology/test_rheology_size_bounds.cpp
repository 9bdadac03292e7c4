// `tunekit rheo` and `tunekit nozzle --fit` on long files: a 10,000-row viscosity file and a
// 100,000-row nozzle file are fitted (their speed is measured by the benchmarks, not here), and
// a file over the row bound is refused with exit 2 naming the option that raises the bound.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "size_bound_inputs.hpp"
#include "test_support.hpp"

using tunekit::test::run_cli;
using tunekit::test::write_scratch;

namespace {

constexpr double kR = 8.314462618;  // J/(mol K)

// Load-cell nozzle measurements: power law K 2e4 Pa.s^n at 410 degC, n 0.35, Arrhenius
// Ea 50 kJ/mol, through the default nozzle (Boles' model), three temperatures, 2 % noise.
// The pressures are made by the forward command itself at a grid of flows.
std::string nozzle_csv(int rows) {
  std::mt19937 gen(53);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::uniform_real_distribution<double> flow(0.5, 20.0);
  // Pressure of the forward model at 1 mm3/s and 410 degC, scaled: dP ~ K aT Q^n.
  const auto r = run_cli({"nozzle", "--K", "20000", "--n", "0.35", "--flow", "1", "--json"});
  REQUIRE(r.code == 0);
  const double dp1 = nlohmann::json::parse(r.out)["results"]["points"][0]["pressure_drop_Pa"].get<double>();
  std::ostringstream csv;
  csv << "flow (mm3/s),pressure (MPa),temperature (degC)\n";
  const double temps[] = {395, 410, 425};
  for (int i = 0; i < rows; ++i) {
    const double T = temps[i % 3], q = flow(gen);
    const double aT = std::exp(50000.0 / kR * (1 / (T + 273.15) - 1 / (410 + 273.15)));
    csv << q << "," << dp1 * aT * std::pow(q, 0.35) * 1e-6 * std::exp(noise(gen)) << "," << T << "\n";
  }
  return csv.str();
}

}  // namespace

TEST_CASE("rheo: a 10000-row viscosity file is fitted with every row counted") {
  const auto path = write_scratch("rheo_size_10000.csv", tunekit::test::cross_rheometer_csv(10000));
  const auto r = run_cli({"rheo", path, "--model", "cross", "--shift", "arrhenius", "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto res = nlohmann::json::parse(r.out)["results"];
  CHECK(res["num_points"] == 10000);
  CHECK(res["params"]["n"]["value"].get<double>() == Approx(0.3).margin(0.02));
  CHECK(res["params"]["Ea_J_per_mol"]["value"].get<double>() == Approx(66500).epsilon(0.05));
  CHECK(res["model_comparison"]["models"].size() >= 5);
}

TEST_CASE("rheo: a file over the row bound is refused with exit 2 naming --max-rows") {
  const auto path = write_scratch("rheo_size_over.csv", tunekit::test::cross_rheometer_csv(400));
  auto r = run_cli({"rheo", path, "--max-rows", "399"});
  CHECK(r.code == 2);
  CHECK(r.err.starts_with("tunekit: error: "));
  CHECK(r.err.find("--max-rows") != std::string::npos);
  CHECK(r.err.find("399") != std::string::npos);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  // The default bound is far above a rheometer file's hundreds of rows but holds.
  const auto big = write_scratch("rheo_size_default.csv", tunekit::test::cross_rheometer_csv(20004));
  r = run_cli({"rheo", big});
  CHECK(r.code == 2);
  CHECK(r.err.find("--max-rows") != std::string::npos);
  // The bound is range-checked like the other numeric options.
  r = run_cli({"rheo", path, "--max-rows", "0"});
  CHECK(r.code == 2);
}

TEST_CASE("nozzle --fit: a 100000-row measurement file is fitted") {
  const auto path = write_scratch("nozzle_size_100000.csv", nozzle_csv(100000));
  const auto r = run_cli({"nozzle", "--fit", path, "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto res = nlohmann::json::parse(r.out)["results"];
  CHECK(res["params"]["n"]["value"].get<double>() == Approx(0.35).margin(0.01));
  CHECK(res["params"]["K_Pa_s_n"]["value"].get<double>() == Approx(20000).epsilon(0.03));
  CHECK(res["params"]["Ea_J_per_mol"]["value"].get<double>() == Approx(50000).epsilon(0.05));
}

TEST_CASE("nozzle --fit: a file over the row bound is refused with exit 2 naming --max-rows") {
  const auto path = write_scratch("nozzle_size_over.csv", nozzle_csv(300));
  auto r = run_cli({"nozzle", "--fit", path, "--max-rows", "299"});
  CHECK(r.code == 2);
  CHECK(r.err.starts_with("tunekit: error: "));
  CHECK(r.err.find("--max-rows") != std::string::npos);
  CHECK(r.err.find("299") != std::string::npos);
  // Far longer than the bound: refused before the file is parsed, with the same option named.
  r = run_cli({"nozzle", "--fit", path, "--max-rows", "10"});
  CHECK(r.code == 2);
  CHECK(r.err.find("--max-rows") != std::string::npos);
  r = run_cli({"nozzle", "--fit", path, "--max-rows", "-3"});
  CHECK(r.code == 2);
}
