#include "tunekit/calibration/presentation/progress.hpp"

#include <algorithm>
#include <ostream>

#include <fmt/format.h>

namespace tunekit::calibration {

ProgressBar::ProgressBar(CliContext& ctx, int total_steps) : ctx_(ctx), total_(total_steps) {}

ProgressBar::~ProgressBar() { stop_ticker(); }

void ProgressBar::begin(const std::string& label, double estimated_s) {
  stop_ticker();
  ++index_;
  label_ = label;
  estimate_s_ = std::max(estimated_s, 0.1);
  fraction_ = -1;
  start_ = std::chrono::steady_clock::now();
  if (!ctx_.interactive) return;
  running_ = true;
  ticker_ = std::thread([this] {
    while (running_) {
      draw();
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
  });
}

void ProgressBar::update(double fraction) { fraction_ = std::clamp(fraction, 0.0, 1.0); }

void ProgressBar::draw() {
  std::lock_guard lock(mutex_);
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  double f = fraction_;
  if (f < 0) f = std::min(0.99, elapsed / estimate_s_);
  const double left = f > 0.01 ? std::max(0.0, elapsed / f - elapsed) : estimate_s_ - elapsed;
  const int width = 30;
  const int filled = static_cast<int>(f * width);
  ctx_.err << fmt::format("\r[{}/{}] [{}{}] {:3.0f}%  {:<28.28}  {:>4.0f} s left ", index_, total_,
                          std::string(filled, '#'), std::string(width - filled, '-'), 100 * f, label_,
                          std::max(0.0, left))
           << std::flush;
}

void ProgressBar::stop_ticker() {
  running_ = false;
  if (ticker_.joinable()) ticker_.join();
}

void ProgressBar::end(const std::string& summary) {
  stop_ticker();
  if (!ctx_.interactive) return;
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::lock_guard lock(mutex_);
  ctx_.err << fmt::format("\r\033[K[{}/{}] {} ({:.1f} s): {}\n", index_, total_, label_, elapsed, summary)
           << std::flush;
}

}  // namespace tunekit::calibration
