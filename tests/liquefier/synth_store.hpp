#pragma once
// Synthetic records of the nonlinear liquefier store (tau(q) = a q^b): a staircase of commanded
// flow levels, each held for `hold_s` (2.5 time constants of the slowest level: the steps never
// settle), simulated on a grid `oversample` times finer than the record with the steps at
// arbitrary fine-grid instants, then sampled at the record's rate with Gaussian noise of
// `noise_rel` times the mean output. Shared by the whole-record tests and the benchmark.

#include <cmath>
#include <random>
#include <vector>

#include "tunekit/fitting/liquefier_model.hpp"

namespace tunekit::test {

struct StoreTruth {
  double a = 0.4 * std::pow(4.0, 0.45);  ///< tau(4 mm^3/s) = 0.4 s
  double b = -0.45;
  double theta_s = 0.1;
  double g = 1.0, c = 0.0;
  fitting::LiquefierSensor sensor = fitting::LiquefierSensor::flow;
  double tau(double q) const { return a * std::pow(q, b); }
  double volume(double q) const { return a * std::pow(q, b + 1) / (b + 1); }
  fitting::LiquefierParams params() const { return {a, b, theta_s, g, c}; }
};

struct StoreRecord {
  fitting::LiquefierRecord rec;
  std::vector<double> clean;  ///< the output without noise
  std::vector<double> step_times, levels;
};

inline StoreRecord synth_store(const StoreTruth& tr, double rate_hz, double duration_s, double noise_rel, unsigned seed,
                               std::vector<double> level_set = {4, 6, 8, 10, 12, 14}, int oversample = 8) {
  std::mt19937 rng(seed);
  const double hold = 2.5 * tr.tau(level_set.front());
  // The level sequence: each step goes to another level, drawn at random.
  std::uniform_int_distribution<std::size_t> pick(0, level_set.size() - 1);
  std::uniform_real_distribution<double> jitter(0.0, 1.0);
  StoreRecord s;
  double level = level_set[pick(rng)];
  s.levels.push_back(level);
  for (double t = hold; t < duration_s; t += hold) {
    double next = level;
    while (next == level) next = level_set[pick(rng)];
    level = next;
    s.step_times.push_back(t + jitter(rng) / rate_hz);  // not on the record's sample grid
    s.levels.push_back(level);
  }
  const double dt_fine = 1.0 / (rate_hz * oversample);
  const auto n_fine = static_cast<std::size_t>(duration_s / dt_fine);
  std::vector<double> tf(n_fine), uf(n_fine);
  std::size_t k = 0;
  for (std::size_t i = 0; i < n_fine; ++i) {
    tf[i] = static_cast<double>(i) * dt_fine;
    while (k < s.step_times.size() && s.step_times[k] <= tf[i]) ++k;
    uf[i] = s.levels[k];
  }
  const auto yf = fitting::simulate_liquefier(tf, uf, tr.params(), tr.sensor, 16);
  double mean = 0;
  for (double v : yf) mean += v;
  mean /= static_cast<double>(yf.size());
  std::normal_distribution<double> noise(0.0, noise_rel * std::abs(mean));
  s.rec.sensor = tr.sensor;
  s.rec.input_unit = "mm^3/s";
  s.rec.output_unit = "mm^3/s";
  for (std::size_t i = 0; i < n_fine; i += static_cast<std::size_t>(oversample)) {
    s.rec.t.push_back(tf[i]);
    s.rec.u.push_back(uf[i]);
    s.clean.push_back(yf[i]);
    s.rec.y.push_back(yf[i] + noise(rng));
  }
  return s;
}

}  // namespace tunekit::test
