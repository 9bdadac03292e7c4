// Liquefier identification benchmarks: a first-order-plus-dead-time step fit with intervals on
// 100k samples, and an H1 frequency-response estimate over 1M samples. Prints medians.
//   build-<dir>/tests/bench/bench_liquefier [--fopdt-only]
//   build-<dir>/tests/bench/bench_liquefier --write-step FILE
// --write-step writes the step record the FOPDT row fits (same generator, same seed) as CSV, with
// its truth in a comment line, and exits: tests/bench/scipy_fopdt.py fits the same samples.
// --fopdt-only times the FOPDT fit alone (for the side-by-side row against SciPy).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <random>
#include <string>
#include <vector>

#include "bench_common.hpp"
#include "tunekit/core/heap_policy.hpp"
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

// The FOPDT row's record: 100k samples at 1 kHz, 10 s before the step and 90 s after; K 2,
// tau 2 s, theta 0.1 s, y0 1, du 1.5, white noise of 0.05. `rng` continues into the H1 row.
constexpr double kTrueK = 2.0, kTrueTau = 2.0, kTrueTheta = 0.1, kTrueY0 = 1.0, kNoise = 0.05;
tunekit::fitting::StepRecord step_record(std::mt19937& rng) {
  tunekit::fitting::StepRecord rec;
  rec.t_step = 0;
  rec.du = 1.5;
  std::normal_distribution<double> noise(0, kNoise);
  for (int i = 0; i < 100000; ++i) {
    const double t = -10.0 + i * 1e-3;
    rec.t.push_back(t);
    rec.y.push_back(tunekit::fitting::step_response(t, 0, rec.du, kTrueK, kTrueTau, kTrueTheta, kTrueY0) + noise(rng));
  }
  return rec;
}

// The record as CSV, every value to 17 significant digits (read back exactly).
bool write_step_csv(const tunekit::fitting::StepRecord& rec, const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return false;
  std::fprintf(f, "# fopdt step: t_step_s=%.17g du=%.17g K=%.17g tau_s=%.17g theta_s=%.17g y0=%.17g noise_sd=%.17g\n",
               rec.t_step, rec.du, kTrueK, kTrueTau, kTrueTheta, kTrueY0, kNoise);
  std::fprintf(f, "t_s,y\n");
  for (std::size_t i = 0; i < rec.t.size(); ++i) std::fprintf(f, "%.17g,%.17g\n", rec.t[i], rec.y[i]);
  return std::fclose(f) == 0;
}
}  // namespace

int main(int argc, char** argv) {
  tunekit::core::keep_freed_memory_in_heap();  // as the tunekit executable runs
  using namespace tunekit;
  std::string write_step;
  bool fopdt_only = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--write-step" && i + 1 < argc) {
      write_step = argv[++i];
    } else if (a == "--fopdt-only") {
      fopdt_only = true;
    } else {
      std::fprintf(stderr, "usage: bench_liquefier [--fopdt-only] [--write-step FILE]\n");
      return 2;
    }
  }
  std::mt19937 rng(1);
  const fitting::StepRecord rec = step_record(rng);
  if (!write_step.empty()) {
    if (!write_step_csv(rec, write_step)) {
      std::fprintf(stderr, "bench_liquefier: cannot write %s\n", write_step.c_str());
      return 1;
    }
    std::printf("wrote %s (%zu samples)\n", write_step.c_str(), rec.t.size());
    return 0;
  }
  fitting::FitResult fit;
  const auto fit_timing = bench::time_ms([&] { fit = fitting::fit_step(rec, fitting::StepModel::fopdt); }, 15, 2);
  const double tau = fit.value("tau_s"), stderr_tau = fit.param("tau_s").std_error;
  const double fit_ms = fit_timing.median_ms;
  const double fit_cpu = median_cpu_ms([&] { (void)fitting::fit_step(rec, fitting::StepModel::fopdt); }, 15);
  std::printf("fopdt_fit_100k_samples: median wall %.2f ms, median cpu %.2f ms (tau_s %.4f +- %.4f)\n", fit_ms, fit_cpu,
              tau, stderr_tau);
  for (const auto& p : fit.params)
    std::printf("  %s %.6g +- %.2g [%.6g, %.6g]\n", p.name.c_str(), p.value, p.std_error, p.ci95_lo, p.ci95_hi);
  bench::print_bench_line("fopdt_fit", fit_timing);
  if (fopdt_only) return 0;

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
