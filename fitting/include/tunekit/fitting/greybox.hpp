#pragma once
// The second-order grey-box liquefier model of Holtrup 2019 appendix C: feeder displacement x in,
// nozzle displacement y out, through the feeder stiffness C_f, the melt's spring-damper
// (C_t, D_t) and the nozzle damping D_n:
//
//   G(s) = (D_t s + C_t) / ((D_n D_t / C_f) s^2 + (D_t + D_n + D_n C_t / C_f) s + C_t)
//
// Dividing through by C_t shows that the data determine only three combinations (time
// constants): tau_t = D_t / C_t, tau_f = D_n / C_f and tau_n = D_n / C_t:
//
//   G(s) = (tau_t s + 1) / (tau_f tau_t s^2 + (tau_t + tau_n + tau_f) s + 1)
//
// Multiplying all four coefficients by one factor leaves G unchanged, so one of them (usually
// the feeder stiffness C_f, known from the drive) must be fixed; the other three then follow.
// Fitting all four is refused as not identifiable (rank-deficient Jacobian).

#include <span>
#include <string>

#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/fitting/least_squares.hpp"
#include "tunekit/fitting/transfer_function.hpp"

namespace tunekit::fitting {

struct GreyBoxParams {
  double C_f = 1;  ///< feeder stiffness, N/m
  double C_t = 1;  ///< melt spring, N/m
  double D_t = 1;  ///< melt damper, N.s/m
  double D_n = 1;  ///< nozzle damping, N.s/m
};

/// The appendix C transfer function (unit DC gain) times K.
TransferFunction greybox_tf(const GreyBoxParams& p, double K = 1.0);

struct GreyBoxCombinations {
  double tau_t_s = 0;  ///< D_t / C_t
  double tau_f_s = 0;  ///< D_n / C_f
  double tau_n_s = 0;  ///< D_n / C_t
};
GreyBoxCombinations greybox_combinations(const GreyBoxParams& p);

struct GreyBoxFitOptions {
  double C_f = 1;        ///< value of the feeder stiffness (N/m)
  bool fix_C_f = true;   ///< false only to demonstrate that all four are not identifiable
  bool fit_gain = true;  ///< also fit a DC gain K (output units per input unit)
  std::string gain_unit = "1";
};

/// Output-error fit of the grey-box model (plus an output offset y0) to a uniformly sampled
/// record; the model output is the ZOH simulation of (u - u[0]). Starts from a small grid of
/// time constants spread over the record. Parameters: C_f (fixed), C_t, D_t, D_n, K, y0; the
/// result's warnings name the identifiable combinations and their values.
FitResult fit_greybox_output_error(std::span<const double> u, std::span<const double> y, double dt,
                                   const GreyBoxFitOptions& options = {});

}  // namespace tunekit::fitting
