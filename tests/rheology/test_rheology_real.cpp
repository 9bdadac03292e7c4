// Real published melt-viscosity curves (datasets/rheology/PROVENANCE.md: the polyVERSE
// literature compilation, Ramprasad et al. 2024): a polymer whose melt exceeds 1e6 Pa.s is
// fitted, not refused, and a liquid-crystalline polyester's transition is named.
#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

#include "test_support.hpp"

using tunekit::test::dataset;
using tunekit::test::run_cli;

TEST_CASE("real curves: the para-polyimidazole above 1e6 Pa.s is fitted, not refused") {
  const auto file = dataset("rheology/polyimidazole_melt_viscosity.csv");
  SECTION("every temperature: a warning with the row, and the 275 degC curve from another source flagged") {
    const auto r = run_cli({"rheo", file, "--json"});
    INFO(r.err);
    REQUIRE(r.code == 0);
    // Poise converted, the 1.4e6 Pa.s plateau at 275 degC let through with its line named.
    CHECK(r.err.find("viscosity: P -> Pa.s (x 0.1)") != std::string::npos);
    CHECK(r.err.find(
              "polyimidazole_melt_viscosity.csv:11: viscosity 1.44883e+06 Pa.s (stated as P) is above 1e+06 Pa.s") !=
          std::string::npos);
    // The 275 degC rows (a second source in the compilation) lie below the 300 degC curve.
    CHECK(r.err.find("the viscosity rises between 275 degC and 300 degC") != std::string::npos);
    const auto j = nlohmann::json::parse(r.out);
    CHECK(j["results"]["superposition"]["superposes"] == false);
  }
  SECTION("300-350 degC with Cross-WLF: fitted and converged, the WLF ridge named") {
    const auto r =
        run_cli({"rheo", file, "--temperatures", "300:350", "--model", "cross-wlf", "--no-compare", "--json"});
    INFO(r.err);
    REQUIRE(r.code == 0);
    const auto j = nlohmann::json::parse(r.out);
    CHECK(j["results"]["diagnostics"]["converged"] == true);
    CHECK(r.err.find("not separately identifiable from 3 temperatures") != std::string::npos);
    CHECK(j["results"]["params"]["D2_K"]["ci95_method"] == "profile-likelihood");
  }
  SECTION("300-350 degC, best model by AIC: superposing, with the identifiable quantities") {
    const auto r = run_cli({"rheo", file, "--temperatures", "300:350", "--json"});
    INFO(r.err);
    REQUIRE(r.code == 0);
    const auto j = nlohmann::json::parse(r.out);
    const auto& res = j["results"];
    CHECK(res["diagnostics"]["converged"] == true);
    CHECK(res["num_points"] == 32);
    CHECK(res["temperatures_K"].size() == 3);
    CHECK(res["diagnostics"]["rms"].get<double>() < 0.1);
    CHECK(res["superposition"]["superposes"] == true);
    CHECK(res.contains("correlation"));
    // The viscosity at each temperature's median shear rate is determined to a few percent.
    int mids = 0;
    for (const auto& [name, q] : res["derived"].items()) {
      if (name.rfind("eta_Pa_s_at_", 0) != 0) continue;
      ++mids;
      CHECK(q["ci95"][1].get<double>() / q["ci95"][0].get<double>() < 1.2);
    }
    CHECK(mids == 3);
    for (const auto& [name, p] : res["params"].items()) {
      INFO(name);
      if (p.contains("fixed")) continue;
      CHECK(p["ci95"][0].is_number());
      CHECK(p["ci95"][1].is_number());
    }
  }
}

TEST_CASE("real curves: the liquid-crystalline polyester's transition temperatures are flagged by name") {
  const auto file = dataset("rheology/lcp_polyester_melt_viscosity.csv");
  const auto r = run_cli({"rheo", file, "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.err.find("the viscosity rises between 160 degC and 180 degC") != std::string::npos);
  const auto j = nlohmann::json::parse(r.out);
  const auto& sp = j["results"]["superposition"];
  CHECK(sp["superposes"] == false);
  REQUIRE(sp["reversals"].size() == 1);
  CHECK(sp["reversals"][0]["lower_K"].get<double>() == Approx(433.15));
  CHECK(sp["reversals"][0]["upper_K"].get<double>() == Approx(453.15));
  CHECK(sp["reversals"][0]["a_T_ratio"].get<double>() > 2);
  // Each side on its own: below the transition and above it.
  for (const char* range : {"130:160", "180:196"}) {
    INFO(range);
    const auto side = run_cli({"rheo", file, "--temperatures", range, "--json"});
    INFO(side.err);
    REQUIRE(side.code == 0);
    CHECK(side.err.find("rises between") == std::string::npos);
    const auto js = nlohmann::json::parse(side.out);
    CHECK(js["results"]["superposition"]["reversals"].empty());
  }
}
