// Benchmark: the calibration history on its embedded default (SQLite).
//  1. Recording one calibration: the whole --record path (open the database, check its schema,
//     take the quantities, write the record, its inputs and quantities in one transaction,
//     committed in write-ahead-log mode, synchronous=NORMAL). The calibration is a real `tunekit calibrate --machine
//     sim` run made once at the start (or the results.json given).
//  2. A trend query over 100 machines x 1,000 runs (10 quantities each, 1,000,000 quantity
//     rows): `tunekit history trend --machine M --json` in-process (query, drift analysis of
//     every quantity, JSON on stdout), and the fleet-wide trend of one quantity
//     (`history trend -q x.freq_hz --json`, all 100 machines).
//   build/tests/bench/bench_history [results.json] [--fleet-db FILE]
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <random>
#include <sstream>

#include <fmt/format.h>

#include "bench_common.hpp"
#include "tunekit/core/heap_policy.hpp"
#include "tunekit/cli/run_cli.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/results/history_record.hpp"
#include "tunekit/history/store.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/core/file_bytes.hpp"

namespace fs = std::filesystem;
using namespace tunekit;

namespace {

double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
}

// Medians of the wall time and of this thread's CPU time (the machine may be shared: the CPU
// time says what the work costs, the wall time what a user waits).
template <class F>
std::pair<bench::Timing, double> wall_and_cpu_ms(F&& f, int runs, int warmup) {
  std::vector<double> cpu;
  const bench::Timing wall = bench::time_ms(
      [&] {
        const double c0 = thread_cpu_ms();
        f();
        cpu.push_back(thread_cpu_ms() - c0);
      },
      runs, warmup);
  cpu.erase(cpu.begin(), cpu.begin() + warmup);
  std::sort(cpu.begin(), cpu.end());
  return {wall, cpu[cpu.size() / 2]};
}

}  // namespace

int main(int argc, char** argv) {
  tunekit::core::keep_freed_memory_in_heap();  // as the tunekit executable runs
  const fs::path dir = fs::temp_directory_path() / fmt::format("tunekit-bench-history-{}", ::getpid());
  fs::create_directories(dir);
  std::string results, fleet_db;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--fleet-db" && i + 1 < argc) fleet_db = argv[++i];  // keep (or reuse) the seeded database
    else results = a;
  }
  if (results.empty()) {
    std::ostringstream out, err;
    const int code =
        cli::run_cli({"calibrate", "--machine", "sim", "--out", (dir / "run").string(), "--json"}, out, err);
    if (code != 0) {
      std::fprintf(stderr, "calibrate failed: %s\n", err.str().c_str());
      return 1;
    }
    results = (dir / "run" / "results.json").string();
  }
  const auto envelope = nlohmann::json::parse(read_file_bytes(results));

  // 1. One calibration recorded, as `calibrate --record` does it.
  calibration::OutputOptions o;
  o.record = true;
  o.json = true;  // no confirmation line
  o.machine_id = "bench-printer";
  o.db = (dir / "record.sqlite").string();
  o.record_source = "runs/calibrate-bench";
  std::ostringstream sink;
  calibration::CliContext ctx{sink, sink};
  const auto [record_timing, record_cpu_ms] =
      wall_and_cpu_ms([&] { calibration::record_result(envelope, o, ctx); }, 31, 3);
  const double record_ms = record_timing.median_ms;
  std::printf("record one calibration (SQLite, %zu-byte result): median %.2f ms wall, %.2f ms CPU\n",
              envelope.dump().size(), record_ms, record_cpu_ms);
  bench::print_bench_line("history_record", record_timing);

  // 2. 100 machines x 1,000 runs.
  const std::string db = fleet_db.empty() ? (dir / "fleet.sqlite").string() : fleet_db;
  if (fleet_db.empty() || !fs::exists(fleet_db)) {
    history::Store store(db);
    store.connection().execute("PRAGMA synchronous=OFF");  // seeding only
    std::mt19937 rng(1);
    std::normal_distribution<double> noise(0, 1);
    for (int run = 0; run < 1000; ++run)
      for (int m = 0; m < 100; ++m) {
        history::NewRecord r;
        r.machine_id = fmt::format("printer-{:03d}", m);
        r.command = "calibrate";
        r.tool_version = "0.1.0";
        r.envelope_schema = 1;
        r.run_utc = fmt::format("2026-{:02d}-{:02d}T{:02d}:{:02d}:00.000Z", 1 + run / 100, 1 + (run / 4) % 25, run % 24,
                                m % 60);
        r.envelope_sha256 = std::string(64, '0');
        r.envelope = "{}";
        r.inputs = {{"axis-x/raw_data_x_tunekit.csv", std::string(64, '1'), 1000000}};
        const double f = 48 - 0.002 * run;
        r.quantities = {{"tau_s", 0.45 + 0.01 * noise(rng), 0.01, "", "s"},
                        {"theta_s", 0.04 + 0.002 * noise(rng), 0.002, "", "s"},
                        {"K", 3.5 + 0.05 * noise(rng), 0.05, "", "N/(mm/s)"},
                        {"x.freq_hz", f + 0.1 * noise(rng), 0.1, "", "Hz"},
                        {"x.zeta", 0.08 + 0.004 * noise(rng), 0.004, "", "1"},
                        {"x.shaper", NAN, NAN, "mzv", "1"},
                        {"y.freq_hz", 37 + 0.1 * noise(rng), 0.1, "", "Hz"},
                        {"y.zeta", 0.1 + 0.004 * noise(rng), 0.004, "", "1"},
                        {"y.shaper", NAN, NAN, "ei", "1"},
                        {"pa_k_s", 0.44 + 0.01 * noise(rng), NAN, "", "s"}};
        store.record(r);
      }
    store.connection().execute("ANALYZE");
  }
  auto trend = [&](std::vector<std::string> args) {
    std::ostringstream out, err;
    args.insert(args.begin(), {"history", "trend", "--db", db, "--json"});
    if (cli::run_cli(args, out, err) > 1) {
      std::fprintf(stderr, "trend failed: %s\n", err.str().c_str());
      std::exit(1);
    }
  };
  const auto [one_timing, one_cpu] = wall_and_cpu_ms([&] { trend({"--machine", "printer-042"}); }, 15, 2);
  const double one_ms = one_timing.median_ms;
  std::printf(
      "trend of one machine, all 10 quantities, every run (100 machines x 1,000 runs): median %.1f ms wall, %.1f ms "
      "CPU\n",
      one_ms, one_cpu);
  bench::print_bench_line("history_trend_machine", one_timing);
  const auto [fleet_timing, fleet_cpu] = wall_and_cpu_ms([&] { trend({"-q", "x.freq_hz"}); }, 7, 1);
  const double fleet_ms = fleet_timing.median_ms;
  std::printf("trend of x.freq_hz over the whole fleet (100 x 1,000 runs): median %.1f ms wall, %.1f ms CPU\n",
              fleet_ms, fleet_cpu);
  bench::print_bench_line("history_trend_fleet", fleet_timing);
  fs::remove_all(dir);
  return 0;
}
