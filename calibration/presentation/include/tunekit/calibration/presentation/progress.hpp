#pragma once
// Progress for long steps. On a terminal (stderr is a tty) a bar with the fraction done and
// an estimate of the time left is redrawn a few times a second while a step runs; off a
// terminal nothing is drawn, so logs and CI output stay quiet and machine-readable.

#include <atomic>
#include <chrono>
#include <mutex>
#include <string>
#include <thread>

#include "tunekit/calibration/results/context.hpp"

namespace tunekit::calibration {

class ProgressBar {
 public:
  /// `total_steps` is how many steps the whole job has (shown as "[2/5]").
  ProgressBar(CliContext& ctx, int total_steps);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  /// Starts a step expected to take about `estimated_s` seconds of wall time.
  void begin(const std::string& label, double estimated_s);
  /// Reports measured progress (0..1) when the step knows it; otherwise time is used.
  void update(double fraction);
  /// Ends the step; on a terminal prints one line with its duration and `summary`.
  void end(const std::string& summary);

 private:
  void draw();
  void stop_ticker();

  CliContext& ctx_;
  int total_;
  int index_ = 0;
  std::string label_;
  double estimate_s_ = 1;
  std::atomic<double> fraction_{-1};
  std::chrono::steady_clock::time_point start_;
  std::atomic<bool> running_{false};
  std::thread ticker_;
  std::mutex mutex_;
};

}  // namespace tunekit::calibration
