// --require: CI thresholds on any analysis result, exit 1 naming each unmet requirement.
#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/calibration/results/requirements.hpp"
#include "tunekit/core/error.hpp"

using tunekit::calibration::evaluate_requirement;
using tunekit::calibration::parse_requirement;

namespace {
const nlohmann::json kResults = nlohmann::json::parse(R"({
  "pooled": {"params": {"tau_s": {"value": 0.45, "stderr": 0.01}, "K": {"value": 0.88}}},
  "axes": {"x": {"modes": [{"freq_hz": 44.2, "zeta": 0.05}], "recommended": {"type": "mzv", "max_accel_mm_s2": 5200}},
           "y": {"modes": [{"freq_hz": 38.0, "zeta": 0.07}]}}
})");
}

TEST_CASE("requirements resolve short paths to the result they name") {
  auto o = evaluate_requirement(parse_requirement("tau_s<0.6"), kResults);
  CHECK(o.met);
  CHECK(o.value == 0.45);
  CHECK(o.resolved_path == "pooled.params.tau_s.value");
  o = evaluate_requirement(parse_requirement("x.freq_hz >= 45"), kResults);
  CHECK_FALSE(o.met);
  CHECK(o.resolved_path == "axes.x.modes[0].freq_hz");
  CHECK(evaluate_requirement(parse_requirement("axes.y.modes[0].zeta<=0.07"), kResults).met);
  CHECK(evaluate_requirement(parse_requirement("max_accel_mm_s2!=5200"), kResults).met == false);
}

TEST_CASE("malformed, unknown and ambiguous requirements are usage errors") {
  CHECK_THROWS_AS(parse_requirement("tau_s"), tunekit::InputError);
  CHECK_THROWS_AS(parse_requirement("tau_s<abc"), tunekit::InputError);
  CHECK_THROWS_AS(evaluate_requirement(parse_requirement("omega<1"), kResults), tunekit::InputError);
  CHECK_THROWS_AS(evaluate_requirement(parse_requirement("freq_hz>1"), kResults), tunekit::InputError);
}

TEST_CASE("an unmet requirement exits 1 and names each unmet requirement, met ones exit 0") {
  const auto path = tunekit::test::write_scratch("req.csv", "time,y\n0,1\n1,2\n2,4\n");
  auto r = tunekit::test::run_cli({"inspect", path, "--time", "time", "--require", "rows>=3", "--require", "span_s<1.5",
                                   "--require", "sample_rate_hz>2"});
  CHECK(r.code == 1);
  CHECK(r.err.find("requirement not met: span_s<1.5 (time.span_s = 2)") != std::string::npos);
  CHECK(r.err.find("requirement not met: sample_rate_hz>2 (time.sample_rate_hz = 1)") != std::string::npos);
  CHECK(r.err.find("rows>=3") == std::string::npos);
  r = tunekit::test::run_cli({"inspect", path, "--time", "time", "--require", "rows>=3", "--json"});
  CHECK(r.code == 0);
  CHECK(nlohmann::json::parse(r.out)["requirements"][0]["met"] == true);
  CHECK(tunekit::test::run_cli({"inspect", path, "--require", "nothing<1"}).code == 2);
}
