#pragma once
// Axis overshoot and settling at the corners of a stepped motion (the rectangle test of
// Hemminger, "Improvements and Characterization of Error, Speed, and Capabilities in Low-Cost
// Additive Manufacturing Systems", MS thesis, UCLA, 2022): the toolhead stops at each corner and
// pauses; the overshoot error is the largest excursion past the settled position.
//
// Two sources of the toolhead's deviation from its commanded path:
//  - an accelerometer with the commanded acceleration on the same time base: the residual
//    (measured - commanded, mm/s^2) is integrated twice over each pause; the drift of the
//    double integration (unknown position and velocity at the start of the pause, a constant
//    sensor offset, the slow random walk of integrated noise) is removed as a least-squares
//    polynomial (cubic by default) over the whole pause, so the pause should hold several
//    periods of the residual vibration.
//  - a position (encoder) column per axis: the deviation is the position minus the settled
//    position at the end of each pause; pauses are where the position stays put.
// Results per corner and axis (axes that moved into the corner): overshoot (mm and % of the
// move), settling time from the end of the commanded motion into a +-band, residual vibration
// amplitude (largest |deviation| after the motion ended) and frequency (from the spacing of
// the deviation's alternating extrema).

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace tunekit::ident {

struct OvershootOptions {
  double band_mm = 0.01;            ///< settling band, +- mm around the settled position
  double tail_fraction = 0.3;       ///< last share of a pause taken as settled (must be within the band)
  int drift_order = 3;              ///< order of the polynomial drift removed from the integrated position (1..5)
  double min_pause_s = 0.05;        ///< shorter rests are not corners
  double min_move_mm = 0.5;         ///< an axis that moved less into a corner is not reported
  double accel_zero_mm_s2 = 1.0;    ///< |commanded acceleration| below this is no acceleration
  double position_still_mm = 0.05;  ///< encoder: spread of a rest (mm) for pause detection
};

struct CornerResult {
  int index = 0;                          ///< 0-based corner number in time order
  std::string axis;                       ///< "x" or "y"
  double t_motion_start_s = 0;            ///< start of the commanded motion into the corner (s)
  double t_motion_end_s = 0;              ///< end of the commanded motion (s)
  double move_mm = 0;                     ///< signed move length of this axis
  double overshoot_mm = 0;                ///< max excursion past the settled position, >= 0 (mm)
  double overshoot_pct = 0;               ///< overshoot_mm / |move_mm| * 100
  double settling_time_s = 0;             ///< from t_motion_end_s until |deviation| stays within the band (s)
  bool settled = true;                    ///< false: still outside the band at the pause's tail
  double residual_amplitude_mm = 0;       ///< max |deviation| after the motion ended (mm)
  double residual_freq_hz = 0;            ///< 0 when fewer than two extrema above the band
  std::vector<double> t_s, deviation_mm;  ///< the reconstructed deviation over the pause
};

struct AxisOvershootSummary {
  std::string axis;
  int corners = 0;
  double mean_overshoot_mm = 0, max_overshoot_mm = 0, mean_overshoot_pct = 0;
  double mean_settling_time_s = 0, max_settling_time_s = 0;
  double mean_residual_amplitude_mm = 0, median_residual_freq_hz = 0;
};

struct OvershootAnalysis {
  std::string source;  ///< "accelerometer" or "position"
  std::vector<CornerResult> corners;
  std::vector<AxisOvershootSummary> axes;
  double motion_time_s = 0;  ///< summed duration of the commanded motions (completion time without pauses)
  std::vector<std::string> warnings;
};

/// Accelerometer source. t (s) strictly increasing; a*, cmd* in mm/s^2, same length.
/// InputError when there are no corners (no motion followed by a pause).
OvershootAnalysis analyze_overshoot_accel(const std::vector<double>& t, const std::vector<double>& ax,
                                          const std::vector<double>& ay, const std::vector<double>& cmd_ax,
                                          const std::vector<double>& cmd_ay, const OvershootOptions& options);

/// Position (encoder) source: x, y in mm (a missing axis: empty vector).
OvershootAnalysis analyze_overshoot_position(const std::vector<double>& t, const std::vector<double>& x,
                                             const std::vector<double>& y, const OvershootOptions& options);

/// Results as JSON (units in the key names; the deviation traces only when `with_traces`).
nlohmann::json to_json(const OvershootAnalysis& a, bool with_traces = false);

/// Figure of merit after Hemminger (2022): the normalized motion speed (mean completion time of
/// the grid / this completion time) where the overshoot is within the tolerance, 0 elsewhere.
double overshoot_figure_of_merit(double overshoot_mm, double tolerance_mm, double completion_s,
                                 double mean_completion_s);

}  // namespace tunekit::ident
