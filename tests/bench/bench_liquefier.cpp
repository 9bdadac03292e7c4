// Liquefier identification benchmarks: a first-order-plus-dead-time step fit with intervals on
// 100k samples, and an H1 frequency-response estimate over 1M samples. Prints medians.
//   build-<dir>/tests/bench/bench_liquefier
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <random>
#include <vector>

#include "bench_common.hpp"
#include "tunekit/fitting/first_order.hpp"
#include "tunekit/ident/spectrum.hpp"

namespace {
// Median process CPU time (ms) of f over `runs` runs: on a shared, loaded machine the wall
// time also counts other processes; the CPU time is what the operation itself costs.
template <class F>
double median_cpu_ms(F&& f, int runs) {
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

int main() {
  using namespace tunekit;
  // 100k samples at 1 kHz: 10 s before the step, 90 s after; K 2, tau 2 s, theta 0.1 s.
  fitting::StepRecord rec;
  rec.t_step = 0;
  rec.du = 1.5;
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0, 0.05);
  for (int i = 0; i < 100000; ++i) {
    const double t = -10.0 + i * 1e-3;
    rec.t.push_back(t);
    rec.y.push_back(fitting::step_response(t, 0, rec.du, 2.0, 2.0, 0.1, 1.0) + noise(rng));
  }
  double tau = 0, stderr_tau = 0;
  const auto fit_timing = bench::time_ms(
      [&] {
        const auto f = fitting::fit_step(rec, fitting::StepModel::fopdt);
        tau = f.value("tau_s");
        stderr_tau = f.param("tau_s").std_error;
      },
      15, 2);
  const double fit_ms = fit_timing.median_ms;
  const double fit_cpu = median_cpu_ms([&] { (void)fitting::fit_step(rec, fitting::StepModel::fopdt); }, 15);
  std::printf("fopdt_fit_100k_samples: median wall %.2f ms, median cpu %.2f ms (tau_s %.4f +- %.4f)\n", fit_ms, fit_cpu,
              tau, stderr_tau);
  bench::print_bench_line("fopdt_fit", fit_timing);

  // H1 over 1M samples: white input through a first-order low-pass, Hann, 4096-sample segments.
  std::vector<double> u(1000000), y(u.size());
  std::normal_distribution<double> white(0, 1);
  double state = 0;
  for (std::size_t i = 0; i < u.size(); ++i) {
    u[i] = white(rng);
    state += 0.05 * (u[i] - state);
    y[i] = state + 0.01 * white(rng);
  }
  ident::WelchOptions wo;
  wo.segment_length = 4096;
  std::size_t bins = 0;
  const auto h1_timing = bench::time_ms(
      [&] {
        const auto fr = ident::h1_estimate(u, y, 1000.0, wo);
        bins = fr.freq_hz.size();
      },
      9, 1);
  const double h1_ms = h1_timing.median_ms;
  const double h1_cpu = median_cpu_ms([&] { (void)ident::h1_estimate(u, y, 1000.0, wo); }, 9);
  std::printf("h1_1M_samples: median wall %.2f ms, median cpu %.2f ms (%zu bins)\n", h1_ms, h1_cpu, bins);
  bench::print_bench_line("h1_estimate", h1_timing);
  return 0;
}
