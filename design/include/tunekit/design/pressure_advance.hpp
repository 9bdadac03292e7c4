#pragma once
// Linear/pressure advance designed from an identified liquefier (docs/export.md).
//
// With a first-order liquefier G(s) = K_g e^{-theta s} / (tau s + 1), feeding the extruder
// with (1 + K s) times the nominal filament speed cancels the lag when K = tau. K is a time
// in seconds: millimetres of filament per mm/s of filament speed, or equally mm^3 per mm^3/s
// of volumetric flow (the ratio is unit-free as long as input and output of the identified
// model are measured in matching units). The steady-state gain K_g does not enter K: it is a
// flow-rate (extrusion multiplier) matter and is only reported. The dead time theta cannot be
// cancelled by any advance and is reported with its consequence.
//
// Smoothing: advance turns a print acceleration a into a step K*r*a of extruder speed
// (r = line cross-section / filament area). Spread over a window T, that step needs an extra
// extruder acceleration c*K*r*a/T, c being the peak of the firmware's smoothing kernel
// (1 for a box average, 2 for Klipper's triangular weighting). The shortest window that keeps
// it under the extruder's limit is T = c*K*r*a / a_extruder_max.

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace tunekit::design {

inline constexpr double kAdvanceNaN = std::numeric_limits<double>::quiet_NaN();

/// Shape of the window a firmware uses to smooth the advance term.
enum class SmoothingKernel {
  box,         ///< plain moving average over T: peak weight 1/T (the issue's K*a*r/T)
  triangular,  ///< Klipper's weighting (T/2 - |t|), total width T: peak weight 2/T
};

/// Peak of the normalized kernel times its total width: 1 (box) or 2 (triangular).
double kernel_peak_factor(SmoothingKernel kernel);

/// Shortest smoothing window (s) keeping the extra extruder acceleration
/// c * k_s * accel * area_ratio / T at or below extruder_accel_limit_mm_s2.
/// Throws InputError for negative or non-finite inputs or a non-positive limit.
double min_smoothing_window_s(double k_s, double print_accel_mm_s2, double area_ratio,
                              double extruder_accel_limit_mm_s2, SmoothingKernel kernel = SmoothingKernel::box);

/// One liquefier identification at a feed rate (from `tunekit step` results.operating_points).
struct LiquefierPoint {
  double feed_mm_s = kAdvanceNaN;  ///< filament feed rate of the operating point, mm/s
  double gain = kAdvanceNaN;       ///< steady-state gain K_g (output per input, units of the data)
  double tau_s = kAdvanceNaN;
  double theta_s = kAdvanceNaN;
};

struct AdvanceInputs {
  // Pooled identification (any of them may be NaN).
  double tau_s = kAdvanceNaN;
  double tau_stderr_s = kAdvanceNaN;
  double theta_s = kAdvanceNaN;
  double gain = kAdvanceNaN;
  /// Unit of the gain as the fit reports it ("1", "mm/(mm)", "N/(mm/s)"); empty when unknown.
  /// The gain is compared with 1 only when it is dimensionless (see gain_is_dimensionless).
  std::string gain_unit;
  std::string tau_source;  ///< "step", "freq", "command line"
  /// Several operating points: flow-dependent advance K(Q) = V(Q)/Q, V the integral of tau over
  /// 0..Q with tau interpolated linearly in flow (flow_advance.hpp derives it).
  std::vector<LiquefierPoint> points;
  /// Rheology prediction: tau(Q) / tau(Q_ref) at the given flows; scaled by tau_s, which is
  /// taken to be the time constant at reference_flow.
  std::vector<double> rheo_flow_mm3_s;
  std::vector<double> rheo_relative_tau;
  double rheo_reference_flow_mm3_s = kAdvanceNaN;

  // Machine (tunekit::machine::MachineProfile); NaN or 0 limits disable the window design.
  double filament_area_mm2 = kAdvanceNaN;
  double line_area_mm2 = kAdvanceNaN;
  double print_speed_mm_s = kAdvanceNaN;
  double print_accel_mm_s2 = kAdvanceNaN;
  double extruder_accel_limit_mm_s2 = kAdvanceNaN;
  /// Volumetric flow the single-number firmware setting is designed for; NaN: print speed
  /// times line cross-section.
  double design_flow_mm3_s = kAdvanceNaN;
};

/// Advance at one flow.
struct ScheduledAdvance {
  double flow_mm3_s = kAdvanceNaN;
  double feed_mm_s = kAdvanceNaN;
  double k_s = kAdvanceNaN;
};

struct AdvanceDesign {
  double k_s = kAdvanceNaN;         ///< advance at the design flow, s
  double k_stderr_s = kAdvanceNaN;  ///< from the pooled fit when known
  std::string k_source;             ///< "pooled", "operating points", "rheology"
  double design_flow_mm3_s = kAdvanceNaN;
  double design_feed_mm_s = kAdvanceNaN;
  double area_ratio = kAdvanceNaN;           ///< r = line cross-section / filament area
  double window_box_s = kAdvanceNaN;         ///< shortest box window (Marlin ADVANCE_TAU reading)
  double window_triangular_s = kAdvanceNaN;  ///< shortest triangular window (Klipper smooth time)
  double theta_s = kAdvanceNaN;
  double theta_track_mm = kAdvanceNaN;  ///< line length printed during theta at print speed
  double gain = kAdvanceNaN;
  std::vector<ScheduledAdvance> schedule;  ///< flow-dependent advance (sorted by flow)
  double trend_k0_s = kAdvanceNaN;         ///< least-squares K(Q) = k0 + k1 Q over the schedule
  double trend_k1_s_per_mm3_s = kAdvanceNaN;
  double single_k_max_rel_error = kAdvanceNaN;  ///< max |K(Q) - K| / K(Q) over the schedule
  std::vector<std::string> notes;               ///< what the design means (informational)
  std::vector<std::string> warnings;            ///< what the user should look at or change
  /// The design flow lies outside the operating points' flows (tau held at the nearest): a warning
  /// the caller gives unless a flow-dependent design restates it (flow_advance.hpp). Empty otherwise.
  std::string outside_range_warning;

  nlohmann::json to_json() const;
};

/// True when a gain unit is "1" or a ratio of one unit to itself ("mm/(mm)", "mm^3/s/(mm^3/s)"):
/// only then does a gain other than 1 mean that output and input disagree.
bool gain_is_dimensionless(const std::string& unit);

/// Designs the advance. Throws InputError when no time constant is available or inputs are
/// implausible (negative tau, flows not increasing, ...).
AdvanceDesign design_advance(const AdvanceInputs& in);

}  // namespace tunekit::design
