#pragma once
// The simulation of the whole-record liquefier model (liquefier_model.hpp), templated on the
// scalar so that the fit differentiates it exactly with Ceres' Jets. Private to the fitting
// library.

#include <cmath>
#include <cstddef>

#include <ceres/jet.h>

namespace tunekit::fitting::liquefier_detail {

inline double value_of(double x) { return x; }
template <int N>
double value_of(const ceres::Jet<double, N>& x) {
  return x.a;
}

/// One step of the store over a time h with the input going linearly from u0 to u1:
/// dV/dt = u - q(V), linearised at V (exact for b = 0).
template <class T>
void store_step(T& V, const T& h, const T& u0, const T& u1, const T& ln_a, const T& bp1, const T& ln_bp1,
                const T& inv_bp1) {
  using std::exp;
  using std::expm1;
  using std::log;
  if (!(value_of(h) > 0)) return;
  const T du = u1 - u0;
  if (!(value_of(V) > 0)) {
    if (value_of(bp1) <= 1.0) {  // b <= 0: an empty store fills without outflow (tau infinite)
      V = (u0 + 0.5 * du) * h;
    } else {  // b > 0: the empty store's time constant at the flow it is fed with
      const T uq = value_of(u1) > value_of(u0) ? u1 : u0;
      if (!(value_of(uq) > 0)) {
        V = T(0.0);
        return;
      }
      const T tau = exp(ln_a + (bp1 - 1.0) * log(uq));
      const T z = h / tau;
      const T e1 = -expm1(-z);
      V = u0 * tau * e1 + du * tau * (1.0 - e1 / z);
    }
    if (value_of(V) < 0) V = T(0.0);
    return;
  }
  const T ln_q = (ln_bp1 + log(V) - ln_a) * inv_bp1;
  const T q = exp(ln_q);
  const T tau = bp1 * V / q;
  const T z = h / tau;
  const T e1 = -expm1(-z);
  V += (u0 - q) * tau * e1 + du * tau * (1.0 - e1 / z);
  if (value_of(V) < 0) V = T(0.0);
}

/// Simulates the record (t, u of n samples) from the stored volume V0 at t[0] and writes the
/// sensor-free signal (q, or V when `volume`) at every sample into out. The delayed input u(t - theta) is piecewise
/// linear with breakpoints at t_j + theta; every piece between two breakpoints or samples is integrated in equal
/// steps: ceil((t[k+1] - t[k]) / h_max) of them for the pieces between samples k and k+1 (1..max_substeps; all
/// max_substeps when h_max is not positive). The count depends on the sample times only, never on the parameters,
/// so the simulation is a smooth function of them.
template <class T>
void simulate(const double* t, const double* u, std::size_t n, const T& a, const T& b, const T& theta, const T& V0,
              bool volume, int max_substeps, double h_max, T* out) {
  using std::exp;
  using std::log;
  const T bp1 = b + 1.0;
  const T ln_a = log(a), ln_bp1 = log(bp1), inv_bp1 = 1.0 / bp1;
  auto q_of = [&](const T& V) {
    if (!(value_of(V) > 0)) return T(0.0);
    return exp((ln_bp1 + log(V) - ln_a) * inv_bp1);
  };
  auto emit = [&](std::size_t k, const T& V) { out[k] = volume ? V : q_of(V); };
  T V = V0;
  if (!(value_of(V) > 0)) V = T(0.0);
  emit(0, V);
  const double th = value_of(theta);
  std::size_t j = 0;  // first input sample whose delayed time lies after the current time
  while (j < n && t[j] + th <= t[0]) ++j;
  // u(s - theta) for s between the delayed samples j-1 and j.
  auto delayed = [&](double s) -> T {
    if (j == 0) return T(u[0]);
    if (j >= n) return T(u[n - 1]);
    const T w = (T(s) - theta - t[j - 1]) / (t[j] - t[j - 1]);
    return u[j - 1] + (u[j] - u[j - 1]) * w;
  };
  int substeps = max_substeps;
  double inv_sub = 1.0 / substeps;
  auto piece = [&](const T& s, const T& e, const T& us, const T& ue) {
    const T h = (e - s) * inv_sub;
    const T du = (ue - us) * inv_sub;
    for (int i = 0; i < substeps; ++i)
      store_step(V, h, us + du * double(i), us + du * double(i + 1), ln_a, bp1, ln_bp1, inv_bp1);
  };
  for (std::size_t k = 0; k + 1 < n; ++k) {
    if (h_max > 0) {
      const double c = std::ceil((t[k + 1] - t[k]) / h_max);
      substeps = c >= max_substeps ? max_substeps : (c > 1 ? static_cast<int>(c) : 1);
      inv_sub = 1.0 / substeps;
    }
    T s(t[k]);
    T us = delayed(t[k]);
    while (j < n && t[j] + th < t[k + 1]) {
      const T e = t[j] + theta;
      const T ue(u[j]);
      piece(s, e, us, ue);
      s = e;
      us = ue;
      ++j;
    }
    const T ue = delayed(t[k + 1]);
    piece(s, T(t[k + 1]), us, ue);
    emit(k + 1, V);
  }
}

}  // namespace tunekit::fitting::liquefier_detail
