// Times `tunekit step` as a C++ program calls it: compute_step() on a log file (read, step fit
// with intervals) and its JSON envelope, in CPU time. The Python row (tests/bench/python_step.py)
// runs this program and the same call from Python alternately and compares. Unlike the other
// benchmark programs it keeps glibc's default heap policy: the Python process it is compared
// with has that one (core/heap_policy.hpp).
//   build/tests/bench/bench_step_command FILE STEP_TIME_S STEP_SIZE [RUNS]
// FILE: bench_liquefier --write-step's record (columns t_s, y; 100k samples, one FOPDT step).
#include <algorithm>
#include <cstdio>
#include <ctime>
#include <string>
#include <vector>

#include "bench_common.hpp"
#include "tunekit/calibration/analyses/step_command.hpp"
#include "tunekit/core/error.hpp"

int main(int argc, char** argv) {
  using namespace tunekit;
  if (argc < 4) {
    std::fprintf(stderr, "usage: bench_step_command FILE STEP_TIME_S STEP_SIZE [RUNS]\n");
    return 2;
  }
  calibration::StepOptions o;
  o.file = argv[1];
  o.output_column = "y";
  o.step_time_s = std::stod(argv[2]);
  o.step_size = std::stod(argv[3]);
  o.analysis.model = fitting::StepModel::fopdt;
  const int runs = argc > 4 ? std::stoi(argv[4]) : 5;
  std::size_t bytes = 0;
  auto once = [&] { bytes += calibration::to_envelope(calibration::compute_step(o)).results().dump().size(); };
  try {
    once();  // warm-up: the file in the page cache, the allocator's arenas
  } catch (const Error& e) {
    std::fprintf(stderr, "%s\n", e.formatted().c_str());
    return 1;
  }
  std::vector<double> ms;
  for (int i = 0; i < runs; ++i) {
    const std::clock_t c0 = std::clock();
    once();
    ms.push_back(1000.0 * static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC);
  }
  const bench::Timing t = bench::summarize_ms(ms);
  std::printf("compute_step + envelope, CPU: median %.2f ms (%zu bytes of results per run)\n", t.median_ms,
              bytes / static_cast<std::size_t>(runs + 1));
  bench::print_bench_line("cpp_step_command_cpu", t);
  return 0;
}
