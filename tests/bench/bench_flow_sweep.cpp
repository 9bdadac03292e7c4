// Flow-sweep analysis benchmark: a 6-level liquefier flow sweep (the liquefier-flow-sweep
// protocol's order: 14 steps, each level reached from below and above) at 1 kHz, about two
// minutes of data, through the whole step analysis (step detection, 14 single-step FOPDT fits,
// the pooled fit, the arrival levels with their rising/falling fits, the trends). Prints medians
// and the "BENCH flow_sweep_analysis" line scripts/bench reads (wall time of the whole analysis).
//   build/tests/bench/bench_flow_sweep [runs] [--json FILE]
// --json writes the analysis (every fit with its values and intervals) to FILE, to compare the
// results of two builds.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "../liquefier/synth_flow_sweep.hpp"
#include "bench_common.hpp"
#include "tunekit/core/heap_policy.hpp"
#include "tunekit/ident/step_analysis.hpp"

namespace {
// Median process CPU time (ms) of f over `runs` runs (the wall time on a shared machine also
// counts waiting for a core).
template <class F>
double median_cpu_ms_flow(F&& f, int runs) {
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
  int runs = 9;
  const char* json_path = nullptr;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--json") == 0 && i + 1 < argc) json_path = argv[++i];
    else runs = std::max(1, std::stoi(argv[i]));
  }
  test::SynthFlowSweepTruth tr;
  // 1.5 to 15 mm^3/s, 8 s per level (14 tau at the slowest level): 3 + 14 * 8 = 115 s.
  const auto s = test::synth_flow_sweep(tr, 6, 1.5, 15, 8.0, 3.0);
  ident::StepAnalysisOptions o;
  o.input_unit = "mm^3/s";
  std::size_t levels = 0;
  double b = 0;
  const bench::Timing wall = bench::time_ms(
      [&] {
        const auto a = ident::analyze_steps(s.t, s.u, s.y, o);
        levels = a.arrival_levels.size();
        b = a.level_trends.tau ? a.level_trends.tau->value("b") : 0;
      },
      runs, 1);
  const double cpu = median_cpu_ms_flow([&] { (void)ident::analyze_steps(s.t, s.u, s.y, o); }, runs);
  std::printf("flow_sweep_6_levels_%zu_samples: median wall %.2f ms, median cpu %.2f ms (%zu arrival levels, b %.4f)\n",
              s.t.size(), wall.median_ms, cpu, levels, b);
  bench::print_bench_line("flow_sweep_analysis", wall);
  if (json_path != nullptr) {
    std::ofstream out(json_path);
    out << ident::to_json(ident::analyze_steps(s.t, s.u, s.y, o)).dump(1) << "\n";
  }
  // Where the time goes: the 14 single-step fits, and the pooled fit over all of them.
  const auto det = ident::detect_steps(s.t, s.u, o.detect);
  std::vector<fitting::StepRecord> recs;
  std::size_t fitted = 0;
  for (const auto& st : det) {
    fitting::StepRecord r;
    r.t.assign(s.t.begin() + static_cast<std::ptrdiff_t>(st.begin), s.t.begin() + static_cast<std::ptrdiff_t>(st.end));
    r.y.assign(s.y.begin() + static_cast<std::ptrdiff_t>(st.begin), s.y.begin() + static_cast<std::ptrdiff_t>(st.end));
    r.t_step = st.t_step_s;
    r.du = st.u_after - st.u_before;
    fitted += r.t.size();
    recs.push_back(std::move(r));
  }
  std::vector<fitting::FitResult> fits;
  const double singles = median_cpu_ms_flow(
      [&] {
        fits.clear();
        for (const auto& r : recs) fits.push_back(fitting::fit_step(r, o.model));
      },
      runs);
  int iterations = 0;
  const double pooled = median_cpu_ms_flow(
      [&] { iterations = fitting::fit_steps_pooled(recs, o.model, &fits.front()).diagnostics.iterations; }, runs);
  std::printf(
      "  of which: %zu single-step fits (%zu samples) median cpu %.2f ms; pooled fit over all steps (%zu + 3 "
      "parameters, %d iterations) median cpu %.2f ms\n",
      recs.size(), fitted, singles, recs.size(), iterations, pooled);
  return 0;
}
