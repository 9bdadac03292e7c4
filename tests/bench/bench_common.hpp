#pragma once
// Tiny timing harness for the benchmark programs: run a callable several times after a
// warm-up and report the median wall time.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

namespace tunekit::bench {

template <class F>
double median_ms(F&& f, int runs = 15, int warmup = 2) {
  for (int i = 0; i < warmup; ++i) f();
  std::vector<double> ms;
  for (int i = 0; i < runs; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    const auto t1 = std::chrono::steady_clock::now();
    ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
  }
  std::sort(ms.begin(), ms.end());
  return ms[ms.size() / 2];
}

}  // namespace tunekit::bench
