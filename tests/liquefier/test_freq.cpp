// Frequency response: sine dwell on Holtrup 2019 appendix D and on synthetic data, exact ZOH
// simulation, broadband H1 through a known second-order system, transfer-function fits.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <sstream>

#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/fitting/transfer_function.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/ident/excitation.hpp"
#include "tunekit/ident/sine_dwell.hpp"
#include "tunekit/ident/spectrum.hpp"

using namespace tunekit;
using tunekit::test::dataset;
using tunekit::test::run_cli;
using tunekit::test::write_scratch;

namespace {
constexpr double kPi = std::numbers::pi;

struct Exp {
  int id;
  double freq_hz;
};
std::vector<Exp> design() {
  const auto d = formats::read_csv(dataset("liquefier/appendix_d/design.csv"));
  std::vector<Exp> v;
  for (std::size_t i = 0; i < d.rows; ++i)
    v.push_back({static_cast<int>(d.column("experiment").values[i]), d.column("freq_hz").values[i]});
  return v;
}
std::string exp_path(int id) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "liquefier/appendix_d/exp_%02d.csv", id);
  return dataset(buf);
}
}  // namespace

TEST_CASE("appendix D: every experiment's sine-dwell gain and phase lag, and experiment 7 matches the thesis") {
  const auto exps = design();
  REQUIRE(exps.size() == 12);
  for (const auto& e : exps) {
    formats::CsvOptions o;
    o.time_column = "time";
    const auto tab = formats::read_csv(exp_path(e.id), o);
    const auto sd = ident::sine_dwell(tab.column("time").values, tab.column("width").values, e.freq_hz,
                                      tab.column("setpoint_width").values, "mm", "mm");
    INFO("experiment " << e.id << " at " << e.freq_hz << " Hz: gain " << sd.gain.value << " +- " << sd.gain.std_error
                       << ", phase lag " << sd.phase_lag_deg.value << " +- " << sd.phase_lag_deg.std_error);
    REQUIRE(sd.input);
    CHECK(std::isfinite(sd.gain.value));
    CHECK(sd.gain.value > 0);
    CHECK(std::isfinite(sd.gain.std_error));
    CHECK(std::isfinite(sd.phase_lag_deg.value));
    CHECK(std::abs(sd.phase_lag_deg.value) <= 180);
    CHECK(sd.gain.ci95_lo < sd.gain.value);
    // The set-point widths are exact sines around 0.66 mm (eq. 4.3).
    CHECK(sd.input->value("offset") == Approx(0.66).margin(0.01));
    if (e.id == 7) {
      CHECK(sd.input->value("amplitude") == Approx(0.785).margin(0.005));
      CHECK(sd.input->value("offset") == Approx(0.661).margin(0.005));
      CHECK(sd.output.value("amplitude") == Approx(0.226).margin(0.005));
      CHECK(sd.output.value("offset") == Approx(0.706).margin(0.005));
    }
  }
}

TEST_CASE("tunekit freq: the line-width call works on appendix D experiment 7") {
  const auto r = run_cli({"freq", exp_path(7), "--time", "time", "--output", "width", "--input", "setpoint_width",
                          "--freq-hz", "0.05305165", "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto j = nlohmann::json::parse(r.out)["results"]["sine_dwell"];
  CHECK(j["input"]["amplitude"]["value"].get<double>() == Approx(0.785).margin(0.005));
  CHECK(j["output"]["offset"]["value"].get<double>() == Approx(0.706).margin(0.005));
  CHECK(j["output"]["amplitude"]["ci95"].size() == 2);
  CHECK(j["gain"]["value"].get<double>() == Approx(0.226 / 0.785).epsilon(0.03));
  CHECK(j.contains("phase_lag_deg"));
  CHECK(j["freq_hz"] == 0.05305165);
  const auto text = run_cli({"freq", exp_path(7), "--time", "time", "--output", "width", "--input", "setpoint_width",
                             "--freq-hz", "0.05305165"});
  CHECK(text.code == 0);
  CHECK(text.out.find("phase lag") != std::string::npos);
}

TEST_CASE("sine dwell on non-uniform samples recovers amplitude, phase and lag within the intervals") {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> jitter(0.0, 0.08);
  std::normal_distribution<double> noise(0, 0.02);
  const double f = 0.7, lag = 35.0;
  std::vector<double> t, u, y;
  double ti = 0;
  for (int i = 0; i < 300; ++i) {
    ti += 0.02 + jitter(rng);
    t.push_back(ti);
    u.push_back(1.0 + 0.5 * std::sin(2 * kPi * f * ti + 0.3) + noise(rng));
    y.push_back(2.0 + 0.8 * std::sin(2 * kPi * f * ti + 0.3 - lag * kPi / 180) + noise(rng));
  }
  const auto sd = ident::sine_dwell(t, y, f, u);
  // Within four standard errors (a single draw may fall outside its 95 % interval).
  CHECK(std::abs(sd.output.value("amplitude") - 0.8) < 4 * sd.output.param("amplitude").std_error);
  CHECK(std::abs(sd.gain.value - 1.6) < 4 * sd.gain.std_error);
  CHECK(sd.gain.ci95_lo < sd.gain.value);
  CHECK(sd.phase_lag_deg.value == Approx(lag).margin(3));
  CHECK(sd.phase_lag_deg.ci95_lo <= lag);
  CHECK(sd.phase_lag_deg.ci95_hi >= lag);
  CHECK(ident::wrap_deg(190) == Approx(-170));
  CHECK(ident::wrap_deg(-180) == Approx(180));
  // Bad input.
  CHECK_THROWS_AS(ident::fit_sine(std::vector<double>{0, 1, 2}, std::vector<double>{1, 2, 1}, 1.0), InputError);
  CHECK_THROWS_AS(ident::fit_sine(std::vector<double>{0, 1, 2, 3, 4}, std::vector<double>{1, 1, 1, 1, 1}, 0.2),
                  InputError);
  CHECK_THROWS_AS(ident::fit_sine(std::vector<double>{0, 1, 1, 3, 4}, std::vector<double>{1, 2, 1, 3, 1}, 0.2),
                  InputError);
}

TEST_CASE("FOH simulation is exact for a ramp, including fractional delays") {
  // G = 1/(tau s + 1) e^{-theta s}, u = t from t = 0: y = s - tau (1 - e^{-s/tau}), s = t - theta.
  const double tau = 0.3, dt = 0.01;
  for (double theta : {0.0, 0.02, 0.037}) {
    fitting::TransferFunction g{{1.0}, {tau, 1.0}, theta};
    std::vector<double> u(200);
    for (std::size_t i = 0; i < u.size(); ++i) u[i] = static_cast<double>(i) * dt;
    const auto y = g.simulate_foh(u, dt);
    for (std::size_t i = 0; i < u.size(); ++i) {
      const double s = static_cast<double>(i) * dt - theta;
      const double exact = s > 0 ? s - tau * (1 - std::exp(-s / tau)) : 0.0;
      INFO("theta " << theta << " sample " << i);
      CHECK(y[i] == Approx(exact).margin(1e-12));
    }
  }
  // Second order: a sampled sine through it, against the ZOH's half-sample lag.
  fitting::TransferFunction g2{
      {1.0}, {1.0 / (4 * std::numbers::pi * std::numbers::pi * 100), 2 * 0.2 / (2 * std::numbers::pi * 10), 1.0}, 0.0};
  std::vector<double> u(2000);
  for (std::size_t i = 0; i < u.size(); ++i) u[i] = std::sin(2 * std::numbers::pi * 3 * static_cast<double>(i) * 0.004);
  const auto yf = g2.simulate_foh(u, 0.004), yz = g2.simulate_zoh(u, 0.004);
  const auto h = g2.response(3);
  double ef = 0, ez = 0;
  for (std::size_t i = 1000; i < u.size(); ++i) {
    const double t = static_cast<double>(i) * 0.004;
    const double exact = std::abs(h) * std::sin(2 * std::numbers::pi * 3 * t + std::arg(h));
    ef = std::max(ef, std::abs(yf[i] - exact));
    ez = std::max(ez, std::abs(yz[i] - exact));
  }
  CHECK(ef < 2e-3);
  CHECK(ez > 5 * ef);
}

TEST_CASE("ZOH simulation is exact for steps, including fractional delays") {
  fitting::TransferFunction fo{{2.0}, {0.5, 1.0}, 0.0125};  // 2 e^{-0.0125 s} / (0.5 s + 1)
  const double dt = 0.01;
  std::vector<double> u(300, 1.0);
  const auto y = fo.simulate_zoh(u, dt);
  for (std::size_t k = 0; k < y.size(); ++k) {
    const double tk = k * dt;
    const double exact = tk > 0.0125 ? 2.0 * (1 - std::exp(-(tk - 0.0125) / 0.5)) : 0.0;
    REQUIRE(y[k] == Approx(exact).margin(1e-10));
  }
  // Second order, underdamped.
  const double wn = 2 * kPi * 3.0, z = 0.3;
  fitting::TransferFunction so{{1.0}, {1 / (wn * wn), 2 * z / wn, 1.0}, 0.0};
  const auto y2 = so.simulate_zoh(u, dt);
  const double wd = wn * std::sqrt(1 - z * z);
  for (std::size_t k = 0; k < y2.size(); k += 7) {
    const double tk = k * dt;
    const double exact =
        1 - std::exp(-z * wn * tk) * (std::cos(wd * tk) + z / std::sqrt(1 - z * z) * std::sin(wd * tk));
    REQUIRE(y2[k] == Approx(exact).margin(1e-9));
  }
  CHECK(std::abs(so.response(3.0)) == Approx(1 / (2 * z)).epsilon(1e-12));
  CHECK(std::arg(so.response(3.0)) == Approx(-kPi / 2).margin(1e-12));
  CHECK(fo.dc_gain() == 2.0);
  CHECK_THROWS_AS(fitting::parse_tf_structure("4,0"), InputError);
  CHECK_THROWS_AS(fitting::parse_tf_structure("1,2"), InputError);
  CHECK(fitting::parse_tf_structure("3,2").zeros == 2);
}

namespace {
// A linear chirp through K wn^2 / (s^2 + 2 zeta wn s + wn^2), integrated by RK4 (continuous input).
void chirp_through_second_order(double fs, double T, double f0, double f1, double K, double fn, double zeta,
                                double sigma, std::vector<double>& u, std::vector<double>& y) {
  const double wn = 2 * kPi * fn;
  auto uf = [&](double t) { return std::sin(2 * kPi * (f0 * t + 0.5 * (f1 - f0) / T * t * t)); };
  auto d = [&](double t, double x0, double x1, double& d0, double& d1) {
    d0 = x1;
    d1 = K * wn * wn * uf(t) - 2 * zeta * wn * x1 - wn * wn * x0;
  };
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0, sigma);
  double x0 = 0, x1 = 0;
  const int sub = 10;
  const double h = 1 / (fs * sub);
  const int n = static_cast<int>(T * fs);
  for (int i = 0; i < n; ++i) {
    const double t = i / fs;
    u.push_back(uf(t));
    y.push_back(x0 + noise(rng));
    for (int s = 0; s < sub; ++s) {
      const double tt = t + s * h;
      double a0, a1, b0, b1, c0, c1, e0, e1;
      d(tt, x0, x1, a0, a1);
      d(tt + h / 2, x0 + h / 2 * a0, x1 + h / 2 * a1, b0, b1);
      d(tt + h / 2, x0 + h / 2 * b0, x1 + h / 2 * b1, c0, c1);
      d(tt + h, x0 + h * c0, x1 + h * c1, e0, e1);
      x0 += h / 6 * (a0 + 2 * b0 + 2 * c0 + e0);
      x1 += h / 6 * (a1 + 2 * b1 + 2 * c1 + e1);
    }
  }
}
}  // namespace

TEST_CASE("broadband: a chirp through a known second-order system, H1 within 1 dB / 5 deg, TF fit fn within 2 %") {
  const double fs = 500, K = 2, fn = 12, zeta = 0.2;
  std::vector<double> u, y;
  chirp_through_second_order(fs, 40, 0.2, 60, K, fn, zeta, 0.01, u, y);
  ident::WelchOptions wo;
  wo.segment_length = 2048;
  const auto fr = ident::h1_estimate(u, y, fs, wo);
  fitting::TransferFunction truth{{K}, {1 / std::pow(2 * kPi * fn, 2), 2 * zeta / (2 * kPi * fn), 1.0}, 0};
  int checked = 0;
  std::vector<double> ff, sg;
  std::vector<std::complex<double>> hh;
  for (std::size_t i = 1; i < fr.freq_hz.size(); ++i) {
    if (fr.coherence[i] <= 0.9) continue;
    const auto ht = truth.response(fr.freq_hz[i]);
    const double db = 20 * std::log10(std::abs(fr.h[i]) / std::abs(ht));
    const double dph = std::arg(fr.h[i] / ht) * 180 / kPi;
    INFO("f = " << fr.freq_hz[i] << " Hz, coherence " << fr.coherence[i] << ": " << db << " dB, " << dph << " deg");
    CHECK(std::abs(db) < 1.0);
    CHECK(std::abs(dph) < 5.0);
    ++checked;
    ff.push_back(fr.freq_hz[i]);
    hh.push_back(fr.h[i]);
    sg.push_back(fitting::h1_sigma(fr.h[i], fr.coherence[i], fr.segments));
  }
  CHECK(checked > 100);
  const auto fit = fitting::fit_tf_frf(ff, hh, sg, fitting::parse_tf_structure("2,0"));
  INFO("fn " << fit.value("fn_hz") << " zeta " << fit.value("zeta") << " K " << fit.value("K"));
  CHECK(fit.value("fn_hz") == Approx(fn).epsilon(0.02));
  CHECK(fit.value("zeta") == Approx(zeta).epsilon(0.1));
  CHECK(fit.value("K") == Approx(K).epsilon(0.05));
  CHECK(fit.param("fn_hz").std_error > 0);
}

// Start values for an output-error fit: each true parameter times factor(its index).
template <class Factor>
fitting::FitResult start_from(const fitting::TfStructure& st, const std::vector<double>& truth, Factor factor) {
  fitting::FitResult start;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    fitting::Param p;
    p.name = fitting::tf_param_names(st)[i];
    p.value = truth[i] * factor(i);
    start.params.push_back(p);
  }
  return start;
}

TEST_CASE("output-error fit of a transfer function with dead time to a random-step record") {
  const double dt = 0.01;
  fitting::TfStructure st{2, 1, true};
  const std::vector<double> truth{1.5, 2.0, 0.4, 0.05, 0.073};  // K, fn_hz, zeta, tz_s, theta_s
  const auto tf = fitting::tf_from_params(st, truth.data());
  std::mt19937 rng(9);
  std::uniform_int_distribution<int> coin(0, 1);
  std::normal_distribution<double> noise(0, 0.01);
  std::vector<double> u;
  double level = 0;
  for (int i = 0; i < 3000; ++i) {
    if (i >= 100 && i % 40 == 0) level = coin(rng) ? 1.0 : -1.0;  // at rest (u = 0) for 1 s first
    u.push_back(level);
  }
  auto y = tf.simulate_zoh(u, dt);
  for (auto& v : y) v += 0.3 + noise(rng);
  const fitting::FitResult start = start_from(st, truth, [](std::size_t i) { return i == 4 ? 0.6 : 1.15; });
  // The record was made by holding each sample from its time stamp: said so.
  const auto fit = fitting::fit_tf_output_error(u, y, dt, st, start, "1", {}, fitting::InterSample::hold);
  const auto names = fitting::tf_param_names(st);
  for (std::size_t i = 0; i < names.size(); ++i) {
    const auto& p = fit.param(names[i]);
    INFO(names[i] << " = " << p.value << " [" << p.ci95_lo << ", " << p.ci95_hi << "] truth " << truth[i]);
    CHECK(p.value == Approx(truth[i]).epsilon(0.05).margin(0.005));
  }
  CHECK(fit.diagnostics.rms == Approx(0.01).epsilon(0.2));
}

TEST_CASE("output-error fit of a staircase whose changes fall between samples: the dead time read in full") {
  // A logger samples a feed whose steps come at any moment of a sample interval, and records each
  // sample as the feed's mean over the interval centred on its time stamp (what tunekit's
  // recorder writes). Read as held from each time stamp, every change would come half a sample
  // late and the dead time read short by half a sample; read as centred (the default for a
  // staircase), it is found to within a tenth of a sample.
  const double dt = 0.01;
  const int fine = 40;  // plant simulated on a grid 40 times finer than the samples
  fitting::TfStructure st{1, 0, true};
  const std::vector<double> truth{2.0, 0.05, 0.0537};  // K, tau_s, theta_s (not a whole number of samples)
  const auto tf = fitting::tf_from_params(st, truth.data());
  std::mt19937 rng(17);
  std::uniform_int_distribution<int> coin(0, 1), phase(0, fine - 1);
  std::normal_distribution<double> noise(0, 0.002);
  std::vector<double> u_fine;
  double level = 0;
  for (int i = 0; i < 2000; ++i) {
    const int switch_at = i >= 50 && i % 15 == 0 ? phase(rng) : fine;
    const double next = coin(rng) ? 1.0 : -1.0;
    for (int j = 0; j < fine; ++j) {
      if (j == switch_at) level = next;
      u_fine.push_back(level);
    }
  }
  const auto y_fine = tf.simulate_zoh(u_fine, dt / fine);
  std::vector<double> u, y;
  for (std::size_t k = 1; (k + 1) * fine < u_fine.size(); ++k) {
    double sum = 0;  // mean over [t_k - dt/2, t_k + dt/2)
    for (std::size_t j = k * fine - fine / 2; j < k * fine + fine / 2; ++j) sum += u_fine[j];
    u.push_back(sum / fine);
    y.push_back(y_fine[k * fine] + noise(rng));
  }
  const fitting::FitResult start = start_from(st, truth, [](std::size_t) { return 1.2; });
  const auto centred = fitting::fit_tf_output_error(u, y, dt, st, start);
  const auto held = fitting::fit_tf_output_error(u, y, dt, st, start, "1", {}, fitting::InterSample::hold);
  INFO("centred theta " << centred.value("theta_s") << ", held " << held.value("theta_s") << ", truth " << truth[2]);
  CHECK(std::abs(centred.value("theta_s") - truth[2]) < 0.1 * dt);
  CHECK(std::abs(centred.value("tau_s") - truth[1]) < 0.02 * truth[1]);
  CHECK(held.value("theta_s") - truth[2] == Approx(-0.5 * dt).margin(0.15 * dt));
}

TEST_CASE("output-error fit with coloured output noise: the intervals widened for it cover tau") {
  // A first-order lag with dead time driven by random steps, its output noise AR(1) with
  // phi = 0.9: s^2 (J^T J)^-1 alone takes the noise for ten times as many independent samples
  // as it holds, and its 95 % interval covers tau far less often than 95 %.
  const double dt = 0.01;
  fitting::TfStructure st{1, 0, true};
  const std::vector<double> truth{2.0, 0.3, 0.05};  // K, tau_s, theta_s
  const auto tf = fitting::tf_from_params(st, truth.data());
  int covered = 0, widened = 0;
  const int draws = 30;
  for (int d = 0; d < draws; ++d) {
    std::mt19937 rng(100 + d);
    std::uniform_int_distribution<int> coin(0, 1);
    std::normal_distribution<double> e(0, 0.01);
    std::vector<double> u;
    double level = 0;
    for (int i = 0; i < 3000; ++i) {
      if (i >= 100 && i % 60 == 0) level = coin(rng) ? 1.0 : -1.0;
      u.push_back(level);
    }
    auto y = tf.simulate_zoh(u, dt);
    double ar = 0;
    for (auto& v : y) {
      ar = 0.9 * ar + e(rng);
      v += ar;
    }
    const fitting::FitResult start = start_from(st, truth, [](std::size_t) { return 1.1; });
    const auto fit = fitting::fit_tf_output_error(u, y, dt, st, start, "1", {}, fitting::InterSample::hold);
    const auto& tau = fit.param("tau_s");
    if (tau.ci95_lo <= truth[1] && truth[1] <= tau.ci95_hi) ++covered;
    if (tau.ci95_method.find("widened for correlated residuals") != std::string::npos) ++widened;
  }
  INFO(covered << " of " << draws << " covered, " << widened << " widened");
  CHECK(widened == draws);
  CHECK(covered >= 26);  // P(X <= 25) = 1.6 % for X ~ Binomial(30, 0.95)
}

TEST_CASE("tunekit freq --mode h1 / oe on the synthetic chirp data set: oe gives fn within 1 % of 12 Hz, covered") {
  auto r = run_cli({"freq", dataset("liquefier/synthetic_chirp.csv"), "--time", "time", "--input", "feed", "--output",
                    "force", "--mode", "h1", "--fit-tf", "2,0", "--fmax", "40", "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  auto j = nlohmann::json::parse(r.out)["results"];
  const auto& bode = j["h1"]["bode"];
  CHECK(bode["freq_hz"].size() == bode["coherence"].size());
  CHECK(bode["phase_deg"].size() == bode["freq_hz"].size());
  CHECK(j["tf_fit"]["params"]["fn_hz"]["value"].get<double>() == Approx(12.0).epsilon(0.02));
  CHECK(j["tf_fit"]["params"]["K"]["value"].get<double>() == Approx(2.0).epsilon(0.05));
  // Unwrapped phase keeps falling past -180 for no fitted model here, but never jumps by 360.
  for (std::size_t i = 1; i < bode["phase_deg"].size(); ++i)
    CHECK(std::abs(bode["phase_deg"][i].get<double>() - bode["phase_deg"][i - 1].get<double>()) < 180);
  r = run_cli({"freq", dataset("liquefier/synthetic_chirp.csv"), "--time", "time", "--input", "feed", "--output",
               "force", "--mode", "oe", "--fit-tf", "2,0", "--fmax", "40", "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  j = nlohmann::json::parse(r.out)["results"];
  // The help's example: the chirp is continuous, so the output-error model takes the input as
  // linear between samples (holding it would add half a sample of delay and move fn by 3 %):
  // fn within 1 % of the data set's 12 Hz, and its 95 % interval holds 12 Hz.
  const auto& fn = j["tf_oe_fit"]["params"]["fn_hz"];
  INFO(fn.dump());
  CHECK(fn["value"].get<double>() == Approx(12.0).epsilon(0.01));
  CHECK(fn["ci95"][0].get<double>() <= 12.0);
  CHECK(12.0 <= fn["ci95"][1].get<double>());
  CHECK(j["tf_oe_fit"]["params"]["zeta"]["value"].get<double>() == Approx(0.2).epsilon(0.02));
  // Errors: no frequency, no input for h1, irregular sampling for h1.
  CHECK(run_cli({"freq", exp_path(7), "--time", "time", "--output", "width"}).code == 2);
  CHECK(run_cli({"freq", exp_path(7), "--time", "time", "--output", "width", "--mode", "h1"}).code == 2);
  std::ostringstream csv;
  csv << "time,u,y\n";
  for (int i = 0; i < 200; ++i)
    csv << i * 0.01 + (i % 2) * 0.004 << "," << std::sin(i * 0.3) << "," << std::cos(i * 0.2) << "\n";
  const auto irregular =
      run_cli({"freq", write_scratch("irregular.csv", csv.str()), "--input", "u", "--output", "y", "--mode", "h1"});
  CHECK(irregular.err.find("uniform sampling") != std::string::npos);
  CHECK(irregular.code == 2);
  CHECK(run_cli({"freq", "--help"}).out.find("Examples:") != std::string::npos);
}

TEST_CASE("a rank-deficient fit prints exactly one error line on the real stderr (exit 1)") {
  // Sampling at exactly twice the dwell frequency: sin and cos of the model are both +-1 times a
  // constant, so amplitude and phase cannot be separated. The covariance fails; the solver
  // library's own logging must not reach stderr before tunekit's one line.
  std::ostringstream csv;
  csv << "time (s),width (mm)\n";
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0, 0.01);
  for (int k = 0; k < 200; ++k) csv << k * 0.1 << ',' << 1 + 0.3 * (k % 2 == 0 ? 1 : -1) + noise(rng) << '\n';
  const auto path = write_scratch("rank_deficient_dwell.csv", csv.str());
  const auto r = tunekit::test::run_exe("freq " + path + " -y width --mode dwell -f 5");
  INFO(r.err);
  CHECK(r.code == 1);
  CHECK(r.err.rfind("tunekit: error: ", 0) == 0);
  CHECK(r.err.find("not identifiable") != std::string::npos);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  CHECK(r.out.empty());
}

TEST_CASE("excitation: a steady hold then a staircase chirp gives the chirp's onset and band") {
  // 200 Hz: 1 s at rest, a ramp to the mean, 3 s steady, then a linear chirp 0.1-2 Hz over 40 s
  // in 50 ms staircase steps, then 1 s steady at the mean.
  const double fs = 200, f0 = 0.1, f1 = 2.0, T = 40, seg = 0.05, settle_end = 4.0;
  std::vector<double> t, u;
  for (int i = 0; i < static_cast<int>((settle_end + T + 1) * fs); ++i) {
    const double ti = i / fs;
    double v = ti < 1 ? 0.0 : std::min(1.0, ti - 1.0) * 2.0;
    if (ti >= settle_end && ti < settle_end + T) {
      const double tk = (std::floor((ti - settle_end) / seg) + 0.5) * seg;
      v = 2.0 + std::sin(2 * kPi * (f0 * tk + 0.5 * (f1 - f0) / T * tk * tk));
    }
    t.push_back(ti);
    u.push_back(v);
  }
  const auto onset = ident::excitation_onset(t, u);
  CHECK(t[onset] == Approx(settle_end - 1 / fs).margin(1e-9));
  CHECK(ident::typical_hold_s(t, ident::input_holds(u)) <= seg + 1e-9);
  ident::WelchOptions wo;
  wo.segment_length = 2048;
  const std::vector<double> chirp(u.begin() + static_cast<std::ptrdiff_t>(onset), u.end());
  const auto band = ident::excited_band(ident::welch_psd(chirp, fs, wo));
  INFO("band " << band.lo_hz << "-" << band.hi_hz << " Hz");
  CHECK(band.hi_hz >= f1);
  CHECK(band.hi_hz <= f1 + 4 * fs / 2048);  // the band's edge, within the window's main lobe
  CHECK(band.lo_hz <= f0 + 2 * fs / 2048);
  // Without a steady hold (a chirp from the first sample), there is no onset.
  const std::vector<double> no_hold(u.begin() + static_cast<std::ptrdiff_t>(onset) + 1, u.end());
  const std::vector<double> t_no_hold(t.begin() + static_cast<std::ptrdiff_t>(onset) + 1, t.end());
  CHECK(ident::excitation_onset(t_no_hold, no_hold) == 0);
}
