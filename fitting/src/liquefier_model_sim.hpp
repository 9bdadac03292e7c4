#pragma once
// The simulation of the whole-record liquefier model (liquefier_model.hpp) on plain doubles, with
// the forward sensitivities of the state (its derivatives with respect to ln a, b, theta and V0,
// propagated beside it step by step: the exact derivatives of the discrete model, the same as
// automatic differentiation of the simulation gives). Private to the fitting library.

#include <cstddef>
#include <vector>

namespace tunekit::fitting::liquefier_detail {

/// The commanded input: values u at instants t (n of them, non-decreasing; two at the same
/// instant make a step), linear between them and held before the first and after the last.
struct InputTrack {
  const double* t = nullptr;
  const double* u = nullptr;
  std::size_t n = 0;
  /// The instants where the input's slope changes (input_kinks), where alone a piece must end;
  /// null: found by simulate itself.
  const std::size_t* kinks = nullptr;
  std::size_t n_kinks = 0;
};

/// The indices of the input's instants where its slope changes: all but those inside a flat
/// stretch (the same value on both sides).
std::vector<std::size_t> input_kinks(const InputTrack& in);

/// The model's parameters in the form the simulation uses.
struct SimParams {
  double ln_a = 0;
  double b = 0;
  double theta = 0;
  double v0 = 0;
  bool b_free = true;  ///< false: the sensitivity to b is not wanted (left 0)
};

/// Simulates the store from V0 at t_out[0] and writes the sensor-free signal (q, or V when
/// `volume`) at each of the n output instants into out. When sens is not null it also receives,
/// row by row (4 per instant), the signal's derivatives with respect to ln a, b, theta and V0.
///
/// The delayed input u(t - theta) is piecewise linear with breakpoints at the input's instants
/// plus theta; every piece between two breakpoints (where the input's slope changes) or output
/// instants is integrated in equal sub-steps: ceil((t_out[k+1] - t_out[k]) / h_max) of them in
/// the interval between outputs k and k+1 (1..max_substeps; all max_substeps when h_max is not
/// positive). The count depends on the instants only, never on the parameters, so the
/// simulation is a smooth function of them.
void simulate(const double* t_out, std::size_t n, const InputTrack& in, const SimParams& p, bool volume,
              int max_substeps, double h_max, double* out, double* sens);

}  // namespace tunekit::fitting::liquefier_detail
