// The intervals an experiment is expected to give, from the Fisher information of its planned
// excitation (experiment_information.hpp).
#include "tunekit/protocols/experiment_information.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/liquefier_model.hpp"
#include "tunekit/ident/base_excited_mode.hpp"
#include "tunekit/protocols/feed_track_plan.hpp"

#include "sweep_moves.hpp"

namespace tunekit::protocols {
namespace {

constexpr double kZ95 = 1.959963984540054;  // the normal distribution's 97.5 % point

/// sigma^2 (J^T J)^-1 from the rows of J; NaN everywhere when J^T J is singular.
Eigen::MatrixXd covariance(const Eigen::MatrixXd& jtj, double sigma) {
  Eigen::FullPivLU<Eigen::MatrixXd> lu(jtj);
  if (!lu.isInvertible())
    return Eigen::MatrixXd::Constant(jtj.rows(), jtj.cols(), std::numeric_limits<double>::quiet_NaN());
  return sigma * sigma * lu.inverse();
}

/// The samples of the record the fit uses: from the end of the track's first steady stretch
/// (what comes before is the liquefier settling from rest: the analyses start after it) plus
/// `phase` sample periods to the track's end, at `rate_hz`.
std::vector<double> record_instants(const ident::FeedTrack& k, double rate_hz, double phase) {
  std::size_t i = 1;
  while (i + 1 < k.t.size() && !(k.u[i] > 0 && k.u[i + 1] == k.u[i] && k.t[i + 1] > k.t[i])) ++i;
  const double start = (i + 1 < k.t.size() ? k.t[i + 1] : k.t.front()) + phase / rate_hz;
  std::vector<double> t;
  for (double x = start; x <= k.t.back(); x += 1.0 / rate_hz) t.push_back(x);
  return t;
}

// The sensor's clock is not the planner's: where its samples fall between the instants of the
// feed's steps is not known before the run, and drifts through it (a converter runs on its own
// oscillator, off its nominal rate by kMinClockError to kMaxClockError). The dead time is told
// mostly by the samples just after each delayed kink of the feed, above all by those that fall
// inside the brief stops Klipper makes between extrude-only moves (a fraction of a millisecond):
// with a few steps, which samples do is a lottery, and the interval the fit reports varies with
// it (the flow sweep's dead time by +-25 % on the simulated printer). The prediction is the
// estimate's variance averaged over kClockDraws sample grids, each with its own phase and clock
// error (a low-discrepancy sequence: the same grids every time): the variance of the estimate
// when the grid is not known, E[Var(estimate | grid)].
constexpr int kClockDraws = 24;
constexpr double kMinClockError = 0.001, kMaxClockError = 0.01;

/// The `k`-th of the kClockDraws grids: (phase in sample periods, relative clock error).
std::pair<double, double> clock_draw(int k) {
  constexpr double kGolden = 0.6180339887498949;
  const double u = std::fmod((k + 1) * kGolden, 1.0);
  const double error = kMinClockError + (kMaxClockError - kMinClockError) * u;
  return {(k + 0.5) / kClockDraws, k % 2 == 0 ? error : -error};
}

/// The track's feed at time x (linear between breakpoints, held outside).
double track_feed(const ident::FeedTrack& k, double x) {
  const auto it = std::upper_bound(k.t.begin(), k.t.end(), x);
  if (it == k.t.begin()) return k.u.front();
  if (it == k.t.end()) return k.u.back();
  const std::size_t j = static_cast<std::size_t>(it - k.t.begin());
  const double h = k.t[j] - k.t[j - 1];
  return h > 0 ? k.u[j - 1] + (k.u[j] - k.u[j - 1]) * (x - k.t[j - 1]) / h : k.u[j];
}

/// The accelerometer's reading y = a + g z'' at `rate_hz` under the pulses, for one mode.
std::vector<double> axis_reading(const std::vector<experiment_gcode::SweepSegment>& segs, double f, double zeta,
                                 double rate_hz, std::vector<double>* accel) {
  const ident::BaseExcitedMode mode(f, zeta);
  ident::ModeState x;
  std::vector<double> y;
  double t = 0, next = 0;
  std::size_t s = 0;
  while (s < segs.size()) {
    const double a = segs[s].accel_mm_s2;
    const double stop = std::min(segs[s].t_end_s, next);
    x = mode.advance(x, stop - t, a, 0);
    t = stop;
    if (t >= next) {
      y.push_back(a + mode.relative_accel(x, a));
      if (accel) accel->push_back(a);
      next += 1.0 / rate_hz;
    }
    if (t >= segs[s].t_end_s) ++s;
  }
  return y;
}

}  // namespace

const PredictedInterval* ExperimentPrediction::find(const std::string& quantity) const {
  for (const auto& i : intervals)
    if (i.quantity == quantity) return &i;
  return nullptr;
}

nlohmann::json ExperimentPrediction::to_json() const {
  nlohmann::json q = nlohmann::json::object();
  for (const auto& i : intervals)
    q[i.quantity] = {{"prior", i.value}, {"half_width", i.half_width}, {"relative_half_width", i.relative()}};
  return {{"intervals", q}, {"basis", basis}};
}

LiquefierPrior typical_liquefier_prior(double noise_N, double rate_hz) {
  LiquefierPrior p;
  p.tau_ref_s = 0.025;
  p.ref_feed_mm_s = 2.25;
  p.b = -0.5;
  p.theta_s = 0.02;
  p.gain_N_per_mm_s = 3.5;
  p.noise_N = noise_N;
  p.rate_hz = rate_hz;
  p.basis = fmt::format(
      "a desktop direct-drive liquefier with PLA (advance 0.05 s: tau 0.025 s at 2.25 mm/s, b -0.5, theta 0.02 s, "
      "3.5 N per mm/s), load cell {:g} N rms at {:g} Hz",
      noise_N, rate_hz);
  return p;
}

AxisPrior typical_axis_prior(double noise_mm_s2, double rate_hz) {
  AxisPrior p;
  p.freq_hz = 45;
  p.zeta = 0.1;
  p.noise_mm_s2 = noise_mm_s2;
  p.rate_hz = rate_hz;
  p.basis = fmt::format("a desktop printer's axis (45 Hz, damping ratio 0.1), accelerometer {:g} mm/s^2 rms at {:g} Hz",
                        noise_mm_s2, rate_hz);
  return p;
}

namespace {

/// The whole-record model's J^T J (columns a, b, theta, v0, g, c) over the samples `t` of the
/// track, the median positive feed over them appended to `feeds`.
Eigen::MatrixXd liquefier_information(const ident::FeedTrack& track, const std::vector<double>& t,
                                      fitting::LiquefierParams p, double prior_theta_s, std::vector<double>& feeds) {
  p.v0 = fitting::liquefier_volume(p, std::max(track_feed(track, t.front() - prior_theta_s), 1e-6));
  const auto sens = fitting::liquefier_sensitivities(t, track.t, track.u, p, fitting::LiquefierSensor::flow);
  const auto y = fitting::simulate_liquefier(t, track.t, track.u, p, fitting::LiquefierSensor::flow);
  Eigen::MatrixXd jtj = Eigen::MatrixXd::Zero(6, 6);
  for (std::size_t i = 0; i < t.size(); ++i) {
    Eigen::Matrix<double, 6, 1> row;
    row << sens[i][0], sens[i][1], sens[i][2], sens[i][3], (y[i] - p.c) / p.g, 1.0;
    jtj += row * row.transpose();
    if (const double u = track_feed(track, t[i]); u > 0) feeds.push_back(u);
  }
  return jtj;
}

}  // namespace

ExperimentPrediction predict_liquefier_record(const Experiment& e, const LiquefierPrior& prior) {
  const ident::FeedTrack track = planned_feed_track(e);
  if (track.t.size() < 3) throw InputError(fmt::format("{} has no planned feed track to predict from", e.protocol));
  if (record_instants(track, prior.rate_hz, 0).size() < 10)
    throw InputError(fmt::format("{} records too little to predict from", e.protocol));
  fitting::LiquefierParams p;
  p.b = prior.b;
  p.a = prior.tau_ref_s * std::pow(prior.ref_feed_mm_s, -prior.b);
  p.theta_s = prior.theta_s;
  p.g = prior.gain_N_per_mm_s;
  p.c = prior.offset_N;
  // The covariance averaged over the grids (each grid's inverted on its own).
  std::vector<double> feeds;
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(6, 6);
  for (int k = 0; k < kClockDraws; ++k) {
    const auto [phase, error] = clock_draw(k);
    cov += covariance(liquefier_information(track, record_instants(track, prior.rate_hz * (1 + error), phase), p,
                                            prior.theta_s, feeds),
                      prior.noise_N) /
           kClockDraws;
  }
  std::nth_element(feeds.begin(), feeds.begin() + feeds.size() / 2, feeds.end());
  const double q_ref = feeds[feeds.size() / 2];
  const Eigen::Vector2d grad(1 / p.a, std::log(q_ref));  // d ln tau_ref / d(a, b)
  const double var_ln_tau = grad.transpose() * cov.topLeftCorner(2, 2) * grad;
  ExperimentPrediction out;
  const double tau_ref = p.a * std::pow(q_ref, p.b);
  out.intervals.push_back({"tau_ref_s", tau_ref, kZ95 * tau_ref * std::sqrt(var_ln_tau)});
  out.intervals.push_back({"b", p.b, kZ95 * std::sqrt(cov(1, 1))});
  out.intervals.push_back({"theta_s", p.theta_s, kZ95 * std::sqrt(cov(2, 2))});
  out.intervals.push_back({"g", p.g, kZ95 * std::sqrt(cov(4, 4))});
  out.basis = prior.basis;
  return out;
}

ExperimentPrediction predict_axis_sweep(const Experiment& e, const AxisPrior& prior) {
  if (e.protocol != "axis-sweep") throw InputError(fmt::format("{} is not an axis sweep", e.protocol));
  const auto& p = e.params;
  auto d = experiment_gcode::sweep_design_from_params(p, e.excitation.value("accel_limit_mm_s2", 0.0));
  d.min_half_mm = e.excitation.value("min_move_mm", 0.0);
  const auto segs = experiment_gcode::add_sweeping(experiment_gcode::vibration_pulses(d), d);
  std::vector<double> accel;
  const auto y = axis_reading(segs, prior.freq_hz, prior.zeta, prior.rate_hz, &accel);
  // Sensitivities to f and zeta by central differences; to the gain (z'') and the offset exactly.
  const double hf = 1e-5 * prior.freq_hz, hz = 1e-5 * prior.zeta;
  const auto fp = axis_reading(segs, prior.freq_hz + hf, prior.zeta, prior.rate_hz, nullptr);
  const auto fm = axis_reading(segs, prior.freq_hz - hf, prior.zeta, prior.rate_hz, nullptr);
  const auto zp = axis_reading(segs, prior.freq_hz, prior.zeta + hz, prior.rate_hz, nullptr);
  const auto zm = axis_reading(segs, prior.freq_hz, prior.zeta - hz, prior.rate_hz, nullptr);
  Eigen::Matrix4d jtj = Eigen::Matrix4d::Zero();
  for (std::size_t i = 0; i < y.size(); ++i) {
    const Eigen::Vector4d row((fp[i] - fm[i]) / (2 * hf), (zp[i] - zm[i]) / (2 * hz), y[i] - accel[i], 1.0);
    jtj += row * row.transpose();
  }
  const Eigen::MatrixXd cov = covariance(jtj, prior.noise_mm_s2);
  ExperimentPrediction out;
  out.intervals.push_back({"freq_hz", prior.freq_hz, kZ95 * std::sqrt(cov(0, 0))});
  out.intervals.push_back({"zeta", prior.zeta, kZ95 * std::sqrt(cov(1, 1))});
  out.basis = prior.basis;
  return out;
}

}  // namespace tunekit::protocols
