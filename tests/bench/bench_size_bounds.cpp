// Benchmark: the three file analyses at the sizes of their row bounds' tests: `tunekit rheo` on
// a 10,000-row viscosity file (model comparison, superposition check and intervals included),
// `tunekit rheo --model cross-wlf` on 10,000 rows at five temperatures where D1, D2 and A1 are
// not separately identifiable (profile-likelihood intervals on the WLF ridge),
// `tunekit nozzle --fit` on 100,000 measurements and `tunekit delta` on 100,000 probe heights,
// each the command's in-process compute function on a generated file. Prints the median of
// several runs (wall and CPU) and BENCH lines.
//   build/tests/bench/bench_size_bounds [runs]
//   build/tests/bench/bench_size_bounds --write-cross-wlf FILE   (only writes that file: time
//       the whole process with `tunekit rheo FILE --model cross-wlf`)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

#include "../support/size_bound_inputs.hpp"
#include "bench_common.hpp"
#include "tunekit/core/heap_policy.hpp"
#include "tunekit/calibration/analyses/delta_command.hpp"
#include "tunekit/calibration/analyses/nozzle_command.hpp"
#include "tunekit/calibration/analyses/rheo_command.hpp"
#include "tunekit/fitting/nozzle_pressure.hpp"
#include "tunekit/sim/delta_probe_sim.hpp"

using namespace tunekit;

namespace {

constexpr double kR = 8.314462618;  // J/(mol K)

void write(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

// Boles' pressure drop of a power law (K 2e4 Pa.s^n, n 0.35, Ea 50 kJ/mol) through the default
// nozzle at three temperatures, 2 % noise.
std::string nozzle_csv(int rows) {
  std::mt19937 gen(53);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::uniform_real_distribution<double> flow(0.5, 20.0);
  const fitting::NozzleGeometry g;
  std::string s = "flow (mm3/s),pressure (MPa),temperature (degC)\n";
  const double temps[] = {395, 410, 425};
  for (int i = 0; i < rows; ++i) {
    const double T = temps[i % 3], q = flow(gen);
    const double aT = std::exp(50000.0 / kR * (1 / (T + 273.15) - 1 / (410 + 273.15)));
    const double dp = fitting::pressure_drop(fitting::PressureModel::boles, 2e4 * aT, 0.35, q * 1e-9, g);
    char line[96];
    std::snprintf(line, sizeof line, "%.6g,%.6g,%g\n", q, dp * 1e-6 * std::exp(noise(gen)), T);
    s += line;
  }
  return s;
}

template <class F>
void time_command(const char* key, const char* what, int runs, F&& f) {
  f();  // warm-up
  std::vector<double> ms, cpu;
  for (int r = 0; r < runs; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    const std::clock_t c0 = std::clock();
    f();
    cpu.push_back(1000.0 * static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  const auto t = bench::summarize_ms(ms);
  std::sort(cpu.begin(), cpu.end());
  bench::print_bench_line(key, t);
  std::printf("%s: median %.1f ms wall (min %.1f, max %.1f), median %.1f ms CPU, over %d runs\n", what, t.median_ms,
              t.min_ms, t.max_ms, cpu[cpu.size() / 2], runs);
}

}  // namespace

int main(int argc, char** argv) {
  tunekit::core::keep_freed_memory_in_heap();  // as the tunekit executable runs
  if (argc == 3 && std::string(argv[1]) == "--write-cross-wlf") {
    write(argv[2], test::cross_wlf_rheometer_csv(10000));
    return 0;
  }
  const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 5;
  const auto dir = std::filesystem::temp_directory_path() / ("tunekit_bench_size_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const std::string rheo = (dir / "rheo_10000.csv").string(), nozzle = (dir / "nozzle_100000.csv").string(),
                    delta = (dir / "delta_100001.csv").string(), wlf = (dir / "rheo_cross_wlf_10000.csv").string();
  write(rheo, test::cross_rheometer_csv(10000));
  write(wlf, test::cross_wlf_rheometer_csv(10000));
  write(nozzle, nozzle_csv(100000));
  write(delta, test::delta_probe_csv(100, 1000));

  calibration::RheoOptions ro;
  ro.file = rheo;
  time_command("rheo_10k_rows", "tunekit rheo, 10,000 rows, model auto (comparison, superposition, intervals)", runs,
               [&] { (void)calibration::compute_rheo(ro); });
  calibration::RheoOptions wo;
  wo.file = wlf;
  wo.model = "cross-wlf";
  time_command("rheo_cross_wlf_10k_rows",
               "tunekit rheo --model cross-wlf, 10,000 rows at 5 temperatures, D1, D2, A1 on a ridge", runs,
               [&] { (void)calibration::compute_rheo(wo); });
  calibration::NozzleOptions no;
  no.fit_file = nozzle;
  time_command("nozzle_fit_100k_rows", "tunekit nozzle --fit, 100,000 rows", runs,
               [&] { (void)calibration::compute_nozzle(no); });
  calibration::DeltaOptions dopt;
  dopt.probes_csv = delta;
  dopt.radius_mm = 105;
  dopt.rod_mm = {215};
  dopt.height_mm = 250;
  time_command("delta_100k_rows", "tunekit delta, 100,001 probe rows, 6 factors", runs,
               [&] { (void)calibration::compute_delta(dopt); });
  std::filesystem::remove_all(dir);
  return 0;
}
