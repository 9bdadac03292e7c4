// The melt stored at a record's first level, measured from its start-up transient: the area
// between the delayed feed and the outflow, on a store whose tau levels off below 0.2 mm/s (a
// Newtonian plateau no power law of the flow follows).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "tunekit/ident/liquefier_record.hpp"
#include "tunekit/ident/rest_volume.hpp"

using namespace tunekit;

namespace {

constexpr double kTheta = 0.02, kGain = 3.5, kOffset = 0.5, kNoise = 0.01;

double true_tau(double x) { return 0.1 * std::pow(std::max(x, 0.2) / 0.2, -0.5); }

/// integral of true_tau over 0..u.
double true_volume(double u) {
  const double plateau = 0.1 * std::min(u, 0.2);
  return u <= 0.2 ? plateau : plateau + 0.1 * std::sqrt(0.2) * 2 * (std::sqrt(u) - std::sqrt(0.2));
}

struct Record {
  std::vector<double> t, y;
};

/// dx/dt = (u(t - theta) - x) / tau(x), y = g x + c, sampled at 200 Hz with noise; the track's
/// feed is linear between its breakpoints.
Record simulate(const ident::FeedTrack& track, double x0, double duration, unsigned seed) {
  auto feed = [&](double t) {
    if (t <= track.t.front()) return track.u.front();
    for (std::size_t i = 1; i < track.t.size(); ++i)
      if (t < track.t[i]) {
        const double h = track.t[i] - track.t[i - 1];
        return h > 0 ? track.u[i - 1] + (track.u[i] - track.u[i - 1]) * (t - track.t[i - 1]) / h : track.u[i];
      }
    return track.u.back();
  };
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, kNoise);
  Record r;
  double x = x0, t = 0;
  const double dt = 1e-5;
  for (int k = 1; k * 0.005 <= duration; ++k) {
    for (; t < k * 0.005 - 0.5 * dt; t += dt) x += dt * (feed(t + 0.5 * dt - kTheta) - x) / true_tau(x);
    r.t.push_back(k * 0.005);
    r.y.push_back(kGain * x + kOffset + noise(rng));
  }
  return r;
}

/// The whole-record model as its fit would report it: a power law through the data's flows, the
/// dead time, the sensor's gain and offset, the residuals' standard deviation.
ident::WholeRecordModel model(const ident::FeedTrack& track, fitting::LiquefierSensor sensor) {
  ident::WholeRecordModel m;
  m.model.sensor = sensor;
  m.model.reference_input = 1.0;
  m.model.variance_factor = 1.0;
  auto& f = m.model.fit;
  for (auto [name, v] : std::vector<std::pair<std::string, double>>{
           {"tau_ref_s", true_tau(1.0)}, {"b", -0.5}, {"theta_s", kTheta}, {"g", kGain}, {"c", kOffset}, {"V0", 0}}) {
    fitting::Param p;
    p.name = name;
    p.value = v;
    f.params.push_back(p);
  }
  fitting::Param a;
  a.name = "a";
  a.value = true_tau(1.0);
  f.derived = {a};
  f.diagnostics.rms = kNoise;
  m.input_track = track;
  return m;
}

const ident::FeedTrack kTrack{{0.0, 0.01, 0.01, 3.0, 3.0, 6.0}, {0.0, 0.0, 1.0, 1.0, 2.0, 2.0}};

}  // namespace

TEST_CASE("the start-up transient's area is the volume stored at the first level, plateau included") {
  const Record r = simulate(kTrack, 0.0, 6.0, 7);
  const auto m = model(kTrack, fitting::LiquefierSensor::flow);
  std::string why;
  const auto v = ident::measure_rest_volume(r.t, r.y, m, &why);
  INFO(why);
  REQUIRE(v);
  const double truth = true_volume(1.0);  // 0.0694 mm; the power law to zero flow says 0.0894
  INFO("measured " << v->value << " +- " << v->std_error << ", truth " << truth);
  CHECK(v->input == 1.0);
  CHECK(v->ci95_lo <= truth);
  CHECK(v->ci95_hi >= truth);
  // The noise summed over the window: sd * dt * sqrt(n) / g; no parameter covariance given.
  CHECK(v->std_error == Approx(kNoise * 0.005 * std::sqrt(static_cast<double>(v->samples)) / kGain).epsilon(0.05));
  CHECK(std::abs(v->value - truth) < 0.02 * truth);
  // The window ends once the model's store has settled at the level, well before the next change.
  CHECK(v->window_end_s < 3.0);

  // The fit's uncertainty of the offset widens it by the window's length over g.
  auto mc = m;
  mc.model.fit.covariance.assign(36, 0.0);
  mc.model.fit.covariance[4 * 6 + 4] = 0.001 * 0.001;
  const auto vc = ident::measure_rest_volume(r.t, r.y, mc);
  REQUIRE(vc);
  const double window = vc->window_end_s - vc->window_begin_s;
  CHECK(vc->std_error == Approx(std::hypot(v->std_error, 0.001 * window / kGain)).epsilon(1e-9));
}

TEST_CASE("the start-up transient is not measured where it cannot be, and says why") {
  const Record r = simulate(kTrack, 0.0, 6.0, 9);
  std::string why;
  CHECK_FALSE(ident::measure_rest_volume(r.t, r.y, model(kTrack, fitting::LiquefierSensor::pressure), &why));
  CHECK(why.find("pressure sensor") != std::string::npos);

  auto no_track = model(kTrack, fitting::LiquefierSensor::flow);
  no_track.input_track = {};
  CHECK_FALSE(ident::measure_rest_volume(r.t, r.y, no_track, &why));
  CHECK(why.find("feed track") != std::string::npos);

  // A store already full at the start: not at rest.
  const Record full = simulate(kTrack, 1.0, 6.0, 11);
  CHECK_FALSE(ident::measure_rest_volume(full.t, full.y, model(kTrack, fitting::LiquefierSensor::flow), &why));
  CHECK(why.find("rest") != std::string::npos);

  // A first level of 0.2 s: the store has not settled before the next change arrives.
  const ident::FeedTrack short_level{{0.0, 0.01, 0.01, 0.2, 0.2, 6.0}, {0.0, 0.0, 1.0, 1.0, 2.0, 2.0}};
  const Record s = simulate(short_level, 0.0, 6.0, 13);
  CHECK_FALSE(ident::measure_rest_volume(s.t, s.y, model(short_level, fitting::LiquefierSensor::flow), &why));
  CHECK(why.find("too short") != std::string::npos);
}
