// Benchmark: read a Klipper raw accelerometer CSV (#time,accel_x,accel_y,accel_z) of about
// 20 MB / 410k rows with the time column checked.
//   bench_csv_read --generate FILE   writes the deterministic test file
//   bench_csv_read FILE              prints the median read time over 15 runs
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include <fmt/format.h>

#include "bench_common.hpp"
#include "tunekit/core/heap_policy.hpp"
#include "tunekit/formats/csv.hpp"

namespace {

void generate(const char* path) {
  FILE* f = std::fopen(path, "w");
  if (!f) {
    std::perror(path);
    std::exit(2);
  }
  std::fputs("#time,accel_x,accel_y,accel_z\n", f);
  const int rows = 410000;
  for (int i = 0; i < rows; ++i) {
    const double t = 2049.0 + i / 3200.0;
    std::fprintf(f, "%.6f,%.6f,%.6f,%.6f\n", t, 1500.0 * std::sin(0.37 * i), -1200.0 * std::cos(0.11 * i),
                 9806.65 + 35.0 * std::sin(0.05 * i));
  }
  std::fclose(f);
}

}  // namespace

int main(int argc, char** argv) {
  tunekit::core::keep_freed_memory_in_heap();  // as the tunekit executable runs
  if (argc == 3 && std::strcmp(argv[1], "--generate") == 0) {
    generate(argv[2]);
    return 0;
  }
  if (argc != 2) {
    std::fprintf(stderr, "usage: bench_csv_read [--generate] FILE\n");
    return 2;
  }
  std::size_t rows = 0;
  const auto timing = tunekit::bench::time_ms([&] {
    const auto t = tunekit::formats::read_csv(argv[1], {{"accel_x", "accel_y", "accel_z"}, "time"});
    rows = t.rows;
  });
  fmt::print("read_csv {}: {} rows, median {:.1f} ms over 15 runs\n", argv[1], rows, timing.median_ms);
  tunekit::bench::print_bench_line("csv_read", timing);
  return 0;
}
