// Benchmark: a Cross-WLF fit of 2,000 points (PEEK, five temperatures, 3 % noise), global
// start included (CRS2-LM + BOBYQA search, then Ceres with covariance). Prints the median of
// several runs in milliseconds.
//   build-rel/tests/bench/bench_rheology [runs]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <random>
#include <vector>

#include "bench_common.hpp"
#include "tunekit/core/heap_policy.hpp"
#include "tunekit/fitting/rheology_fit.hpp"
#include "tunekit/fitting/viscosity.hpp"

using namespace tunekit::fitting;

int main(int argc, char** argv) {
  tunekit::core::keep_freed_memory_in_heap();  // as the tunekit executable runs
  const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 9;
  const auto& peek = cross_wlf_material("PEEK").params;
  RheologyData d;
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0, 0.03);
  for (double degc : {370.0, 390.0, 410.0, 430.0, 450.0})
    for (int i = 0; i < 400; ++i) {
      const double g = std::pow(10.0, -1 + i * 5.0 / 399);
      const double T = celsius_to_kelvin(degc);
      d.shear_rate_1_s.push_back(g);
      d.temperature_K.push_back(T);
      d.viscosity_Pa_s.push_back(cross_wlf_viscosity(peek, g, T) * std::exp(noise(rng)));
    }
  ViscosityFitOptions o;
  o.model = ViscosityModel::cross_wlf;
  std::vector<double> ms, cpu;
  FitResult fit;
  for (int r = 0; r < runs; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    const std::clock_t c0 = std::clock();
    fit = fit_viscosity(d, o);
    cpu.push_back(1000.0 * static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  tunekit::bench::print_bench_line("cross_wlf_fit", tunekit::bench::summarize_ms(ms));
  std::sort(ms.begin(), ms.end());
  std::sort(cpu.begin(), cpu.end());
  std::printf(
      "cross-wlf fit, %zu points, global start included: median %.1f ms wall (min %.1f, max %.1f), "
      "median %.1f ms CPU, over %d runs\n",
      d.size(), ms[ms.size() / 2], ms.front(), ms.back(), cpu[cpu.size() / 2], runs);
  std::printf("  n %.4f  tau_star %.5g Pa  D1 %.4g Pa.s  D2 %.2f K  A1 %.3f  (%d iterations)\n", fit.value("n"),
              fit.value("tau_star_Pa"), fit.value("D1_Pa_s"), fit.value("D2_K"), fit.value("A1"),
              fit.diagnostics.iterations);
  return 0;
}
