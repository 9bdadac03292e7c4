#include "tunekit/design/thermal_control.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::design {
namespace {

bool positive(double v) { return std::isfinite(v) && v > 0; }

/// The loss to the ambient at fan duty f, W/K (the model's linear interpolation).
double ambient_loss_w_per_k(const ident::ThermalModel& m, double fan_duty) {
  return m.ambient_transfer_w_per_k + fan_duty * (m.fan_transfer_w_per_k - m.ambient_transfer_w_per_k);
}

void require_model(const ident::ThermalModel& m) {
  if (!positive(m.heater_power_w) || !positive(m.block_heat_capacity_j_per_k) ||
      !positive(m.sensor_responsiveness_per_s) || !positive(m.ambient_transfer_w_per_k))
    throw InputError(fmt::format(
        "the thermal model needs a positive heater power P, block heat capacity C, sensor responsiveness R and "
        "ambient transfer A (P {} W, C {} J/K, R {} 1/s, A {} W/K)",
        m.heater_power_w, m.block_heat_capacity_j_per_k, m.sensor_responsiveness_per_s, m.ambient_transfer_w_per_k));
  if (!std::isfinite(m.fan_transfer_w_per_k) || m.fan_transfer_w_per_k < 0)
    throw InputError(
        fmt::format("the thermal model's fan transfer F must be >= 0 W/K, not {}", m.fan_transfer_w_per_k));
}

/// The loop L(jw) = G(jw) C(jw): the model's two lags and delay under the parallel PID.
std::complex<double> loop_at(const ThermalPid& p, double w) {
  using C = std::complex<double>;
  const C s(0.0, w);
  const C plant =
      p.process_gain_k * std::exp(-p.loop_delay_s * s) / ((p.block_time_s * s + 1.0) * (p.sensor_time_s * s + 1.0));
  return plant * (p.kp_per_k + p.ki_per_k_s / s + p.kd_s_per_k * s);
}

/// Gain margin, phase margin and Ms of the loop, on a logarithmic frequency grid fine enough for
/// the delay's phase (2000 points per decade from 1e-6 to 1e3 rad/s).
void fill_margins(ThermalPid& p) {
  constexpr int kPerDecade = 2000;
  constexpr double kLogFirst = -6.0, kLogLast = 3.0;
  const int n = static_cast<int>((kLogLast - kLogFirst) * kPerDecade);
  double ms = 0.0, gm = INFINITY, pm = INFINITY;
  std::complex<double> prev{};
  for (int i = 0; i <= n; ++i) {
    const double w = std::pow(10.0, kLogFirst + static_cast<double>(i) / kPerDecade);
    const std::complex<double> l = loop_at(p, w);
    ms = std::max(ms, 1.0 / std::abs(1.0 + l));
    if (i > 0) {
      // Phase crossing -180 degrees: the imaginary part changes sign while the real part is negative.
      if (prev.imag() * l.imag() <= 0 && l.real() < 0 && prev.real() < 0) gm = std::min(gm, 1.0 / std::abs(l));
      if ((std::abs(prev) - 1.0) * (std::abs(l) - 1.0) <= 0) {
        double ph = std::arg(l) * 180.0 / std::numbers::pi;
        pm = std::min(pm, 180.0 + (ph > 0 ? ph - 360.0 : ph));
      }
    }
    prev = l;
  }
  p.gain_margin = gm;
  p.phase_margin_deg = pm;
  p.max_sensitivity = ms;
}

}  // namespace

ThermalPid design_thermal_pid(const ident::ThermalModel& m, const ThermalPidOptions& o) {
  require_model(m);
  if (!(o.fan_duty >= 0 && o.fan_duty <= 1))
    throw InputError(fmt::format("the design's fan duty must be within 0 to 1, not {}", o.fan_duty));
  if (!positive(o.loop_delay_s))
    throw InputError(fmt::format("the loop delay must be above 0 s, not {}", o.loop_delay_s));
  const double loss = ambient_loss_w_per_k(m, o.fan_duty);
  if (!positive(loss)) throw InputError(fmt::format("the ambient loss at fan duty {} is not positive", o.fan_duty));
  ThermalPid p;
  p.process_gain_k = m.heater_power_w / loss;
  p.block_time_s = m.block_heat_capacity_j_per_k / loss;
  p.sensor_time_s = 1.0 / m.sensor_responsiveness_per_s;
  p.loop_delay_s = o.loop_delay_s;
  p.closed_loop_time_s = o.closed_loop_time_s > 0 ? o.closed_loop_time_s : p.sensor_time_s;
  // SIMC in series form: the sensor's lag is cancelled by the derivative (Skogestad 2003, eq. for
  // second-order processes with tau2 > theta); the integral time is capped at 4 (tau_c + theta).
  const double tc = p.closed_loop_time_s + p.loop_delay_s;
  const double kc = p.block_time_s / (p.process_gain_k * tc);
  const double ti = std::min(p.block_time_s, 4.0 * tc);
  const double td = p.sensor_time_s;
  // Series (1 + 1/(ti s))(1 + td s) to parallel kp + ki/s + kd s.
  p.kp_per_k = kc * (1.0 + td / ti);
  p.ki_per_k_s = kc / ti;
  p.kd_s_per_k = kc * td;
  fill_margins(p);
  p.rule = fmt::format(
      "SIMC (Skogestad 2003) for a second-order process with dead time: k = P/A = {:.4g} K, tau1 = C/A = {:.4g} s, "
      "tau2 = 1/R = {:.4g} s, loop delay {:.3g} s, closed-loop time constant {:.4g} s{}",
      p.process_gain_k, p.block_time_s, p.sensor_time_s, p.loop_delay_s, p.closed_loop_time_s,
      o.closed_loop_time_s > 0 ? "" : " (the sensor's lag)");
  return p;
}

KlipperPidGains klipper_pid_gains(const ThermalPid& pid) {
  return {pid.kp_per_k * kKlipperPidParamBase, pid.ki_per_k_s * kKlipperPidParamBase,
          pid.kd_s_per_k * kKlipperPidParamBase};
}

RrfHeaterModel rrf_heater_model(const ident::ThermalModel& m, double exponent, double match_rise_k,
                                double loop_delay_s) {
  require_model(m);
  if (!(exponent >= 1.0 && exponent <= 1.6))
    throw InputError(fmt::format(
        "RepRapFirmware's cooling exponent E must be within 1 to 1.6 (src/Heating/FOPDT.cpp), not {}", exponent));
  if (!positive(match_rise_k))
    throw InputError(
        fmt::format("the temperature rise the cooling rate is matched at must be above 0 K, not {}", match_rise_k));
  if (!std::isfinite(loop_delay_s) || loop_delay_s < 0)
    throw InputError(fmt::format("the loop delay must be >= 0 s, not {}", loop_delay_s));
  const double c = m.block_heat_capacity_j_per_k;
  RrfHeaterModel r;
  r.heating_rate_k_s = m.heater_power_w / c;
  r.cooling_exponent = exponent;
  r.cooling_rate_k_s = (m.ambient_transfer_w_per_k / c) * match_rise_k / std::pow(match_rise_k / 100.0, exponent);
  r.fan_cooling_rate_k_s = 100.0 * (m.fan_transfer_w_per_k - m.ambient_transfer_w_per_k) / c;
  r.dead_time_s = 1.0 / m.sensor_responsiveness_per_s + loop_delay_s;
  return r;
}

}  // namespace tunekit::design
