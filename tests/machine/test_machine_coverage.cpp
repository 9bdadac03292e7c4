// The grid-based coverage planner for test prints (after Li and Yao, Coverage Path Planning
// Application on FDM 3D Printer, USC, 2018) against the plain zigzag, and its G-code against the
// machine profile's safety check.
#include <cmath>
#include <set>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/protocols/coverage_planner.hpp"
#include "tunekit/firmware/dialect.hpp"
#include "tunekit/protocols/experiments.hpp"
#include "tunekit/protocols/runner.hpp"
#include "tunekit/protocols/safety.hpp"
#include "tunekit/sim/builtin_profile.hpp"

using namespace tunekit::protocols;
using namespace tunekit::firmware;

TEST_CASE("coverage planner travels less and retracts less than the zigzag on the standard test patterns",
          "[machine][coverage]") {
  const auto profile = tunekit::sim::builtin_sim_profile();
  const TestPatternSet set;
  const CoverageMotion motion;
  const auto pce = plan_test_patterns(set, profile, "pce", motion);
  const auto zz = plan_test_patterns(set, profile, "zigzag", motion);
  INFO("pce travel " << pce.stats.travel_mm << " mm, " << pce.stats.retractions << " retractions, " << pce.stats.time_s
                     << " s; zigzag " << zz.stats.travel_mm << " mm, " << zz.stats.retractions << ", "
                     << zz.stats.time_s << " s");
  CHECK(pce.stats.travel_mm < zz.stats.travel_mm);
  CHECK(pce.stats.retractions < zz.stats.retractions);
  CHECK(pce.stats.time_s < zz.stats.time_s);
  // Both cover the same cells: every extruded move's end cells, collected on the grid.
  auto cells = [&](const CoveragePlan& p) {
    std::set<std::pair<long, long>> s;
    for (const auto& m : p.moves) {
      if (!m.extrude) continue;
      const double len = std::hypot(m.x1 - m.x0, m.y1 - m.y0);
      const int steps = static_cast<int>(std::lround(len / p.cell_mm * 4)) + 1;
      for (int k = 0; k <= steps; ++k) {
        const double f = static_cast<double>(k) / steps;
        const double x = m.x0 + f * (m.x1 - m.x0), y = m.y0 + f * (m.y1 - m.y0);
        // Only points at cell centres (within 1 % of a cell) name a cell.
        const double gx = x / p.cell_mm - 0.5, gy = y / p.cell_mm - 0.5;
        if (std::abs(gx - std::round(gx)) < 0.01 && std::abs(gy - std::round(gy)) < 0.01)
          s.insert({std::lround(gx), std::lround(gy)});
      }
    }
    return s;
  };
  CHECK(cells(pce) == cells(zz));
  // Every planned move stays inside the profile's x/y travel.
  for (const auto* p : {&pce, &zz})
    for (const auto& m : p->moves) {
      for (double x : {m.x0, m.x1}) CHECK((x >= profile.axis("x").min_mm && x <= profile.axis("x").max_mm));
      for (double y : {m.y0, m.y1}) CHECK((y >= profile.axis("y").min_mm && y <= profile.axis("y").max_mm));
    }
}

TEST_CASE("test-pattern G-code of both planners passes the machine profile's safety check", "[machine][coverage]") {
  const auto profile = tunekit::sim::builtin_sim_profile();
  const Dialect d;  // Marlin
  for (double zigzag : {0.0, 1.0}) {
    const auto e = build_experiment("test-pattern", {{"zigzag", zigzag}}, "", profile, d);
    const auto v = check_protocol(e.gcode, profile, e.sensors);
    INFO((v.empty() ? std::string() : v.front().what));
    CHECK(v.empty());
  }
  const auto r = tunekit::test::run_cli({"run", "test-pattern", "--dry-run", "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto res = nlohmann::json::parse(r.out)["results"];
  CHECK(res["experiment"]["protocol"] == "test-pattern");
}

TEST_CASE("test patterns larger than the bed are refused with exit code 2", "[machine][coverage]") {
  const auto r = tunekit::test::run_cli({"run", "test-pattern", "--dry-run", "-p", "pads=20"});
  CHECK(r.code == 2);
  CHECK(r.err.find("do not fit the bed") != std::string::npos);
}
