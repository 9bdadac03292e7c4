// Step fits that follow the commanded feed track (fitting::StepRecord::input_t): a first-order
// liquefier fed through Klipper's stops between extrude-only moves, logged as a load cell logs
// its feed (each sample's mean over its window), fitted against the track and against the means.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/first_order.hpp"
#include "tunekit/fitting/least_squares.hpp"
#include "tunekit/ident/feed_track.hpp"
#include "tunekit/ident/step_analysis.hpp"

using namespace tunekit;

namespace {

// The truth of the simulated printer's liquefier with one time constant (sim: tau_flow_exponent=0).
constexpr double kTrackK = 3.5, kTrackTau = 0.026, kTrackTheta = 0.02, kTrackY0 = 0.5;
constexpr double kTrackRate = 200, kTrackAccel = 2000;  // load cell (Hz); extrude-only acceleration (mm/s^2)

// Levels held one second each, joined by Klipper's stop: decelerate to rest, accelerate again.
// The first stop begins `phase` s into a sample window, so the stops fall anywhere in theirs.
ident::FeedTrack stop_track(const std::vector<double>& levels, double phase) {
  ident::FeedTrack k;
  double t = -1.0;
  k.t.push_back(t);
  k.u.push_back(levels.front());
  for (std::size_t i = 1; i < levels.size(); ++i) {
    t = static_cast<double>(i - 1) + phase;
    k.t.insert(k.t.end(), {t, t + levels[i - 1] / kTrackAccel});
    k.u.insert(k.u.end(), {levels[i - 1], 0.0});
    t += (levels[i - 1] + levels[i]) / kTrackAccel;
    k.t.push_back(t);
    k.u.push_back(levels[i]);
  }
  k.t.push_back(static_cast<double>(levels.size()));
  k.u.push_back(levels.back());
  return k;
}

struct StopRecord {
  std::vector<double> t, u, y;  // s, logged window-mean feed (mm/s), noise-free force (N)
};

// The liquefier's force at 200 Hz, integrated on a 2 us grid independently of the fits' exact
// solution (the input at each step's middle), and the window means of the feed.
StopRecord simulate_stops(const ident::FeedTrack& k) {
  constexpr double h = 2e-6;
  const double begin = k.t.front(), end = k.t.back();
  const auto steps = static_cast<std::size_t>((end - begin) / h);
  std::vector<double> x(steps + 1), fed(steps + 1);
  const double e = std::exp(-h / kTrackTau);
  x[0] = k.u.front();
  std::size_t piece = 1;
  auto feed_at = [&](double s) {
    while (piece + 1 < k.t.size() && k.t[piece] <= s) ++piece;
    const double a = k.t[piece - 1], b = k.t[piece];
    return b > a ? k.u[piece - 1] + (k.u[piece] - k.u[piece - 1]) * std::min(1.0, (s - a) / (b - a)) : k.u[piece];
  };
  for (std::size_t j = 0; j < steps; ++j) {
    const double v = feed_at(begin + (static_cast<double>(j) + 0.5) * h);
    x[j + 1] = v + (x[j] - v) * e;
    fed[j + 1] = fed[j] + v * h;
  }
  auto at = [&](const std::vector<double>& f, double s) {
    const double p = std::clamp((s - begin) / h, 0.0, static_cast<double>(steps));
    const auto j = std::min(static_cast<std::size_t>(p), steps - 1);
    return f[j] + (f[j + 1] - f[j]) * (p - static_cast<double>(j));
  };
  StopRecord r;
  for (double t = begin + 0.1; t < end - 0.01; t += 1 / kTrackRate) {
    r.t.push_back(t);
    r.u.push_back((at(fed, t + 0.5 / kTrackRate) - at(fed, t - 0.5 / kTrackRate)) * kTrackRate);
    r.y.push_back(kTrackY0 + kTrackK * at(x, t - kTrackTheta));
  }
  return r;
}

std::vector<double> stop_noise(const std::vector<double>& y, double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  std::vector<double> out = y;
  for (double& v : out) v += noise(rng);
  return out;
}

// The simulated flow sweep's levels around its top one (mm/s of filament): up to the top, down
// from it and on down, the steps whose stops are the largest.
const std::vector<double> kTopLevels{2.606, 3.826, 5.618, 3.826, 2.606};

}  // namespace

TEST_CASE("step fits that follow the feed track read tau through Klipper's stops, the window means do not") {
  // The stops' dips (2-5 ms) lie somewhere within their 5 ms sample windows; a model driven by
  // each window's mean feed places them up to half a window wrong, a tenth of tau in the force
  // it predicts after them. The track places them where the planner did.
  const auto track = stop_track(kTopLevels, 0.0031);
  const StopRecord rec = simulate_stops(track);
  const auto y = stop_noise(rec.y, 0.02, 5);
  ident::StepAnalysisOptions o;
  const auto by_track = ident::analyze_steps(rec.t, rec.u, y, o, &track);
  const auto by_means = ident::analyze_steps(rec.t, rec.u, y, o);
  REQUIRE(by_track.steps.size() == 4);
  REQUIRE(by_means.steps.size() == 4);
  CHECK_FALSE(by_track.input_track.empty());
  CHECK(by_means.input_track.empty());
  CHECK(ident::to_json(by_track)["steps_driven_by"] == "feed track");
  CHECK(ident::to_json(by_means)["steps_driven_by"] == "logged input");
  double worst_means = 0;
  for (std::size_t i = 0; i < 4; ++i) {
    REQUIRE(by_track.steps[i].fit);
    REQUIRE(by_means.steps[i].fit);
    const auto& f = *by_track.steps[i].fit;
    const double tau_means = by_means.steps[i].fit->value("tau_s");
    INFO("step " << i << ": tau " << f.value("tau_s") << " +- " << f.param("tau_s").std_error << " (track), "
                 << tau_means << " (window means)");
    CHECK(f.value("tau_s") == Approx(kTrackTau).epsilon(0.01));
    CHECK(std::abs(f.value("tau_s") - kTrackTau) < 3 * f.param("tau_s").std_error);
    CHECK(f.value("theta_s") == Approx(kTrackTheta).margin(3e-4));
    CHECK(f.value("K") == Approx(kTrackK).epsilon(0.005));
    worst_means = std::max(worst_means, std::abs(tau_means / kTrackTau - 1));
  }
  CHECK(worst_means > 0.02);  // what the track repairs
  REQUIRE(by_track.pooled);
  CHECK(by_track.pooled->value("tau_s") == Approx(kTrackTau).epsilon(0.005));
}

TEST_CASE("the step model that follows a feed track is at its least-squares optimum and matches the ideal step") {
  const auto track = stop_track(kTopLevels, 0.0017);
  const StopRecord rec = simulate_stops(track);
  const auto y = stop_noise(rec.y, 0.02, 9);
  fitting::StepRecord r;
  for (std::size_t i = 0; i < rec.t.size(); ++i)
    if (rec.t[i] > 0.5 && rec.t[i] < 1.99) {
      r.t.push_back(rec.t[i]);
      r.y.push_back(y[i]);
    }
  r.t_step = 1.0017 + (kTopLevels[1] + kTopLevels[2]) / (2 * kTrackAccel);  // the stop's middle
  r.du = kTopLevels[2] - kTopLevels[1];
  fitting::set_input_track(r, track.t, track.u);
  CHECK(r.input_t.front() == Approx(r.t.front() - 0.5 / kTrackRate));
  CHECK(r.input_t.back() == r.t.back());
  const auto f = fitting::fit_step(r, fitting::StepModel::fopdt);
  // Ceres from the fit, on the model's values alone (its own derivatives by differences), finds
  // no lower cost: the exact derivatives the fit used lead where the cost is least.
  fitting::LsqProblem prob;
  prob.params = {{"K", "1", f.value("K")},
                 {"tau_s", "s", f.value("tau_s"), 1e-9, 1e3},
                 {"theta_s", "s", f.value("theta_s"), 0.0, 1e3},
                 {"y0", "1", f.value("y0")}};
  prob.num_residuals = static_cast<int>(r.t.size());
  prob.residuals = [&r](const double* p, double* res) {
    const auto m = fitting::step_model_output(r, p[0], p[1], p[2], p[3]);
    for (std::size_t i = 0; i < m.size(); ++i) res[i] = m[i] - r.y[i];
    return true;
  };
  fitting::LsqOptions lo;
  lo.compute_covariance = false;
  const auto ceres = fitting::solve_least_squares("fopdt on the track", prob, lo);
  CHECK(ceres.diagnostics.rss >= f.diagnostics.rss * (1 - 1e-9));
  // A track that is an ideal step gives the ideal step's model at every sample.
  fitting::StepRecord ideal = r;
  ideal.input_t.clear();
  ideal.input_u.clear();
  fitting::StepRecord jump = r;
  const std::vector<double> jt{0.0, r.t_step, r.t_step, 3.0},
      ju{kTopLevels[1], kTopLevels[1], kTopLevels[2], kTopLevels[2]};
  fitting::set_input_track(jump, jt, ju);
  const auto mi = fitting::step_model_output(ideal, kTrackK, kTrackTau, kTrackTheta, kTrackY0);
  const auto mj = fitting::step_model_output(jump, kTrackK, kTrackTau, kTrackTheta, kTrackY0);
  for (std::size_t i = 0; i < mi.size(); ++i) CHECK(mj[i] == Approx(mi[i]).margin(1e-9));
  CHECK_THROWS_AS(fitting::set_input_track(jump, std::vector<double>{1, 0}, std::vector<double>{1, 1}), InputError);
}

TEST_CASE("Monte-Carlo: following the feed track, tau's 95 % interval covers the truth in 90-99 % of 200 draws",
          "[repeats]") {
  // The step down from the top level, whose stop is the largest, at its noise: the interval is
  // the fit's own, with nothing of the stop left in the residuals.
  const auto track = stop_track(kTopLevels, 0.0042);
  const StopRecord rec = simulate_stops(track);
  int covered = 0, n = 0;
  for (unsigned seed = 2000; seed < 2200; ++seed) {
    const auto y = stop_noise(rec.y, 0.02, seed);
    fitting::StepRecord r;
    for (std::size_t i = 0; i < rec.t.size(); ++i)
      if (rec.t[i] > 1.5 && rec.t[i] < 2.99) {
        r.t.push_back(rec.t[i]);
        r.y.push_back(y[i]);
      }
    r.t_step = 2.0042 + (kTopLevels[2] + kTopLevels[3]) / (2 * kTrackAccel);
    r.du = kTopLevels[3] - kTopLevels[2];
    fitting::set_input_track(r, track.t, track.u);
    const auto fit = fitting::fit_step(r, fitting::StepModel::fopdt);
    const auto& p = fit.param("tau_s");
    ++n;
    if (p.ci95_lo <= kTrackTau && kTrackTau <= p.ci95_hi) ++covered;
  }
  const double coverage = static_cast<double>(covered) / n;
  INFO("coverage " << coverage << " over " << n << " draws");
  CHECK(n == 200);
  CHECK(coverage >= 0.90);
  CHECK(coverage <= 0.99);
}
