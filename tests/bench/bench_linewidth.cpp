// Line width: time from a photo in memory (8-bit grey, already decoded) to the width profile
// of one line, for 1920x1080 and 3840x2160 images (issue 6 targets: < 30 ms and < 100 ms).
// Also reports PNG decoding separately. Prints the median of several runs.
//
//   build/tests/bench/bench_linewidth [runs]
#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <fmt/format.h>
#include "../vision/synthetic_render.hpp"
#include "bench_common.hpp"
#include "tunekit/core/heap_policy.hpp"
#include "tunekit/vision/image_io.hpp"
#include "tunekit/vision/line_width.hpp"

namespace rd = tunekit::test::render;
using Clock = std::chrono::steady_clock;

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

void bench(int w, int h, double line_px, int runs) {
  const auto cov = rd::coverage(w, h, rd::straight_line(0.06 * w, 0.45 * h, 0.94 * w, 0.55 * h, line_px), 8);
  rd::Photo ph;
  ph.noise = 2.0;
  ph.vignetting = 0.3;
  ph.blur_px = 1.2;
  const cv::Mat img = rd::photograph(cov, ph);
  const std::string png = tunekit::vision::encode_png(img);
  std::vector<double> t_profile, t_decode, cpu_profile;
  std::size_t samples = 0;
  double mean_w = 0;
  for (int r = 0; r < runs; ++r) {
    const auto t0 = Clock::now();
    const cv::Mat decoded = tunekit::vision::decode_image(png, "bench.png", tunekit::vision::ImageColor::gray);
    const auto t1 = Clock::now();
    const std::clock_t c1 = std::clock();
    const auto res = tunekit::vision::measure_line_widths(tunekit::vision::to_gray_float(decoded));
    const auto t2 = Clock::now();
    cpu_profile.push_back(1000.0 * static_cast<double>(std::clock() - c1) / CLOCKS_PER_SEC);
    t_decode.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    t_profile.push_back(std::chrono::duration<double, std::milli>(t2 - t1).count());
    if (res.lines.size() != 1) {
      std::fprintf(stderr, "bench_linewidth: expected 1 line, found %zu\n", res.lines.size());
      std::exit(1);
    }
    samples = res.lines[0].samples.size();
    mean_w = res.lines[0].mean_width_px;
  }
  fmt::print(
      "{}x{} one line ({} px wide, {} profile samples, measured {:.3f} px): profile median {:.1f} ms "
      "(CPU {:.1f} ms), PNG decode median {:.1f} ms ({} runs)\n",
      w, h, line_px, samples, mean_w, median(t_profile), median(cpu_profile), median(t_decode), runs);
  tunekit::bench::print_bench_line(fmt::format("linewidth_{}x{}", w, h).c_str(),
                                   tunekit::bench::summarize_ms(t_profile));
}

}  // namespace

int main(int argc, char** argv) {
  tunekit::core::keep_freed_memory_in_heap();  // as the tunekit executable runs
  const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 11;
  bench(1920, 1080, 12.0, runs);
  bench(3840, 2160, 24.0, runs);
  return 0;
}
