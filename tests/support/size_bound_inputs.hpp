#pragma once
// Large generated inputs shared by the row-bound tests and their benchmark (header-only: the
// benchmarks link no test framework).

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <string>

#include "tunekit/ident/delta_kinematics.hpp"
#include "tunekit/sim/delta_probe_sim.hpp"

namespace tunekit::test {

/// A Cross melt with an Arrhenius shift (66.5 kJ/mol) at 380-440 degC, 3 % log-normal noise:
/// `rows` rows of shear rate (1/s), viscosity (Pa.s) and temperature (degC).
inline std::string cross_rheometer_csv(int rows) {
  constexpr double kR = 8.314462618;  // J/(mol K)
  std::mt19937 gen(20190101);
  std::normal_distribution<double> noise(0.0, 0.03);
  std::ostringstream csv;
  csv << "shear_rate (1/s),viscosity (Pa.s),temperature (degC)\n";
  const double temps[] = {380, 400, 420, 440};
  const int per = rows / 4;
  for (int i = 0; i < rows; ++i) {
    const double T = temps[i % 4];
    const double g = std::pow(10.0, 4.0 * (i / 4) / std::max(per - 1, 1));
    const double aT = std::exp(66500.0 / kR * (1 / (T + 273.15) - 1 / (400 + 273.15)));
    const double eta0 = 3000 * aT;
    const double eta = eta0 / (1 + std::pow(eta0 * g / 1e5, 0.7));
    csv << g << "," << eta * std::exp(noise(gen)) << "," << T << "\n";
  }
  return csv.str();
}

/// A PEEK melt on Cross-WLF (Holtrup 2019, Table 2.4: n 0.4266, tau* 124139 Pa, D1 2.89808e16
/// Pa.s, D2 403.15 K, A1 36.041, A2 51.6 K) at five temperatures, 370-450 degC, shear rates
/// 0.1-10^4 1/s, 3 % log-normal noise: `rows` rows of shear rate (1/s), viscosity (Pa.s) and
/// temperature (degC). Over 80 K, 240 K above D2, the WLF shift is nearly an Arrhenius one: D1,
/// D2 and A1 are not separately identifiable (`tunekit rheo --model cross-wlf` warns, and their
/// intervals are profile-likelihood ones).
inline std::string cross_wlf_rheometer_csv(int rows) {
  constexpr double kA1 = 36.041, kA2 = 51.6, kD1 = 2.89808e16, kD2 = 403.15, kN = 0.4266, kTau = 124139;
  std::mt19937 gen(20190405);
  std::normal_distribution<double> noise(0.0, 0.03);
  std::ostringstream csv;
  csv << "shear_rate (1/s),viscosity (Pa.s),temperature (degC)\n";
  const double temps[] = {370, 390, 410, 430, 450};
  const int per = rows / 5;
  for (int i = 0; i < rows; ++i) {
    const double T = temps[i % 5], TK = T + 273.15;
    const double g = std::pow(10.0, -1.0 + 5.0 * (i / 5) / std::max(per - 1, 1));
    const double eta0 = kD1 * std::exp(-kA1 * (TK - kD2) / (kA2 + TK - kD2));
    const double eta = eta0 / (1 + std::pow(eta0 * g / kTau, 1 - kN));
    csv << g << "," << eta * std::exp(noise(gen)) << "," << T << "\n";
  }
  return csv.str();
}

/// Probe points (x, y, z in mm) of a 105 mm radius delta whose real radius is 104.2 mm, endstops
/// and tower angles a little off: `rings` rings of `points_per_ring` points plus the centre.
inline std::string delta_probe_csv(int rings, int points_per_ring) {
  ident::DeltaGeometry nominal;
  nominal.radius_mm = 105.0;
  nominal.rod_mm = {215.0, 215.0, 215.0};
  nominal.homed_height_mm = 250.0;
  auto truth = nominal;
  truth.endstop_mm = {0.35, -0.20, 0.10};
  truth.radius_mm = 104.2;
  truth.angle_deg = {210.4, 329.7, 90.0};
  const auto probes =
      sim::simulate_delta_probes(nominal, truth, sim::delta_probe_pattern(85, rings, points_per_ring), 0.01, 11);
  std::ostringstream csv;
  csv << "x_mm,y_mm,z_mm\n";
  for (const auto& p : probes) csv << p.x_mm << "," << p.y_mm << "," << p.z_mm << "\n";
  return csv.str();
}

}  // namespace tunekit::test
