#pragma once
// Sums of exponentially damped sinusoids: the free decay of lightly damped modes (a plucked
// belt, a tapped toolhead). Start values from the matrix-pencil method (Hua and Sarkar,
// "Matrix pencil method for estimating parameters of exponentially damped/undamped sinusoids
// in noise", IEEE Trans. ASSP, 1990), refined by nonlinear least squares in the time domain
// with 95 % intervals (least_squares.hpp).
//
// Model, t = k / fs (s), component i with natural frequency f_i (Hz) and damping ratio zeta_i:
//   y(t) = c + sum_i exp(-zeta_i w_i t) (a_i cos(w_di t) + b_i sin(w_di t)),
//   w_i = 2 pi f_i, w_di = w_i sqrt(1 - zeta_i^2).
// Parameters are named f<i>_hz, zeta<i>, a<i>, b<i> (i from 0) and offset (y's unit).

#include <vector>

#include "tunekit/fitting/fit_result.hpp"

namespace tunekit::fitting {

/// One damped sinusoid found by the matrix pencil.
struct PencilComponent {
  double freq_hz = 0;    ///< natural frequency, Hz
  double zeta = 0;       ///< damping ratio (negative for a growing component)
  double amplitude = 0;  ///< initial amplitude at k = 0, y's unit
  double phase_rad = 0;  ///< at k = 0: amplitude * cos(w_d t + phase)
  /// In a fit: 0 for a free frequency; k >= 2 ties this component's natural frequency to k times
  /// component 0's (a harmonic of a string's fundamental), so that every harmonic informs f0.
  int harmonic = 0;
  /// In a fit: the upper bound of this component's damping ratio; 0 for the general bound (0.9).
  double max_zeta = 0;
};

/// Matrix-pencil estimate of the damped sinusoids in a real record `y` sampled at `fs_hz`:
/// `order` complex exponentials (two per real sinusoid) from a pencil of `pencil` columns
/// (0: min(N/3, 100)). Components with positive frequency, strongest first. InputError for a
/// record too short for the order.
std::vector<PencilComponent> matrix_pencil(const std::vector<double>& y, double fs_hz, int order, int pencil = 0);

/// Least-squares fit of the model above to `y` (sampled at fs_hz) from the start values
/// `start` (frequency and damping of each component; amplitudes are refitted), each frequency
/// kept within start x (1 -+ freq_rel_bound). A component whose `harmonic` is k >= 2 has no
/// frequency of its own: f<i>_hz is reported as k f0_hz with k times f0's error and interval
/// (a fixed parameter of the fit). FitError when it does not converge or the parameters are not
/// identifiable.
FitResult fit_damped_sinusoids(const std::vector<double>& y, double fs_hz, const std::vector<PencilComponent>& start,
                               double freq_rel_bound = 0.5);

/// fit_damped_sinusoids of one model from several start sets, the fit of least residual sum of
/// squares kept. starts.front() is the model (its frequencies centre the bounds; its ties and
/// damping bounds hold for all); every set gives start frequencies and dampings for the same
/// components (e.g. the matrix pencil's at several orders, the spectrum's). A fit ends in the
/// minimum nearest its start, and on a record with more motion than its lines that minimum can
/// move with the start's last digits; the least of several starts is the data's answer. Start
/// sets whose fit fails are passed over; FitError (the first reason) when every one fails.
FitResult fit_damped_sinusoids_best_of(const std::vector<double>& y, double fs_hz,
                                       const std::vector<std::vector<PencilComponent>>& starts,
                                       double freq_rel_bound = 0.5);

/// Model value at sample k for parameters laid out as fit_damped_sinusoids names them.
double damped_sinusoids_value(const FitResult& fit, double t_s);

}  // namespace tunekit::fitting
