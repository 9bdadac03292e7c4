#pragma once
// Sine dwell (Holtrup 2019 ch. 4.3.3 and appendices D-E): at a known frequency f, the record is
// fitted by y(t) = offset + amplitude sin(2 pi f t + phase). The model is linear in
// (offset, a, b) with a sin + b cos, so the least-squares solution is found exactly and then
// polished by solve_least_squares in (amplitude, phase_deg, offset) to get their standard
// errors and 95 % intervals. Sampling may be non-uniform (line widths measured around a ring).

#include <optional>
#include <span>
#include <string>

#include "tunekit/fitting/fit_result.hpp"

namespace tunekit::ident {

/// One sine fit: parameters amplitude (unit), phase_deg (deg, in (-180, 180]), offset (unit).
/// Throws InputError for fewer than 4 samples, NaN, mismatched lengths, non-increasing time, a
/// constant record or a non-positive frequency; FitError when the amplitude is not identifiable.
fitting::FitResult fit_sine(std::span<const double> t, std::span<const double> y, double freq_hz,
                            const std::string& unit = "1");

struct SineDwell {
  double freq_hz = 0;
  fitting::FitResult output;
  std::optional<fitting::FitResult> input;
  fitting::Param gain;           ///< output amplitude / input amplitude
  fitting::Param phase_lag_deg;  ///< input phase - output phase, in (-180, 180]; positive: output lags
};

/// Fits the output (and the input, when given) at freq_hz; gain and phase lag with intervals
/// propagated from the two independent fits (first-order delta method, Student t).
SineDwell sine_dwell(std::span<const double> t, std::span<const double> y, double freq_hz,
                     std::span<const double> u = {}, const std::string& y_unit = "1", const std::string& u_unit = "1");

/// JSON: {freq_hz, output: {amplitude, phase_deg, offset, diagnostics}, input: {...}, gain, phase_lag_deg}.
nlohmann::json to_json(const SineDwell& s);

/// Wraps an angle in degrees into (-180, 180].
double wrap_deg(double deg);

}  // namespace tunekit::ident
