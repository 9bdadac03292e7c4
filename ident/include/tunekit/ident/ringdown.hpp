#pragma once
// Free-decay (ring-down) analysis of an accelerometer record: a plucked belt, a tapped
// toolhead. Records of this kind are short (a fraction of a second to a few seconds at
// 0.4-6.4 kHz) and hold one impact followed by the decay of a few lightly damped modes, so
// they are analysed in the time domain instead of by Welch's method:
//   1. the impact is the largest excursion; the decay window starts `settle_s` after it;
//   2. the channel whose fundamental line stands highest over its spectrum's median is analysed
//      (or the one named);
//   3. strength gate: the RMS of the first 0.1 s of the decay over the noise floor (the RMS
//      before the impact, or of the record's last fifth when there is too little before it);
//      a record below `min_strength` is refused (FitError, exit 1) with the measured ratio;
//   4. harmonic-aware choice of the fundamental on a zero-padded spectrum of the window: when
//      the strongest peak P has a clear peak at P/2 (or P/3), that peak is the fundamental and
//      P its harmonic -- a plucked string's second harmonic is often the strongest line in one
//      accelerometer channel;
//   5. the fundamental, its harmonic and the other strong lines are fitted as damped
//      sinusoids (matrix pencil start, least-squares refinement; fitting/damped_sinusoids.hpp),
//      giving frequency and damping ratio with 95 % intervals.
// The intervals assume white residuals; the fit's whiteness p-value is reported with them.

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/ident/resonance.hpp"

namespace tunekit::ident {

struct RingdownOptions {
  double min_hz = 20.0;                ///< lowest fundamental considered, Hz
  double max_hz = 0.0;                 ///< highest line considered, Hz; 0: 0.45 x the sample rate
  double settle_s = 0.03;              ///< skipped after the impact (the impact and the first, large and
                                       ///< not yet free swings are not a free decay of fixed frequency)
  double max_window_s = 0.5;           ///< longest decay window fitted, s
  double min_strength = 3.0;           ///< refuse below this signal/noise RMS ratio
  int max_components = 3;              ///< damped sinusoids fitted (fundamental first)
  double max_line_shift = 0.05;        ///< a fitted line may move this fraction from its spectral start
  double harmonic_tolerance = 0.03;    ///< relative tolerance of f = P/2, P/3
  double min_subharmonic_ratio = 0.1;  ///< the peak at P/2 must reach this fraction of P's height
  std::string channel;                 ///< analyse this channel; empty: the strongest
};

struct RingdownChannel {
  std::string name;
  double signal_rms = 0;  ///< first 0.1 s of the decay window, mm/s^2
  double noise_rms = 0;   ///< noise floor, mm/s^2
  double strength = 0;    ///< signal_rms / noise_rms
};

struct RingdownResult {
  std::string path;
  std::string channel;
  double sample_rate_hz = 0;
  double impact_s = 0;        ///< time of the impact from the record's start, s
  double window_start_s = 0;  ///< from the record's start, s
  double window_s = 0;        ///< length of the fitted decay window, s
  std::vector<RingdownChannel> channels;
  double strength = 0;                 ///< of the analysed channel
  double strongest_peak_hz = 0;        ///< highest line of the window's spectrum
  double spectral_freq_hz = 0;         ///< the fundamental's line on the zero-padded spectrum (start value)
  bool strongest_is_harmonic = false;  ///< the strongest line was a harmonic of the fundamental
  int harmonic_number = 1;             ///< strongest line / fundamental (1, 2 or 3)
  double freq_hz = 0;                  ///< fundamental, natural frequency
  double freq_stderr_hz = 0;
  double freq_ci95_lo = 0, freq_ci95_hi = 0;
  double damped_freq_hz = 0;  ///< f sqrt(1 - zeta^2), what a tuner reads
  double zeta = 0;
  double zeta_stderr = 0;
  double zeta_ci95_lo = 0, zeta_ci95_hi = 0;
  std::vector<double> other_lines_hz;  ///< the other fitted components' frequencies
  fitting::FitResult fit;
  std::vector<std::string> warnings;
};

/// Analyses one record. FitError (exit 1) for a record too weak to measure (naming the
/// strength and the threshold) or a fit that fails; InputError for a record too short.
RingdownResult analyze_ringdown(const AccelRecord& record, const RingdownOptions& options = {});

nlohmann::json to_json(const RingdownResult& r);

}  // namespace tunekit::ident
