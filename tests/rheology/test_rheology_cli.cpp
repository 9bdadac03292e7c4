// `tunekit rheo` and `tunekit nozzle` end to end: JSON field names other work relies on,
// worked examples, and exit code 2 with the reason for bad input.
#include <catch2/catch.hpp>

#include <algorithm>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "test_support.hpp"

using tunekit::test::dataset;
using tunekit::test::run_cli;
using tunekit::test::write_scratch;

TEST_CASE("rheo --model cross-wlf --json: parameters, comparison and prediction") {
  const auto r = run_cli({"rheo", dataset("rheology/peek_cross_wlf_synthetic.csv"), "--model", "cross-wlf", "--json",
                          "--nozzle-d", "0.6", "--nozzle-l", "4", "--cone-angle", "30", "--entrance-D", "5",
                          "--predict-at", "405", "--reference-flow", "3", "--power-law-window", "600:950"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto j = nlohmann::json::parse(r.out);
  const auto& res = j["results"];
  CHECK(res["model"] == "cross-wlf");
  for (const char* k : {"n", "tau_star_Pa", "D1_Pa_s", "D2_K", "D3_K_per_Pa", "A1", "A2_K"}) {
    INFO(k);
    REQUIRE(res["params"].contains(k));
    CHECK(res["params"][k].contains("value"));
    CHECK(res["params"][k].contains("stderr"));
    CHECK(res["params"][k]["ci95"].size() == 2);
    CHECK(res["params"][k].contains("unit"));
  }
  CHECK(res["params"]["tau_star_Pa"]["unit"] == "Pa");
  CHECK(res["diagnostics"]["converged"] == true);
  // The synthetic set was made from PEEK's Table 2.4 values.
  CHECK(res["params"]["n"]["value"].get<double>() == Approx(0.4266).epsilon(0.1));
  REQUIRE(res.contains("model_comparison"));
  CHECK(res["model_comparison"]["models"].size() >= 5);
  CHECK(!res["model_comparison"]["best"].get<std::string>().empty());
  const auto& p = res["prediction"];
  for (const char* k : {"temperature_K", "flow_mm3_s", "dP_dQ_Pa_s_per_mm3", "relative_tau", "reference_flow_mm3_s"})
    CHECK(p.contains(k));
  CHECK(p["temperature_K"].get<double>() == Approx(678.15));
  CHECK(p["reference_flow_mm3_s"].get<double>() == 3.0);
  REQUIRE(p["flow_mm3_s"].size() == p["relative_tau"].size());
  for (std::size_t i = 0; i < p["flow_mm3_s"].size(); ++i)
    if (p["flow_mm3_s"][i].get<double>() == 3.0) CHECK(p["relative_tau"][i].get<double>() == Approx(1.0));
  CHECK(res["power_law"]["fits"].size() == 3);
  // Deterministic output.
  const auto again = run_cli({"rheo", dataset("rheology/peek_cross_wlf_synthetic.csv"), "--model", "cross-wlf",
                              "--json", "--nozzle-d", "0.6", "--nozzle-l", "4", "--cone-angle", "30", "--entrance-D",
                              "5", "--predict-at", "405", "--reference-flow", "3", "--power-law-window", "600:950"});
  CHECK(again.out == r.out);
}

TEST_CASE("rheo refuses bad input with exit code 2 and the reason") {
  const std::string head = "shear_rate (1/s),viscosity (Pa.s),temperature (degC)\n";
  SECTION("negative shear rate") {
    const auto f = write_scratch("rheo_neg.csv", head + "10,1000,400\n-5,900,400\n100,800,400\n");
    const auto r = run_cli({"rheo", f, "--model", "cross", "--no-compare"});
    CHECK(r.code == 2);
    CHECK(r.err.find("negative shear rate") != std::string::npos);
    CHECK(r.err.find("rheo_neg.csv:3") != std::string::npos);
  }
  SECTION("a single temperature for a temperature-dependent model") {
    const auto f = write_scratch("rheo_oneT.csv", head +
                                                      "1,3000,400\n10,2500,400\n100,1200,400\n1000,350,400\n"
                                                      "3000,180,400\n10000,80,400\n");
    const auto r = run_cli({"rheo", f, "--model", "cross-wlf"});
    CHECK(r.code == 2);
    CHECK(r.err.find("single temperature") != std::string::npos);
  }
  SECTION("fewer points than parameters") {
    const auto f = write_scratch("rheo_few.csv", head + "1,3000,400\n10,2500,400\n");
    const auto r = run_cli({"rheo", f, "--model", "cross", "--no-compare"});
    CHECK(r.code == 2);
    CHECK(r.err.find("data points for 3 free parameters") != std::string::npos);
  }
  SECTION("viscosity in mPa.s labelled Pa.s: let through with a warning that names the row and the unit") {
    // Magnitude alone cannot prove a unit mix-up (real melts exceed 1e6 Pa.s), so it is a warning.
    const auto f = write_scratch("rheo_mpa.csv", head +
                                                     "1,3.0e6,400\n10,2.5e6,400\n100,1.2e6,400\n1000,3.5e5,400\n"
                                                     "3000,1.8e5,400\n");
    const auto r = run_cli({"rheo", f, "--model", "cross", "--no-compare"});
    INFO(r.err);
    CHECK(r.code == 0);
    CHECK(r.err.find("rheo_mpa.csv:2: viscosity 3e+06 Pa.s") != std::string::npos);
    CHECK(r.err.find("mPa.s") != std::string::npos);
  }
  SECTION("a flow curve that falls is let through with a located warning") {
    // eta drops 100-fold while gamma rises 10-fold: the stress falls (a mix-up or instability).
    const auto f = write_scratch("rheo_falling_stress.csv", head +
                                                                "1,3000,400\n10,2500,400\n100,25,400\n1000,20,400\n"
                                                                "3000,15,400\n");
    const auto r = run_cli({"rheo", f, "--model", "cross", "--no-compare"});
    INFO(r.err);
    CHECK(r.err.find("rheo_falling_stress.csv:4: the shear stress falls from 25000 to 2500 Pa") != std::string::npos);
  }
  SECTION("viscosity and shear-stress columns that disagree by a unit factor are refused") {
    const auto f = write_scratch("rheo_inconsistent.csv",
                                 "shear_rate (1/s),viscosity (Pa.s),shear_stress (Pa),temperature (degC)\n"
                                 "1,3.0e6,3.0e3,400\n10,2.5e6,2.5e4,400\n100,1.2e6,1.2e5,400\n1000,3.5e5,3.5e5,400\n"
                                 "3000,1.8e5,5.4e5,400\n");
    const auto r = run_cli({"rheo", f, "--model", "cross", "--no-compare"});
    CHECK(r.code == 2);
    CHECK(r.err.find("disagree") != std::string::npos);
    CHECK(r.err.find("0.001 times") != std::string::npos);
  }
  SECTION("--viscosity-unit states the unit of a header without one, and may not contradict a header") {
    const auto f = write_scratch("rheo_nounit_eta.csv",
                                 "shear_rate (1/s),viscosity,temperature (degC)\n1,3.0e6,400\n10,2.5e6,400\n"
                                 "100,1.2e6,400\n1000,3.5e5,400\n3000,1.8e5,400\n10000,8e4,400\n");
    const auto r = run_cli({"rheo", f, "--model", "cross", "--no-compare", "--viscosity-unit", "mPa.s", "--json"});
    INFO(r.err);
    REQUIRE(r.code == 0);
    const auto j = nlohmann::json::parse(r.out);
    // 3e6 mPa.s = 3000 Pa.s: the plateau comes out in Pa.s, and no magnitude warning.
    CHECK(j["results"]["params"]["eta0_Pa_s"]["value"].get<double>() == Approx(3000).epsilon(0.3));
    CHECK(r.err.find("above 1e+06") == std::string::npos);
    const auto g = write_scratch("rheo_unit_clash.csv", head + "1,3000,400\n10,2500,400\n100,1200,400\n1000,350,400\n");
    const auto bad = run_cli({"rheo", g, "--model", "cross", "--no-compare", "--viscosity-unit", "P"});
    CHECK(bad.code == 2);
    CHECK(bad.err.find("the viscosity column says 'Pa.s'") != std::string::npos);
  }
  SECTION("the same data labelled mPa.s are converted and fitted") {
    const auto f = write_scratch("rheo_mpa_ok.csv",
                                 "shear_rate (1/s),viscosity (mPa.s),temperature (degC)\n1,3.0e6,400\n10,2.5e6,400\n"
                                 "100,1.2e6,400\n1000,3.5e5,400\n3000,1.8e5,400\n10000,8e4,400\n");
    const auto r = run_cli({"rheo", f, "--model", "cross", "--no-compare", "--json"});
    INFO(r.err);
    CHECK(r.code == 0);
  }
  SECTION("degC values in a column labelled K") {
    const auto f = write_scratch("rheo_k.csv",
                                 "shear_rate (1/s),viscosity (Pa.s),temperature (K)\n1,3000,180\n"
                                 "10,2500,180\n100,1200,200\n1000,350,200\n");
    const auto r = run_cli({"rheo", f, "--model", "cross-wlf"});
    CHECK(r.code == 2);
    CHECK(r.err.find("look like degC") != std::string::npos);
  }
  SECTION("a temperature without a unit") {
    const auto f = write_scratch("rheo_nounit.csv", "shear_rate (1/s),viscosity (Pa.s),temperature\n1,3000,400\n");
    const auto r = run_cli({"rheo", f});
    CHECK(r.code == 2);
    CHECK(r.err.find("no unit") != std::string::npos);
  }
}

TEST_CASE("nozzle: forward examples of the seed and the inverse fit") {
  {
    const auto r = run_cli({"nozzle", "--K", "10114", "--n", "0.51", "--flow", "20", "--cone-angle", "45", "--json"});
    INFO(r.err);
    REQUIRE(r.code == 0);
    const auto j = nlohmann::json::parse(r.out);
    CHECK(j["results"]["points"][0]["pressure_drop_MPa"].get<double>() == Approx(12.164).epsilon(5e-4));
  }
  {
    const auto r = run_cli({"nozzle", "--material", "peek-power-law", "-T", "405", "--flow", "3", "--json"});
    INFO(r.err);
    REQUIRE(r.code == 0);
    const auto j = nlohmann::json::parse(r.out);
    CHECK(j["results"]["points"][0]["pressure_drop_MPa"].get<double>() == Approx(4.980).epsilon(2e-3));
    CHECK(j["results"].contains("prediction"));
  }
  {
    const auto r = run_cli({"nozzle", "--fit", dataset("rheology/nozzle_pressure_synthetic.csv"), "--json"});
    INFO(r.err);
    REQUIRE(r.code == 0);
    const auto j = nlohmann::json::parse(r.out);
    const auto& ps = j["results"]["params"];
    CHECK(ps["n"]["ci95"][0].get<double>() <= 0.539);
    CHECK(ps["n"]["ci95"][1].get<double>() >= 0.539);
    CHECK(ps["K_Pa_s_n"]["ci95"][0].get<double>() <= 7988);
    CHECK(ps["K_Pa_s_n"]["ci95"][1].get<double>() >= 7988);
  }
  {
    const auto r = run_cli({"nozzle", "--flow", "3"});
    CHECK(r.code == 2);
    CHECK(r.err.find("rheology one way") != std::string::npos);
  }
  {
    const auto r = run_cli({"nozzle", "--K", "8000", "--n", "0.5", "--flow", "3", "--nozzle-d", "6"});
    CHECK(r.code == 2);
  }
  {
    const auto r = run_cli({"nozzle", "--help"});
    CHECK(r.out.find("Examples") != std::string::npos);
  }
}

TEST_CASE(
    "rheo fits a rheometer export with its own column names through --shear-rate, --viscosity and --temperature-col") {
  // The synthetic PEEK set rewritten as a German-language rheometer export: semicolons, units in
  // brackets with UTF-8 symbols, names the reader cannot guess.
  const std::string src = tunekit::test::read_text(dataset("rheology/peek_cross_wlf_synthetic.csv"));
  std::string body =
      "Messpunkt;Scherrate [1/s];Viskosit\xc3\xa4t [Pa\xc2\xb7s];Temperatur [\xc2\xb0"
      "C]\n";
  std::istringstream in(src);
  std::string line;
  int row = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line.find("shear_rate") != std::string::npos) continue;
    std::replace(line.begin(), line.end(), ',', ';');
    body += std::to_string(++row) + ";" + line + "\n";
  }
  REQUIRE(row > 20);
  const std::string path = write_scratch("rheometer_export.csv", body);

  const auto refused = run_cli({"rheo", path, "--model", "cross-wlf"});
  CHECK(refused.code == 2);
  CHECK(refused.err.find("no shear-rate column") != std::string::npos);
  CHECK(refused.err.find("--shear-rate") != std::string::npos);

  const auto r = run_cli({"rheo", path, "--model", "cross-wlf", "--no-compare", "--json", "--shear-rate", "Scherrate",
                          "--viscosity", "Viskosit\xc3\xa4t", "--temperature-col", "Temperatur"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto ref = run_cli(
      {"rheo", dataset("rheology/peek_cross_wlf_synthetic.csv"), "--model", "cross-wlf", "--no-compare", "--json"});
  REQUIRE(ref.code == 0);
  const auto j = nlohmann::json::parse(r.out)["results"];
  const auto k = nlohmann::json::parse(ref.out)["results"];
  // The same data under other names: the same fit.
  for (const char* p : {"n", "tau_star_Pa", "D1_Pa_s", "D2_K", "A1"})
    CHECK(j["params"][p]["value"].get<double>() == Approx(k["params"][p]["value"].get<double>()).epsilon(1e-9));
  CHECK(j["params"]["n"]["value"].get<double>() == Approx(0.4266).epsilon(0.1));
}
