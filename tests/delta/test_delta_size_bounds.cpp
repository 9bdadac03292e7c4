// `tunekit delta` on a long probe file: 100,000 simulated probe heights are fitted (the speed
// is measured by the benchmarks, not here), and a file over the row bound is refused with
// exit 2 naming the option that raises the bound.
#include <catch2/catch.hpp>

#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "size_bound_inputs.hpp"
#include "test_support.hpp"
#include "tunekit/ident/delta_kinematics.hpp"
#include "tunekit/sim/delta_probe_sim.hpp"

using namespace tunekit;

TEST_CASE("delta: a 100000-row probe file is fitted") {
  const auto path = test::write_scratch("delta_size_100001.csv", test::delta_probe_csv(100, 1000));
  const auto r = test::run_cli({"delta", path, "--radius", "105", "--rod", "215", "--height", "250", "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto res = nlohmann::json::parse(r.out)["results"];
  CHECK(res["residual_mm"].size() == 100001);
  CHECK(res["params"]["delta_radius"]["value"].get<double>() == Approx(104.2).margin(0.01));
  CHECK(res["params"]["angle_a"]["value"].get<double>() == Approx(210.4).margin(0.02));
  CHECK(res["flatness_after"]["rms_mm"].get<double>() < 0.012);
}

TEST_CASE("delta: a probe file over the row bound is refused with exit 2 naming --max-rows") {
  const auto path = test::write_scratch("delta_size_over.csv", test::delta_probe_csv(4, 10));  // 41 rows
  auto r = test::run_cli({"delta", path, "--radius", "105", "--rod", "215", "--height", "250", "--max-rows", "40"});
  CHECK(r.code == 2);
  CHECK(r.err.starts_with("tunekit: error: "));
  CHECK(r.err.find("--max-rows") != std::string::npos);
  CHECK(r.err.find("40") != std::string::npos);
  r = test::run_cli({"delta", path, "--radius", "105", "--rod", "215", "--height", "250", "--max-rows", "41"});
  CHECK(r.code == 0);
}
