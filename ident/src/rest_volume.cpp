// The stored volume at a record's first level from its start-up transient (rest_volume.hpp).
#include "tunekit/ident/rest_volume.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "tunekit/ident/liquefier_record.hpp"
#include "tunekit/fitting/stats.hpp"

namespace tunekit::ident {
namespace {

// Two-sided 95 % quantile of the normal distribution: the area sums hundreds of samples.
// Time constants of the first level waited after the store has reached it at its mean rate: the
// transient left then is e^-10 (5e-5) of the level's volume, far below the area's noise.
constexpr double kSettleTimeConstants = 10.0;
// A record starts at rest when the outflow it shows before the first feed arrives is within
// three standard errors of zero, or within this share of the first level (a load cell's offset
// drifts by a few mN between a tare and a run).
constexpr double kRestShare = 0.02;
// The start of a record may be measured less precisely than the rest (a camera's line test: where
// the bead is thin or not yet there its width is the integrated contrast, several times noisier
// than the edge fit that takes over at 80 % of the line's width): up to the first sample at 80 %
// of the first level, the noise is that of the samples at rest, when there are at least 20 of
// them, with their own correlation's variance factor.
constexpr double kStartShare = 0.8;
constexpr std::size_t kMinRestSamples = 20;
// Parameter order of the whole-record fit (fitting/liquefier_model.hpp): tau_ref_s, b, theta_s, g, c, V0.
constexpr std::size_t kTheta = 2, kGain = 3, kOffset = 4;

nlohmann::json rest_num(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

std::optional<RestVolume> refuse(std::string* why, std::string reason) {
  if (why != nullptr) *why = std::move(reason);
  return std::nullopt;
}

/// The first level of a track that starts with the feed off: when it begins (t_on), its feed and
/// when the next change begins. False when the track does not start off or never holds a level.
struct FirstLevel {
  double t_on = fitting::kNaN, u1 = fitting::kNaN, t_change = fitting::kNaN;
};

std::optional<FirstLevel> first_level(const FeedTrack& k) {
  if (k.t.size() < 3 || k.u.front() != 0) return std::nullopt;
  std::size_t on = 1;
  while (on < k.t.size() && k.u[on] == 0) ++on;
  if (on >= k.t.size()) return std::nullopt;
  FirstLevel f;
  f.t_on = k.t[on - 1];
  // The rise ends where the track holds its value over a breakpoint pair.
  for (std::size_t j = on; j + 1 < k.t.size(); ++j)
    if (k.u[j + 1] == k.u[j] && k.u[j] > 0) {
      f.u1 = k.u[j];
      std::size_t e = j + 1;
      while (e + 1 < k.t.size() && k.u[e + 1] == f.u1) ++e;
      f.t_change = e + 1 < k.t.size() ? k.t[e] : std::numeric_limits<double>::infinity();
      return f;
    }
  return std::nullopt;
}

// The noise (output unit, variance factor included) of the samples at rest before the first feed
// arrives; `s` (the model's) when there are too few of them.
double start_noise(std::span<const double> t, std::span<const double> y, const FirstLevel& level, double theta,
                   double c, double s) {
  std::vector<double> r;
  for (std::size_t i = 0; i < t.size() && t[i] < level.t_on + theta; ++i) r.push_back(y[i] - c);
  if (r.size() < kMinRestSamples) return s;
  double mean = 0;
  for (double v : r) mean += v / static_cast<double>(r.size());
  double ss = 0;
  for (double& v : r) v -= mean, ss += v * v;
  return std::sqrt(ss / static_cast<double>(r.size() - 1) * fitting::residual_variance_factor(r));
}

}  // namespace

std::optional<RestVolume> measure_rest_volume(std::span<const double> t, std::span<const double> y,
                                              const WholeRecordModel& m, std::string* why) {
  if (m.model.sensor != fitting::LiquefierSensor::flow)
    return refuse(why, "a pressure sensor reads the stored volume at every level: nothing below the data to measure");
  if (m.input_track.empty()) return refuse(why, "no commanded feed track: the start's instant is known to a sample");
  if (t.size() < 8 || y.size() != t.size()) return refuse(why, "the record is too short");
  const auto level = first_level(m.input_track);
  if (!level) return refuse(why, "the feed track does not start with the feed off and then hold a level");
  const auto& f = m.model.fit;
  const double theta = f.value("theta_s"), g = f.value("g"), c = f.value("c");
  const fitting::LiquefierParams p = m.model.params();
  const double u1 = level->u1;
  const double t_settle = level->t_on + theta + fitting::liquefier_volume(p, u1) / u1 +
                          kSettleTimeConstants * fitting::liquefier_tau_s(p, u1);
  if (!(t_settle <= level->t_change + theta) || !(t_settle < t.back()))
    return refuse(why, "the first level is too short to settle within it");
  if (!(t.front() <= level->t_on + theta))
    return refuse(why, "the record begins after the feed has reached the nozzle");

  // Rest: the outflow before the first feed arrives.
  double pre_sum = 0;
  std::size_t pre = 0;
  for (std::size_t i = 0; i < t.size() && t[i] < level->t_on + theta; ++i, ++pre) pre_sum += (y[i] - c) / g;
  const double s = f.diagnostics.rms * std::sqrt(m.model.variance_factor);
  if (pre == 0 || !(std::abs(pre_sum / static_cast<double>(pre)) <=
                    3 * s / std::abs(g) / std::sqrt(static_cast<double>(pre)) + kRestShare * u1))
    return refuse(why, "the record does not start at rest");

  RestVolume v;
  v.input = u1;
  const std::vector<double> edges = sample_window_edges(t);
  double out = 0, width_sq = 0, start_width_sq = 0;
  std::size_t i = 0;
  bool rising = true;
  for (; i < t.size() && t[i] <= t_settle; ++i) {
    const double w = edges[i + 1] - edges[i], q = (y[i] - c) / g;
    out += q * w;
    rising = rising && !(q >= kStartShare * u1);
    (rising ? start_width_sq : width_sq) += w * w;
  }
  v.samples = i;
  const double s_start = start_noise(t, y, *level, theta, c, s);
  v.window_begin_s = edges.front();
  v.window_end_s = edges[i];
  const double fed = feed_track_integral(m.input_track, v.window_end_s - theta) -
                     feed_track_integral(m.input_track, v.window_begin_s - theta);
  v.value = fed - out;

  // d V / d (theta, g, c), with the fit's covariance (natural units, times the variance factor).
  const std::array<double, 3> J{-u1, out / g, (v.window_end_s - v.window_begin_s) / g};
  const std::array<std::size_t, 3> idx{kTheta, kGain, kOffset};
  const std::size_t n = f.params.size();
  double var = (s * s * width_sq + s_start * s_start * start_width_sq) / (g * g);
  if (f.covariance.size() == n * n)
    for (std::size_t a = 0; a < 3; ++a)
      for (std::size_t b = 0; b < 3; ++b)
        var += J[a] * J[b] * f.covariance[idx[a] * n + idx[b]] * m.model.variance_factor;
  v.std_error = std::sqrt(var);
  v.ci95_lo = v.value - fitting::kZ95 * v.std_error;
  v.ci95_hi = v.value + fitting::kZ95 * v.std_error;
  if (!(v.value > 0) || !std::isfinite(v.std_error))
    return refuse(why, "the start-up transient's area is not positive (the record's start is not a rise from rest)");
  return v;
}

nlohmann::json to_json(const std::optional<RestVolume>& v, const std::string& why) {
  if (!v) return {{"measured", false}, {"why", why}};
  return {{"measured", true},
          {"input", rest_num(v->input)},
          {"value", rest_num(v->value)},
          {"stderr", rest_num(v->std_error)},
          {"ci95", {rest_num(v->ci95_lo), rest_num(v->ci95_hi)}},
          {"window_s", {rest_num(v->window_begin_s), rest_num(v->window_end_s)}},
          {"samples", v->samples},
          {"basis",
           "the start-up transient's area from rest, integral of (u(t - theta) - (y - c) / g) dt until settled at the "
           "first level"}};
}

}  // namespace tunekit::ident
