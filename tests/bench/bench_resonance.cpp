// Benchmark: a 410k-sample Klipper raw accelerometer CSV (128 s at 3.2 kHz, a 5 -> 133 Hz sweep
// at 1 Hz/s over two modes) through `tunekit shaper --json`: CSV reading, sampling checks,
// Welch PSD, peak detection, modal fit and shaper selection. Runs the CLI in-process several
// times and prints the median; with --exe PATH it instead starts the real `tunekit` binary as a
// whole process each run (posix_spawn, output to /dev/null), which includes the dynamic loading
// of every shared library; with --write-only it only writes the CSV (for /usr/bin/time -v).
//
//   bench_resonance [--runs N] [--csv PATH] [--write-only] [--klipper-compatible] [--exe PATH]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include "../resonance/synth_sweep.hpp"
#include "bench_common.hpp"
#include "tunekit/core/heap_policy.hpp"
#include "tunekit/cli/run_cli.hpp"

namespace {

// Runs `exe args...` with stdout and stderr to /dev/null; returns its exit code (or 127) and
// adds the child's CPU time (user + system, ms) to `cpu_ms`.
int run_process(const std::string& exe, const std::vector<std::string>& args, std::vector<double>& cpu_ms,
                std::vector<double>& peak_rss_mb) {
  std::vector<char*> argv;
  std::vector<std::string> all{exe};
  all.insert(all.end(), args.begin(), args.end());
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  // posix_spawn (vfork semantics): the child does not copy this benchmark's page tables, whose
  // cost (a fork of a process holding the synthetic record) is not tunekit's.
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, exe.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) return 127;
  int status = 0;
  struct rusage ru {};
  if (wait4(pid, &status, 0, &ru) != pid) return 127;
  cpu_ms.push_back(1e3 * (ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
                   1e-3 * (ru.ru_utime.tv_usec + ru.ru_stime.tv_usec));
  peak_rss_mb.push_back(static_cast<double>(ru.ru_maxrss) / 1024.0);  // ru_maxrss is in KiB on Linux
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

}  // namespace

int main(int argc, char** argv) {
  tunekit::core::keep_freed_memory_in_heap();  // as the tunekit executable runs
  int runs = 7;
  std::string csv = "/tmp/raw_data_x_bench.csv";
  bool write_only = false, klipper = false;
  std::string exe;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--runs" && i + 1 < argc) runs = std::stoi(argv[++i]);
    else if (a == "--csv" && i + 1 < argc) csv = argv[++i];
    else if (a == "--write-only") write_only = true;
    else if (a == "--klipper-compatible") klipper = true;
    else if (a == "--exe" && i + 1 < argc) exe = argv[++i];
  }
  tunekit::test::SweepSpec spec;
  spec.f_start_hz = 5;
  spec.f_end_hz = 133;
  spec.hz_per_sec = 1;
  const auto rec = tunekit::test::synth_sweep({{42.0, 0.05, 1.0}, {77.0, 0.08, 0.6}}, spec);
  {
    std::ofstream f(csv, std::ios::binary);
    f << tunekit::test::to_klipper_csv(rec);
  }
  fmt::print("wrote {} ({} samples, {:.1f} s at {} Hz)\n", csv, rec.t.size(), rec.t.back() - rec.t.front(),
             spec.sample_rate_hz);
  if (write_only) return 0;
  std::vector<double> ms, cpu, rss;
  std::string last;
  for (int r = 0; r < runs; ++r) {
    std::ostringstream out, err;
    std::vector<std::string> args = {"shaper", csv, "--json"};
    if (klipper) args.push_back("--klipper-compatible");
    const auto t0 = std::chrono::steady_clock::now();
    const int code = exe.empty() ? tunekit::cli::run_cli(args, out, err) : run_process(exe, args, cpu, rss);
    const auto t1 = std::chrono::steady_clock::now();
    if (code != 0) {
      fmt::print(stderr, "tunekit shaper failed ({}): {}\n", code, err.str());
      return 1;
    }
    ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    last = out.str();
  }
  tunekit::bench::print_bench_line(exe.empty() ? "shaper_in_process" : "shaper_process",
                                   tunekit::bench::summarize_ms(ms));
  std::sort(ms.begin(), ms.end());
  fmt::print("tunekit shaper on 410k samples{}: median {:.1f} ms over {} runs (min {:.1f}, max {:.1f})\n",
             exe.empty() ? " (in-process)" : " (whole process " + exe + ")", ms[ms.size() / 2], runs, ms.front(),
             ms.back());
  if (!cpu.empty()) {
    std::sort(cpu.begin(), cpu.end());
    fmt::print("  process CPU time (user + system): median {:.1f} ms (min {:.1f}, max {:.1f})\n", cpu[cpu.size() / 2],
               cpu.front(), cpu.back());
    const auto peak = tunekit::bench::summarize_ms(rss);  // MB, not ms: same statistics
    fmt::print("  peak resident memory: median {:.1f} MB (min {:.1f}, max {:.1f})\n", peak.median_ms, peak.min_ms,
               peak.max_ms);
    tunekit::bench::print_bench_line("shaper_process_rss", peak.median_ms, peak.min_ms, peak.max_ms, "MB", peak.runs);
  }
  return 0;
}
