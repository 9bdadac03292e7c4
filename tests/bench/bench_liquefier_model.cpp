// Benchmark: the whole-record liquefier model (a store with tau = a q^b, dead time, sensor gain
// and offset) fitted by output error to 120 s of a never-settled staircase at 1 kHz (120k
// samples), start values included. Rows: the fit with its linearised intervals, and the whole
// analysis as `tunekit step` runs it (profile-likelihood intervals of b and theta and the test of
// the linear model added). Usage: bench_liquefier_model [runs] [--fit-only]
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include "../liquefier/synth_store.hpp"
#include "bench_common.hpp"
#include "tunekit/core/heap_policy.hpp"
#include "tunekit/fitting/liquefier_model.hpp"

namespace {
template <class F>
double median_cpu_ms_model(F&& f, int runs) {
  std::vector<double> ms;
  for (int i = 0; i < runs; ++i) {
    const std::clock_t c0 = std::clock();
    f();
    ms.push_back(1000.0 * static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC);
  }
  std::sort(ms.begin(), ms.end());
  return ms[ms.size() / 2];
}
}  // namespace

int main(int argc, char** argv) {
  tunekit::core::keep_freed_memory_in_heap();  // as the tunekit executable runs
  using namespace tunekit;
  const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 7;
  const test::StoreTruth tr;
  auto s = test::synth_store(tr, 1000.0, 120.0, 0.02, 17, {4, 6, 8, 10, 12, 14}, 2);
  // The input as a CSV record carries it (sampled at the sensor's instants), as `tunekit step` fits it.
  s.rec.input_t.clear();
  s.rec.input_u.clear();
  fitting::LiquefierFitOptions fast;
  fast.profile = false;
  fast.fit_b = true;
  double b = 0, a = 0;
  const auto fit_t = bench::time_ms(
      [&] {
        const auto m = fitting::fit_liquefier_model(s.rec, fast);
        b = m.nonlinear.value("b");
        a = m.nonlinear.derived.front().value;
      },
      runs, 1);
  const double fit_cpu = median_cpu_ms_model([&] { (void)fitting::fit_liquefier_model(s.rec, fast); }, runs);
  std::printf("liquefier_model_fit_%zu_samples: median wall %.1f ms, median cpu %.1f ms (a %.4f, b %.4f)\n",
              s.rec.t.size(), fit_t.median_ms, fit_cpu, a, b);
  bench::print_bench_line("liquefier_model_fit", fit_t);
  if (argc > 2 && std::string(argv[2]) == "--fit-only") return 0;
  int solves = 0;
  const auto full_t = bench::time_ms(
      [&] {
        const auto m = fitting::fit_liquefier_model(s.rec);
        solves = m.profile_solves;
      },
      std::max(1, runs / 2), 0);
  std::printf("liquefier_model_full_%zu_samples: median wall %.1f ms (%d profile solves)\n", s.rec.t.size(),
              full_t.median_ms, solves);
  bench::print_bench_line("liquefier_model_full", full_t);
  return 0;
}
