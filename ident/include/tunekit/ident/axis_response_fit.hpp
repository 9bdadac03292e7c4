#pragma once
// The resonances of an axis from its accelerometer record and the motion that was commanded:
// an output-error fit in the time domain.
//
// A spectrum (Welch's averaged periodogram of a sweep) describes a resonance only approximately:
// the sweep passes the peak at a finite rate, the window smears it, and the excitation's shape
// is assumed. When the commanded motion is known piece by piece (commanded_motion.hpp), the
// record itself can be modelled: the accelerometer reads
//     y(t) = a(t) + sum_k g_k z_k''(t) + offset,
// a(t) the commanded acceleration, z_k the deflection of mode k driven through its base
// (base_excited_mode.hpp, exact over each piece), g_k the share of the motion the mode carries
// (1 for a single mode that carries it all), offset the sensor's bias. Each mode's deflection at
// the record's first sample is estimated too (what the motion before the record left ringing).
// The parameters minimise the squared difference with the record (Ljung, System Identification:
// Theory for the User, 1999, section 7.2, the output-error model). Their intervals are the
// least-squares ones, inflated by the residuals' autocorrelation (fitting::residual_variance_factor,
// Bartlett 1935) where the model does not describe the record to its noise. Starting values come
// from the spectrum's modal fit.

#include <functional>
#include <future>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/fitting/modal_fit.hpp"
#include "tunekit/ident/commanded_motion.hpp"
#include "tunekit/ident/resonance.hpp"

namespace tunekit::ident {

struct AxisResponseOptions {
  double confidence = 0.95;
  double max_zeta = 0.5;  ///< upper bound of each damping ratio
};

struct AxisResponseFit {
  fitting::FitResult fit;                    ///< freq_hz_k, zeta_k, gain_k, z0_mm_k, v0_mm_s_k, offset_mm_s2
  std::vector<fitting::ModeEstimate> modes;  ///< sorted by frequency, intervals inflated
  double variance_inflation = 1;
  std::size_t samples = 0;
  std::size_t pieces = 0;  ///< pieces of commanded motion within the record
};

/// A record's channel and the commanded motion laid on the record's clock (cut at every sample and
/// every piece boundary, from the first piece that starts within the record): all that
/// fit_axis_response needs besides the starting values. It does not depend on them, so it can be
/// built while the spectrum that gives them is analysed (on another core). It keeps its own copy
/// of the samples. InputError when the record ends where the motion starts or the motion does not
/// overlap the record.
class AxisResponseInput {
 public:
  /// `channel`: the samples of the axis' channel, the first at start_time_s (s on the motion's
  /// clock), at sample_rate_hz; `path` names the record in errors.
  AxisResponseInput(std::span<const double> channel, double start_time_s, double sample_rate_hz,
                    const std::string& path, const std::vector<AccelPiece>& motion);
  /// From the record's channel for its axis ("accel_x" for 'x'; InputError without one).
  AxisResponseInput(const AccelRecord& record, const std::vector<AccelPiece>& motion);
  AxisResponseInput(AxisResponseInput&&) noexcept;
  AxisResponseInput& operator=(AxisResponseInput&&) noexcept;
  ~AxisResponseInput();

  struct Data;  ///< defined where the fit is
  const Data& data() const { return *data_; }

 private:
  std::unique_ptr<Data> data_;
};

/// An AxisResponseInput of `record`'s channel for its axis and the motion that read_motion()
/// returns, both on another thread (std::async); get() rethrows their errors. The record's channel
/// must stay where it is until then (moving the record keeps it in place; destroying or resizing it
/// does not).
std::future<AxisResponseInput> prepare_axis_response(const AccelRecord& record,
                                                     std::function<std::vector<AccelPiece>()> read_motion);

/// The record's channel for its axis ("accel_x" for 'x'); InputError when it has none.
const std::vector<double>& axis_channel(const AccelRecord& record);

/// Fits the modes of `input` from `starts` (see below). FitError when the fit fails.
AxisResponseFit fit_axis_response(const AxisResponseInput& input, const std::vector<fitting::ModeStart>& starts,
                                  const AxisResponseOptions& options = {});

/// Fits the modes of `record`'s channel for its axis ("accel_x" for 'x') against `motion` (that
/// axis' commanded motion on the record's clock), from `starts`. InputError when the record has
/// no such channel or the motion does not overlap the record; FitError when the fit fails.
AxisResponseFit fit_axis_response(const AccelRecord& record, const std::vector<AccelPiece>& motion,
                                  const std::vector<fitting::ModeStart>& starts,
                                  const AxisResponseOptions& options = {});

/// How far the fit against the motion may lie from the spectrum's fit, in half-widths of the
/// spectrum's 95 % interval, before it is not believed: the spectrum's interval carries its own
/// model error, so two estimates of one mode lie within it; three half-widths apart, one of them
/// is wrong (a motion on another clock than the samples, a record of something else).
inline constexpr double kMotionFitAgreementHalfWidths = 3.0;

/// Replaces the spectrum's modes in `m` by the fit of `record` against `motion` (method
/// "output_error"), started from them. The spectrum's modes stay, with a warning that says why,
/// when that fit fails or when a mode's frequency or damping ratio lies more than
/// kMotionFitAgreementHalfWidths of the spectrum's interval away from the spectrum's estimate.
void refine_modes_with_motion(AxisModes& m, const AccelRecord& record, const std::vector<AccelPiece>& motion);

/// The same with the record and its motion being prepared by prepare_axis_response: its errors
/// too become the warning.
void refine_modes_with_motion(AxisModes& m, std::future<AxisResponseInput>& input);

}  // namespace tunekit::ident
