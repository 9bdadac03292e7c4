#pragma once
// The quantities a result is tracked by, taken from a tunekit JSON envelope (the same JSON the
// commands print with --json). Names are the same whichever command measured them, so a
// machine's trend joins its calibrations and its hand-run analyses:
//   tau_s, theta_s, K          liquefier step response (s, s, output unit per input unit)
//   freq.tau_s, freq.theta_s   the same from the frequency response's reported fit (results.fit)
//   <axis>.freq_hz, <axis>.zeta          the axis's dominant resonance and its damping ratio
//   <axis>.shaper, <axis>.shaper_freq_hz the input shaper chosen (type, Hz)
//   <axis>.max_accel_mm_s2               the acceleration the chosen shaper allows
//   pa_k_s, pa_smooth_s        pressure advance gain and smoothing time (s)
//   belt_a.freq_hz, belt_b.freq_hz       a CoreXY machine's two belts' fundamentals (tunekit belts)
//   belt_a.tension_n, belt_b.tension_n   their tensions in N, when the span was given
//   <command>.<param>          any other fitted parameter with a value and standard error
//                              (e.g. rheo.n), found under a "params" object

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/history/store.hpp"

namespace tunekit::history {

/// The quantities of one envelope (or of a bare `results` object of `command`).
std::vector<Quantity> extract_quantities(const std::string& command, const nlohmann::json& results);

/// The quantities a trend shows by default, in display order (those present are shown).
const std::vector<std::string>& headline_quantities();

}  // namespace tunekit::history
