// The history store on both databases: the same cases run against SQLite and against a
// PostgreSQL server the test starts itself.
#include <chrono>
#include <cmath>
#include <csignal>
#include <random>
#include <thread>
#include <unistd.h>

#include <catch2/catch.hpp>

#include "history_fixture.hpp"
#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/history/drift.hpp"
#include "tunekit/history/quantities.hpp"
#include "tunekit/history/store.hpp"

using namespace tunekit;
using namespace tunekit::history;

namespace {

NewRecord sample_record(const std::string& machine, double tau, double freq) {
  NewRecord r;
  r.machine_id = machine;
  r.command = "calibrate";
  r.tool_version = "9.9.9";
  r.envelope_schema = 1;
  r.envelope_sha256 = std::string(64, 'a');
  r.envelope = R"({"command":"calibrate"})";
  r.inputs = {{"axis-x/raw_data_x_tunekit.csv", std::string(64, 'b'), 1234},
              {"liquefier-step/load.csv", std::string(64, 'c'), 99}};
  r.quantities = {
      {"tau_s", tau, 0.01, "", "s"}, {"x.freq_hz", freq, 0.2, "", "Hz"}, {"x.shaper", NAN, NAN, "mzv", "1"}};
  return r;
}

std::int64_t count(Connection& c, const std::string& sql) { return as_int(c.query(sql).at(0).at(0)); }

// Every record has exactly the inputs and quantities it says, and nothing points at a missing record.
void check_consistent(Connection& c) {
  CHECK(count(c,
              "SELECT COUNT(*) FROM records r WHERE n_quantities <> (SELECT COUNT(*) FROM quantities q WHERE "
              "q.record_id = r.id)") == 0);
  CHECK(count(c,
              "SELECT COUNT(*) FROM records r WHERE n_inputs <> (SELECT COUNT(*) FROM record_inputs i WHERE "
              "i.record_id = r.id)") == 0);
  CHECK(
      count(c,
            "SELECT COUNT(*) FROM quantities q WHERE NOT EXISTS (SELECT 1 FROM records r WHERE r.id = q.record_id)") ==
      0);
  CHECK(
      count(
          c,
          "SELECT COUNT(*) FROM record_inputs i WHERE NOT EXISTS (SELECT 1 FROM records r WHERE r.id = i.record_id)") ==
      0);
  if (c.backend() == Backend::sqlite) CHECK(as_text(c.query("PRAGMA integrity_check").at(0).at(0)) == "ok");
}

}  // namespace

TEST_CASE("history store: migrations run on open, once, and a newer schema is refused") {
  TUNEKIT_FOR_EACH_HISTORY_BACKEND(db, "migrations");
  {
    Store s(db.url);
    CHECK(s.schema_version() == kHistorySchemaVersion);
    CHECK(count(s.connection(), "SELECT COUNT(*) FROM schema_migrations") == kHistorySchemaVersion);
  }
  {
    Store again(db.url);  // reopening applies nothing twice
    CHECK(count(again.connection(), "SELECT COUNT(*) FROM schema_migrations") == kHistorySchemaVersion);
    CHECK(count(again.connection(), "SELECT COUNT(*) FROM records") == 0);
    again.connection().query("INSERT INTO schema_migrations (version, description, applied_utc) VALUES ($1, $2, $3)",
                             {std::int64_t{kHistorySchemaVersion + 1}, std::string("from the future"), utc_now()});
  }
  try {
    Store newer(db.url);
    FAIL("a database with a newer schema was opened");
  } catch (const InputError& e) {
    CHECK_THAT(e.what(), Catch::Contains("newer than this tunekit"));
  }
}

TEST_CASE("history store: a record keeps its inputs' digests, tool version, UTC time and quantities") {
  TUNEKIT_FOR_EACH_HISTORY_BACKEND(db, "record");
  Store s(db.url);
  const std::string before = utc_now();
  const auto id = s.record(sample_record("printer-07", 0.45, 48.25));
  REQUIRE(id);
  const auto rec = s.get(*id);
  REQUIRE(rec);
  CHECK(rec->machine_id == "printer-07");
  CHECK(rec->command == "calibrate");
  CHECK(rec->tool_version == "9.9.9");
  CHECK(rec->recorded_utc >= before);
  CHECK(rec->recorded_utc.size() == 24);  // YYYY-MM-DDTHH:MM:SS.mmmZ
  CHECK(rec->recorded_utc.back() == 'Z');
  CHECK(rec->run_utc == rec->recorded_utc);
  REQUIRE(rec->inputs.size() == 2);
  CHECK(rec->inputs[0].path == "axis-x/raw_data_x_tunekit.csv");
  CHECK(rec->inputs[0].sha256 == std::string(64, 'b'));
  CHECK(rec->inputs[0].bytes == 1234);
  REQUIRE(rec->quantities.size() == 3);
  CHECK(rec->quantities[0].name == "tau_s");
  CHECK(rec->quantities[0].value == 0.45);  // doubles round-trip exactly on both backends
  CHECK(rec->quantities[0].stderr_value == 0.01);
  CHECK(rec->quantities[1].name == "x.freq_hz");
  CHECK(rec->quantities[1].value == 48.25);
  CHECK(rec->quantities[2].text == "mzv");
  CHECK(std::isnan(rec->quantities[2].value));
  CHECK(rec->envelope == R"({"command":"calibrate"})");
  CHECK_FALSE(s.get(*id + 1000));

  // Runs are ordered by when they ran, not by when they were recorded.
  auto late = sample_record("printer-07", 0.5, 47.0);
  late.run_utc = "2030-01-01T00:00:00.000Z";
  auto early = sample_record("printer-07", 0.4, 49.0);
  early.run_utc = "2020-01-01T00:00:00.000Z";
  s.record(late);
  s.record(early);
  const auto series = s.series("printer-07", "x.freq_hz");
  REQUIRE(series.size() == 3);
  CHECK(series[0].value == 49.0);
  CHECK(series[1].value == 48.25);
  CHECK(series[2].value == 47.0);
  CHECK(s.series("printer-07").size() == 3);
  const auto machines = s.machines();
  REQUIRE(machines.size() == 1);
  CHECK(machines[0].runs == 3);
  CHECK(machines[0].first_run_utc == "2020-01-01T00:00:00.000Z");
  check_consistent(s.connection());
}

TEST_CASE("history store: an import recorded twice is kept once, live records always") {
  TUNEKIT_FOR_EACH_HISTORY_BACKEND(db, "dedupe");
  Store s(db.url);
  auto r = sample_record("m1", 0.45, 48);
  r.source = "/archive/m1/runs/calibrate-20261101-120000";
  r.deduplicate = true;
  CHECK(s.record(r));
  CHECK_FALSE(s.record(r));  // same machine, source and results
  r.envelope_sha256 = std::string(64, 'd');
  CHECK(s.record(r));  // different results from the same place
  auto live = sample_record("m1", 0.45, 48);
  CHECK(s.record(live));
  CHECK(s.record(live));
  CHECK(s.records("m1").size() == 4);
  check_consistent(s.connection());
}

TEST_CASE("history store: bad machine ids and a failed record leave nothing behind") {
  TUNEKIT_FOR_EACH_HISTORY_BACKEND(db, "bad_input");
  Store s(db.url);
  CHECK_THROWS_AS(s.record(sample_record("", 1, 1)), InputError);
  CHECK_THROWS_AS(s.record(sample_record(std::string(129, 'm'), 1, 1)), InputError);
  CHECK_THROWS_AS(s.record(sample_record("tab\there", 1, 1)), InputError);
  auto dup = sample_record("m1", 1, 1);
  dup.quantities.push_back(dup.quantities[0]);  // the same quantity twice violates the key mid-transaction
  CHECK_THROWS_AS(s.record(dup), InputError);
  CHECK(count(s.connection(), "SELECT COUNT(*) FROM records") == 0);
  CHECK(count(s.connection(), "SELECT COUNT(*) FROM quantities") == 0);
  CHECK(s.record(sample_record("m1", 1, 1)));  // the connection is usable after the rollback
}

TEST_CASE("history store: a process killed mid-record leaves the database consistent") {
  TUNEKIT_FOR_EACH_HISTORY_BACKEND(db, "killed");
  { Store create(db.url); }
  std::mt19937 rng(7);
  std::int64_t seen_before = 0;
  for (int round = 0; round < 5; ++round) {
    const pid_t pid = ::fork();
    REQUIRE(pid >= 0);
    if (pid == 0) {
      // The child records large records (many quantities, one transaction each) until killed.
      try {
        Store s(db.url);
        auto r = sample_record("victim", 0.45, 48);
        for (int q = 0; q < 400; ++q) r.quantities.push_back({"extra.q" + std::to_string(q), q * 1.0, 0.1, "", "1"});
        for (;;) s.record(r);
      } catch (...) {
      }
      ::_exit(99);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(std::uniform_int_distribution<int>(300, 900)(rng)));
    ::kill(pid, SIGKILL);
    CHECK(test::wait_process(pid) == 128 + SIGKILL);
    Store s(db.url);
    check_consistent(s.connection());
    const std::int64_t n = count(s.connection(), "SELECT COUNT(*) FROM records");
    CHECK(n >= seen_before);
    seen_before = n;
  }
  // PostgreSQL logs a client that died inside a transaction: at least one kill hit a record
  // halfway (the server rolled it back).
  if (backend_ == "postgresql")
    CHECK_THAT(test::postgres_server_log(),
               Catch::Contains("unexpected EOF on client connection with an open transaction"));
  Store s(db.url);
  CHECK(seen_before > 0);  // the child did write records before it was killed
  CHECK(count(s.connection(), "SELECT COUNT(*) FROM quantities") == seen_before * 403);
  CHECK(s.record(sample_record("victim", 0.5, 47)));
  check_consistent(s.connection());
}

TEST_CASE("history drift: drift is a change whose interval lies beyond the quantity's margin") {
  auto pt = [](double v, double se) { return SeriesPoint{0, "t", v, se, "", "Hz"}; };
  // Baseline 48 +- 0.2; noise limit 1.96 * sqrt(0.04 + 0.04) = 0.554 Hz, margin 1 % = 0.48 Hz:
  // drift when |change| > 1.034 Hz. Run 2: -0.5 Hz and run 3: -0.9 Hz (beyond the noise, within
  // the margin's reach) are not drift; run 4: -1.1 Hz is; run 5 back within; runs 6 and 7 beyond.
  const std::vector<SeriesPoint> s{pt(48, 0.2),   pt(47.5, 0.2), pt(47.1, 0.2), pt(46.9, 0.2),
                                   pt(47.9, 0.2), pt(46, 0.2),   pt(45, 0.2)};
  const auto d = analyse_drift("x.freq_hz", s, {});
  REQUIRE(d.points.size() == 7);
  CHECK(d.baseline == 48);
  CHECK(d.margin.relative == Approx(0.01));
  CHECK(d.points[1].threshold == Approx(1.96 * std::sqrt(0.08)));
  CHECK(d.points[1].margin == Approx(0.48));
  CHECK_FALSE(d.points[0].drifted);
  CHECK_FALSE(d.points[1].drifted);
  CHECK_FALSE(d.points[2].drifted);
  CHECK(d.points[3].drifted);
  CHECK_FALSE(d.points[4].drifted);
  CHECK(d.points[5].drifted);
  CHECK(d.points[6].drifted);
  REQUIRE(d.drifted_since);
  CHECK(*d.drifted_since == 5);  // the stretch that lasts to the latest run
  CHECK(d.significant_change_pct() == Approx(-100.0 * 3 / 48));
  // A real change far beyond the noise but within the margin is not drift: 0.4 % of K.
  const auto k = analyse_drift("K", {pt(3.5, 0.001), pt(3.514, 0.001)}, {});
  CHECK(k.points[1].threshold < 0.014);
  CHECK_FALSE(k.latest_drifted());
  // A larger coverage factor turns the same change into noise.
  const auto wide = analyse_drift("x.freq_hz", s, {1, 20.0});  // limit 5.66 Hz > the 3 Hz change
  CHECK_FALSE(wide.latest_drifted());
  CHECK(wide.significant_change_pct() == 0);
  // A two-run baseline averages them and combines their errors.
  const auto two = analyse_drift("x.freq_hz", s, {2, 1.96});
  CHECK(two.baseline == Approx(47.75));
  CHECK(two.baseline_stderr == Approx(std::sqrt(0.08) / 2));
  CHECK_FALSE(two.points[1].drifted);  // part of the baseline
  CHECK_THROWS_AS(analyse_drift("x", s, {0, 1.96}), InputError);
}

TEST_CASE("history drift: a designed quantity drifts only through what it was designed from") {
  // The shaper chosen and its maximum acceleration change in run 3 and run 4; the X resonance
  // drifts only in run 4: only run 4's designed values are drift.
  const std::vector<SeriesPoint> w{{1, "t", NAN, NAN, "mzv", "1"},
                                   {2, "t", NAN, NAN, "mzv", "1"},
                                   {3, "t", NAN, NAN, "ei", "1"},
                                   {4, "t", NAN, NAN, "ei", "1"}};
  const std::vector<SeriesPoint> acc{{1, "t", 4033, NAN, "", "mm/s^2"},
                                     {2, "t", 4033, NAN, "", "mm/s^2"},
                                     {3, "t", 4100, NAN, "", "mm/s^2"},
                                     {4, "t", 3600, NAN, "", "mm/s^2"}};
  const std::vector<SeriesPoint> f{{1, "t", 48, 0.1, "", "Hz"},
                                   {2, "t", 48, 0.1, "", "Hz"},
                                   {3, "t", 47.9, 0.1, "", "Hz"},
                                   {4, "t", 45, 0.1, "", "Hz"}};
  std::vector<tunekit::history::DriftSeries> all{
      analyse_drift("x.shaper", w, {}), analyse_drift("x.max_accel_mm_s2", acc, {}), analyse_drift("y.freq_hz", f, {})};
  CHECK(all[0].is_text);
  CHECK(all[0].margin.designed);
  CHECK(all[2].latest_drifted());  // the Y resonance, measured, drifts on its own
  for (std::size_t i = 0; i < 2; ++i)
    for (const auto& p : all[i].points) CHECK_FALSE(p.drifted);  // alone, designed values never drift
  tunekit::history::follow_designed(all);
  for (std::size_t i = 0; i < 2; ++i) CHECK_FALSE(all[i].latest_drifted());  // X's follow X, not Y
  all.push_back(analyse_drift("x.freq_hz", f, {}));
  CHECK(all.back().latest_drifted());
  tunekit::history::follow_designed(all);
  for (std::size_t i = 0; i < 2; ++i) {
    INFO(all[i].name);
    CHECK_FALSE(all[i].points[2].drifted);
    CHECK(all[i].points[3].drifted);
    REQUIRE(all[i].drifted_since);
    CHECK(*all[i].drifted_since == 3);
  }
}

TEST_CASE("history quantities: taken from calibrate, step and shaper results by the same names") {
  const auto cal = nlohmann::json::parse(R"json({
    "liquefier": {"step": {"pooled": {"params": {"tau_s": {"value": 0.45, "stderr": 0.01}, "theta_s": {"value": 0.04, "stderr": 0.002},
                                                  "K": {"value": 3.5, "stderr": 0.05}}}, "units": {"K": "N/(mm/s)"}}},
    "axes": {"x": {"modes": [{"freq_hz": 95, "freq_stderr_hz": 1, "zeta": 0.05, "zeta_stderr": 0.01},
                             {"freq_hz": 48.1, "freq_stderr_hz": 0.1, "zeta": 0.08, "zeta_stderr": 0.004}],
                   "fit": {"dominant_mode": 1}, "recommended": {"type": "mzv", "freq_hz": 47.5, "max_accel_mm_s2": 8000}}},
    "compensators": {"settings": {"pa_k_s": 0.44}}})json");
  const auto q = extract_quantities("calibrate", cal);
  auto find = [&](const std::string& n) -> const Quantity* {
    for (const auto& x : q)
      if (x.name == n) return &x;
    return nullptr;
  };
  REQUIRE(find("tau_s"));
  CHECK(find("tau_s")->value == 0.45);
  CHECK(find("tau_s")->stderr_value == 0.01);
  CHECK(find("K")->unit == "N/(mm/s)");
  REQUIRE(find("x.freq_hz"));
  CHECK(find("x.freq_hz")->value == 48.1);  // the dominant mode, not the first listed
  CHECK(find("x.freq_hz")->stderr_value == 0.1);
  CHECK(find("x.zeta")->value == 0.08);
  CHECK(find("x.shaper")->text == "mzv");
  CHECK(find("x.shaper_freq_hz")->value == 47.5);
  CHECK(find("pa_k_s")->value == 0.44);
  // A hand-run step analysis gives the same names.
  const auto step = extract_quantities("step", cal["liquefier"]["step"]);
  REQUIRE(step.size() == 3);
  CHECK(step[0].name == "tau_s");
  // Other commands: fitted parameters under "params".
  const auto rheo = extract_quantities(
      "rheo", nlohmann::json::parse(R"({"fits": {"power_law": {"params": {"n": {"value": 0.52, "stderr": 0.01}}}}})"));
  REQUIRE(rheo.size() == 1);
  CHECK(rheo[0].name == "rheo.n");
}
