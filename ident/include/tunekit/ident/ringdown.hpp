#pragma once
// Free-decay (ring-down) analysis of an accelerometer record: a plucked belt, a tapped
// toolhead. Records of this kind are short (a fraction of a second to a few seconds at
// 0.4-6.4 kHz) and hold one impact followed by the decay of a few lightly damped modes, so
// they are analysed in the time domain instead of by Welch's method:
//   1. the impact is the largest excursion; the decay window starts `settle_s` after it;
//   2. strength gate: the RMS of the first 0.1 s of the decay over the noise floor (the RMS
//      before the impact, or of the record's last fifth when there is too little before it);
//      a record whose strongest channel is below `min_strength` is refused (FitError, exit 1);
//   3. the fundamental, from all channels together: the spectral lines of every channel's
//      window and of the channels' summed spectrum, each measured against its own spectrum's
//      median, are pooled; every clear line is a candidate fundamental f, and its harmonic
//      series (lines at 2f, 3f, ... within `harmonic_tolerance`) is collected. The candidate
//      whose series carries the most power wins, and a series with harmonics wins over a lone
//      line unless the lone line is over five times stronger -- a plucked string rings with its
//      harmonics. Every series is collected over the same band (up to `max_hz`), so a line at
//      f/2 that is clearly there makes the line at f its second harmonic, however strong:
//      f/2's series then holds every line of f's. A pluck whose second
//      harmonic is the strongest line in every channel therefore reads at its fundamental.
//      A weaker line at f/2 of a clear line, and a pair of lines g, 2g both well over the
//      floor, are candidates too (`min_fundamental_line_ratio`, `min_pair_line_ratio`);
//   4. the projection: the channels are combined as y = sum_c w_c x_c with the unit vector w
//      in which the fundamental stands highest over the noise (each channel weighted by its
//      noise, the principal direction of the fundamental's complex amplitudes). A named
//      channel is used alone instead;
//   5. the fundamental, its harmonics and the other strong lines of the projection are
//      fitted as damped sinusoids (least squares from several starts, the matrix pencil's at
//      several orders and the spectrum's, the least residual kept; fitting/damped_sinusoids.hpp):
//      the harmonics at exactly k f0, each line of the series with its own damping, amplitude
//      and phase, the other lines free, giving the fundamental's frequency (informed by every
//      harmonic) and damping ratio with 95 % intervals. Where the residuals are not white, up to
//      four lines of the other motion (a high-order matrix pencil's) are added, each with its
//      own frequency and damping, when they lower the BIC. A candidate whose fitted fundamental
//      has no amplitude (a Wald test, before those lines are added) is set aside and the next
//      one taken;
//   6. what is not a ring-down is refused (FitError, exit 1): no line standing above the
//      spectrum's floor (a weak pluck, a bump), a line that does not decay (a fan's or a
//      motor's steady tone), a decay faster than `max_zeta` (a tap on the frame, when the
//      caller asks for a belt).
// The intervals are Wald intervals; where the residuals are not white (Ljung-Box p < 0.01) the
// frequency's and damping's are widened by the residuals' spectral level at the lines
// (`interval_factor`), and the whiteness p-value is reported with them.

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/ident/resonance.hpp"

namespace tunekit::ident {

struct RingdownOptions {
  double min_hz = 20.0;  ///< lowest fundamental considered, Hz
  /// Highest line considered (harmonics too), Hz, at most 0.45 x the sample rate; 0: that limit.
  /// Input shapers act below about 200 Hz (Klipper's resonance test stops at 133 Hz by default) and
  /// printer belts ring at 50-250 Hz; the lines a toolhead accelerometer shows above 400 Hz are its
  /// mount, the frame's panels and fans, and on real plucks they can outweigh the belt's series.
  double max_hz = 400.0;
  double settle_s = 0.03;        ///< skipped after the impact (the impact and the first, large and
                                 ///< not yet free swings are not a free decay of fixed frequency)
  double max_window_s = 0.5;     ///< longest decay window fitted, s
  double min_strength = 3.0;     ///< refuse below this signal/noise RMS ratio
  int max_components = 5;        ///< damped sinusoids fitted (fundamental and harmonics first), besides
                                 ///< the other motion's lines added where the residuals are not white
  double max_line_shift = 0.05;  ///< a fitted line may move this fraction from its spectral start
  /// Relative tolerance of a harmonic at k f: a belt's overtones run at most about 1 % sharp of
  /// k f (its bending stiffness), and a wider tolerance pairs unrelated lines by chance.
  double harmonic_tolerance = 0.015;
  double min_line_ratio = 4.0;         ///< a line must stand this many times (amplitude) over its spectrum's median
  double min_subharmonic_ratio = 0.1;  ///< a candidate fundamental must reach this fraction of the strongest
                                       ///< line's amplitude
  /// A line at f/2 of a clear line f is a candidate fundamental when it stands this many
  /// times (amplitude) over the spectrum's median and reaches `min_fundamental_to_harmonic` of
  /// f's amplitude: where the sensor sits near a node of the fundamental, a real pluck's
  /// fundamental can stand lower than its second harmonic.
  double min_fundamental_line_ratio = 2.5;
  double min_fundamental_to_harmonic = 0.25;
  /// Two lines g and 2g that both stand this many times (amplitude) over the median make g a
  /// candidate fundamental, and a series counts its harmonics down to this ratio.
  double min_pair_line_ratio = 3.0;
  double max_decay_ratio = 0.8;  ///< refuse a fundamental whose fitted envelope keeps more than this fraction
                                 ///< of its amplitude over the window (a steady tone)
  double max_zeta = 0;           ///< refuse a fundamental damped more than this (a tap); 0: no limit
  std::string channel;           ///< analyse this channel alone; empty: the best projection of all
  /// Relative change of every start frequency (1 + this) and damping ratio (1 - this) of the fit,
  /// 0 in use: checks that the answer is the record's, not the start values' last digits.
  double start_perturbation = 0;
};

struct RingdownChannel {
  std::string name;
  double signal_rms = 0;  ///< first 0.1 s of the decay window, mm/s^2
  double noise_rms = 0;   ///< noise floor, mm/s^2
  double strength = 0;    ///< signal_rms / noise_rms
  double weight = 0;      ///< its weight in the analysed projection (the weights' squares sum to 1)
};

/// One line of the fundamental's harmonic series (k = 1 is the fundamental).
struct RingdownHarmonic {
  int k = 1;
  double freq_hz = 0;        ///< fitted natural frequency when fitted, else the spectral line, Hz
  double rel_amplitude = 0;  ///< spectral amplitude over the fundamental's (summed over the channels)
  bool fitted = false;       ///< fitted as a damped sinusoid of the projection
  double zeta = 0;           ///< its damping ratio when fitted
};

struct RingdownResult {
  std::string path;
  std::string channel;     ///< the named channel, or "projection"
  std::string projection;  ///< the analysed combination, e.g. "0.83 accel_x + 0.55 accel_y - 0.05 accel_z"
  double sample_rate_hz = 0;
  double impact_s = 0;        ///< time of the impact from the record's start, s
  double window_start_s = 0;  ///< from the record's start, s
  double window_s = 0;        ///< length of the fitted decay window, s
  std::vector<RingdownChannel> channels;
  double strength = 0;                      ///< of the analysed projection (decay RMS over noise RMS)
  double strongest_peak_hz = 0;             ///< highest line of the window's summed spectrum
  double spectral_freq_hz = 0;              ///< the fundamental's line on the zero-padded spectrum (start value)
  bool strongest_is_harmonic = false;       ///< the strongest line was a harmonic of the fundamental
  int harmonic_number = 1;                  ///< strongest line / fundamental (1, 2, 3, ...)
  std::vector<RingdownHarmonic> harmonics;  ///< the fundamental's series found (k = 1 first)
  double freq_hz = 0;                       ///< fundamental, natural frequency
  double freq_stderr_hz = 0;
  double freq_ci95_lo = 0, freq_ci95_hi = 0;
  double damped_freq_hz = 0;  ///< f sqrt(1 - zeta^2), what a tuner reads
  double zeta = 0;
  double zeta_stderr = 0;
  double zeta_ci95_lo = 0, zeta_ci95_hi = 0;
  /// False when the fundamental's damping reached the fit's bound for a line of the series: its
  /// component then holds the impact's heavily damped transient at that frequency as well as
  /// the line, so zeta is no mode's damping. The frequency is still the series' (tied to its
  /// harmonics), and the damping a belt is judged by is the series' least-damped line's.
  bool zeta_identified = true;
  double series_zeta = 0;  ///< the least damping ratio among the fitted lines of the series (k >= 1)
  double decay_ratio = 0;  ///< the fundamental's envelope at the window's end over its start
  /// How much the frequency's Wald interval was widened for residuals that are not white (the
  /// residuals' spectral level at the series' lines over their mean); 1: not widened.
  double interval_factor = 1;
  std::vector<double> other_lines_hz;  ///< the other fitted components' frequencies
  fitting::FitResult fit;
  std::vector<std::string> warnings;
};

/// Analyses one record. FitError (exit 1) for a record that is no ring-down (too weak, no
/// line over the noise, a steady tone, a decay faster than max_zeta; the message names the
/// measured value and the threshold) or a fit that fails; InputError for a record too short.
RingdownResult analyze_ringdown(const AccelRecord& record, const RingdownOptions& options = {});

nlohmann::json to_json(const RingdownResult& r);

}  // namespace tunekit::ident
