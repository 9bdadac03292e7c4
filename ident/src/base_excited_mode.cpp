// A base-excited resonant mode, exact over pieces of linear acceleration (base_excited_mode.hpp).
#include "tunekit/ident/base_excited_mode.hpp"

#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::ident {
namespace {
/// |1 - zeta| below this is treated as critical damping (the under- and over-damped forms
/// divide by sqrt|1 - zeta^2|).
constexpr double kCriticalDampingBand = 1e-7;
}  // namespace

BaseExcitedMode::BaseExcitedMode(double freq_hz, double zeta)
    : freq_hz_(freq_hz), zeta_(zeta), w_(2 * std::numbers::pi * freq_hz), c_(2 * zeta * w_), k_(w_ * w_) {
  if (!(freq_hz > 0) || !std::isfinite(freq_hz) || !(zeta > 0) || !std::isfinite(zeta))
    throw InputError(
        fmt::format("a resonant mode needs a frequency > 0 and a damping ratio > 0 (got {} Hz, {})", freq_hz, zeta));
}

ModeState BaseExcitedMode::free_response(const ModeState& e, double h) const {
  const double s = zeta_ * w_;  // decay rate, 1/s
  const double e0 = e.z_mm, d0 = e.v_mm_s;
  if (std::abs(1 - zeta_) < kCriticalDampingBand) {
    const double decay = std::exp(-w_ * h), b = d0 + w_ * e0;
    return {(e0 + b * h) * decay, (d0 - w_ * b * h) * decay};
  }
  if (zeta_ < 1) {
    const double wd = w_ * std::sqrt(1 - zeta_ * zeta_);
    const double decay = std::exp(-s * h), cs = std::cos(wd * h), sn = std::sin(wd * h);
    return {decay * (e0 * cs + (d0 + s * e0) / wd * sn), decay * (d0 * cs - (k_ * e0 + s * d0) / wd * sn)};
  }
  const double q = w_ * std::sqrt(zeta_ * zeta_ - 1), r1 = -s + q, r2 = -s - q;
  const double A = (d0 - r2 * e0) / (r1 - r2), B = (r1 * e0 - d0) / (r1 - r2);
  const double x1 = std::exp(r1 * h), x2 = std::exp(r2 * h);
  return {A * x1 + B * x2, r1 * A * x1 + r2 * B * x2};
}

ModeState BaseExcitedMode::advance(const ModeState& x, double h, double a0, double j) const {
  if (h <= 0) return x;
  // Particular solution of z'' + c z' + k z = -(a0 + j s): z_p = -(a0 + j s)/k + c j/k^2.
  const double zp0 = -a0 / k_ + c_ * j / (k_ * k_), vp = -j / k_;
  const double zp1 = zp0 - j * h / k_;
  const ModeState e = free_response({x.z_mm - zp0, x.v_mm_s - vp}, h);
  return {e.z_mm + zp1, e.v_mm_s + vp};
}

void BaseExcitedMode::free_map(double h, double phi[2][2]) const {
  if (zeta_ < 1 && std::abs(1 - zeta_) >= kCriticalDampingBand) {
    // free_response's under-damped form for (1, 0) and (0, 1).
    const double s = zeta_ * w_, wd = w_ * std::sqrt(1 - zeta_ * zeta_);
    const double decay = std::exp(-s * h), cs = decay * std::cos(wd * h), sn = decay * std::sin(wd * h) / wd;
    phi[0][0] = cs + s * sn;
    phi[0][1] = sn;
    phi[1][0] = -k_ * sn;
    phi[1][1] = cs - s * sn;
    return;
  }
  const ModeState c0 = free_response({1, 0}, h), c1 = free_response({0, 1}, h);
  phi[0][0] = c0.z_mm;
  phi[1][0] = c0.v_mm_s;
  phi[0][1] = c1.z_mm;
  phi[1][1] = c1.v_mm_s;
}

ModeState BaseExcitedMode::advance(const ModeState& x, double h, double a0, double j, const double phi[2][2]) const {
  if (h <= 0) return x;
  // As advance() without phi: the free response of the state less the particular solution.
  const double zp0 = -a0 / k_ + c_ * j / (k_ * k_), vp = -j / k_;
  const double zp1 = zp0 - j * h / k_;
  const double e0 = x.z_mm - zp0, d0 = x.v_mm_s - vp;
  return {phi[0][0] * e0 + phi[0][1] * d0 + zp1, phi[1][0] * e0 + phi[1][1] * d0 + vp};
}

ModeStep BaseExcitedMode::step(double h) const {
  ModeStep s;
  s.h_s = h;
  const ModeState c0 = advance({1, 0}, h, 0, 0), c1 = advance({0, 1}, h, 0, 0);
  s.phi[0][0] = c0.z_mm;
  s.phi[1][0] = c0.v_mm_s;
  s.phi[0][1] = c1.z_mm;
  s.phi[1][1] = c1.v_mm_s;
  const ModeState ga = advance({}, h, 1, 0), gj = advance({}, h, 0, 1);
  s.g_accel[0] = ga.z_mm;
  s.g_accel[1] = ga.v_mm_s;
  s.g_jerk[0] = gj.z_mm;
  s.g_jerk[1] = gj.v_mm_s;
  return s;
}

}  // namespace tunekit::ident
