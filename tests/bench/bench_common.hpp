#pragma once
// Tiny timing harness for the benchmark programs: run a callable several times after a
// warm-up and report the median wall time (and the fastest and slowest run), plus the
// "BENCH ..." line scripts/bench reads.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <utility>
#include <vector>

namespace tunekit::bench {

/// Median, fastest and slowest of several timed runs, in milliseconds.
struct Timing {
  double median_ms = 0;
  double min_ms = 0;
  double max_ms = 0;
  int runs = 0;
};

/// Summarizes run times (ms); `ms` must not be empty.
inline Timing summarize_ms(std::vector<double> ms) {
  std::sort(ms.begin(), ms.end());
  return {ms[ms.size() / 2], ms.front(), ms.back(), static_cast<int>(ms.size())};
}

/// Runs f `warmup` times untimed, then `runs` times timed (wall clock).
template <class F>
Timing time_ms(F&& f, int runs = 15, int warmup = 2) {
  for (int i = 0; i < warmup; ++i) f();
  std::vector<double> ms;
  for (int i = 0; i < runs; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    const auto t1 = std::chrono::steady_clock::now();
    ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
  }
  return summarize_ms(std::move(ms));
}

template <class F>
double median_ms(F&& f, int runs = 15, int warmup = 2) {
  return time_ms(std::forward<F>(f), runs, warmup).median_ms;
}

/// The machine-readable line scripts/bench collects into docs/benchmarks.md:
///   BENCH <key> median=<x> min=<x> max=<x> unit=<unit> runs=<n>
inline void print_bench_line(const char* key, double median, double min, double max, const char* unit, int runs) {
  std::printf("BENCH %s median=%.3f min=%.3f max=%.3f unit=%s runs=%d\n", key, median, min, max, unit, runs);
  std::fflush(stdout);
}
inline void print_bench_line(const char* key, const Timing& t) {
  print_bench_line(key, t.median_ms, t.min_ms, t.max_ms, "ms", t.runs);
}

}  // namespace tunekit::bench
