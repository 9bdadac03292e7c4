#pragma once
// Sizing of the liquefier frequency-response experiment (a feed chirp) and of its analysis
// from the time constant one expects: a prior step result, a machine's earlier calibration
// or the rheology prediction. A first-order liquefier G(s) = K e^{-theta s} / (tau s + 1)
// has its corner at f_c = 1 / (2 pi tau); the chirp must dwell on both sides of it and the
// Welch segments of the H1 estimate must be long enough to put several frequency bins below
// it (Holtrup, Tuning liquefier dynamics, MSc thesis, University of Twente, 2019, ch. 4.3.3).
//
// Without any expectation, the literature value of Bellini's liquefier model, tau = 0.45 s
// (Bellini, Guceri and Bertoldi, Liquefier dynamics in fused deposition, J. Manuf. Sci. Eng.,
// 2004; quoted by Holtrup, 2019, eq. 2.21), is the starting point.

#include <cstddef>

namespace tunekit::protocols {

/// Bellini's literature time constant (s), used when nothing better is known.
inline constexpr double kLiteratureLiquefierTau_s = 0.45;

struct ChirpPlan {
  double expected_tau_s = 0;    ///< s, what the plan was sized for
  double corner_hz = 0;         ///< 1 / (2 pi tau), Hz
  double freq_min_hz = 0;       ///< chirp start: a decade below the corner (at most half the staircase's reach)
  double freq_max_hz = 0;       ///< chirp end: five times the corner, within the staircase's reach
  double duration_s = 0;        ///< chirp duration: 20 corner periods, at least 20 s
  double settle_s = 0;          ///< steady feed before the chirp: 10 tau, at least 2 s
  double analysis_start_s = 0;  ///< record time (s) from which the analysis uses the data (the liquefier has settled)
  double welch_segment_s = 0;   ///< Welch segment duration (s) giving bins at most corner / 3 apart
  double analysis_fmax_hz = 0;  ///< highest frequency worth analysing (Hz): the chirp's end

  /// Welch segment length in samples at sample_rate_hz: the smallest power of two at least
  /// welch_segment_s long.
  std::size_t welch_segment_samples(double sample_rate_hz) const;
};

/// Plans the chirp for an expected time constant (s). staircase_step_s is the duration of one
/// constant-feed move of the chirp's staircase (the chirp protocol's segment_s): the chirp ends
/// where a period still has 10 of them. Throws InputError for a non-positive or non-finite tau
/// or step.
ChirpPlan plan_liquefier_chirp(double expected_tau_s, double staircase_step_s = 0.02);

}  // namespace tunekit::protocols
