#pragma once
// Synthetic records of the nonlinear liquefier store (tau(q) = a q^b): a staircase of commanded
// flow levels, each held for 2.5 time constants of the slowest level (the steps never settle),
// stepping at instants drawn uniformly inside a sample interval (never on the record's grid). The
// record carries what a real one would: the commanded staircase exactly (input_t, input_u: the
// feed is known from the G-code) and sampled at the record's instants (u), and the sensor's
// output at the record's rate with Gaussian noise of `noise_rel` times the mean output, simulated
// from the exact staircase with `oversample` sub-steps in every piece. Shared by the
// whole-record tests and the benchmark.

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
  // The exact staircase: two points at each step's instant.
  std::vector<double> tu{0.0}, uu{s.levels.front()};
  for (std::size_t k = 0; k < s.step_times.size(); ++k) {
    tu.insert(tu.end(), {s.step_times[k], s.step_times[k]});
    uu.insert(uu.end(), {s.levels[k], s.levels[k + 1]});
  }
  const auto n = static_cast<std::size_t>(duration_s * rate_hz);
  std::vector<double> t(n), u(n);
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {
    t[i] = static_cast<double>(i) / rate_hz;
    while (k < s.step_times.size() && s.step_times[k] <= t[i]) ++k;
    u[i] = s.levels[k];
  }
  const auto clean = fitting::simulate_liquefier(t, tu, uu, tr.params(), tr.sensor, oversample);
  double mean = 0;
  for (double v : clean) mean += v;
  mean /= static_cast<double>(clean.size());
  std::normal_distribution<double> noise(0.0, noise_rel * std::abs(mean));
  s.rec.sensor = tr.sensor;
  s.rec.input_unit = "mm^3/s";
  s.rec.output_unit = "mm^3/s";
  s.rec.t = t;
  s.rec.u = u;
  s.rec.input_t = tu;
  s.rec.input_u = uu;
  s.clean = clean;
  for (double v : clean) s.rec.y.push_back(v + noise(rng));
  return s;
}

}  // namespace tunekit::test
