#pragma once
// The design stages of `tunekit export` (export_design.cpp): from typed design inputs to the
// advance design, the flow-dependent design and the firmware's shapers. Private to calibration.

#include <map>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/calibration/commands/design_inputs.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/commands/export_command.hpp"
#include "tunekit/firmware/firmware_export.hpp"
#include "tunekit/design/flow_advance.hpp"
#include "tunekit/design/pressure_advance.hpp"

namespace tunekit::calibration::export_design {

/// The liquefier's side of the design: the advance inputs, the levels in flow and tau's trend.
struct LiquefierInputs {
  design::AdvanceInputs in;
  std::vector<StepLevel> levels;                       ///< the step analysis' operating points (u > 0)
  bool levels_in_flow = false;                         ///< their u is mm^3/s (else filament feed, mm/s)
  std::optional<design::TauPowerLaw> trend_u;          ///< tau = a u^b over the levels' u
  std::optional<StepModelInput> model;                 ///< the whole-record model (designed from first)
  nlohmann::json agreement = nlohmann::json::array();  ///< step against frequency response tau
  /// The 95 % interval (s) of the tau the advance is designed from, as its fit reports it.
  double tau_ci95_lo = std::numeric_limits<double>::quiet_NaN();
  double tau_ci95_hi = std::numeric_limits<double>::quiet_NaN();
};

/// Step (else frequency response) tau and the levels; --pa-k overrides them. Compares the step
/// and frequency-response tau by the one agreement rule (agreement.hpp) and warns when they differ.
/// The advance's 95 % interval (s). Without a flow design: tau's own interval, scaled by K / tau
/// (K is the pooled tau, or tau times a rheology factor), else K +- 1.96 times tau's standard
/// error. With one: the flow design's bounds (the levels' intervals,
/// and the melt stored below the lowest identified flow, flow_advance.hpp); when those bounds do
/// not hold the levels' intervals (a whole-record model's trend), they are widened by the widest
/// relative interval of the model's tau: every tau within its interval keeps V(Q)/Q, an average
/// of the taus up to Q, within that bound. When the melt below the data is known (measured from
/// the record's start-up transient, or read by a pressure sensor at every level) the design's
/// band is already the 95 % interval of V(Q)/Q and is returned as it is. nullopt when neither is known.
std::optional<std::pair<double, double>> advance_interval(const LiquefierInputs& li, const ExportOutcome& outcome);

LiquefierInputs liquefier_inputs(const ExportOptions& a, const DesignInputs& d, Envelope& env);

/// The machine profile's filament, line and limits (assumed defaults without --profile).
void apply_machine_profile(const ExportOptions& a, LiquefierInputs& li, Envelope& env);

/// Each axis' shaper as the firmware can take it: the recommendation, or the best-scoring
/// candidate the firmware has (with a warning); InputError when it has none.
std::map<std::string, firmware::ShaperSetting> firmware_shapers(const DesignInputs& d, firmware::ExportFirmware fw,
                                                                bool ft_motion, Envelope& env);

/// The advance design and, with two or more levels, the flow-dependent one (with the rheology
/// cross-check when a prediction was given); fills outcome.design, outcome.flow and the settings.
/// Returns the rheology cross-check's JSON (null without one).
nlohmann::json design_advance(const ExportOptions& a, LiquefierInputs& li, ExportOutcome& outcome);

}  // namespace tunekit::calibration::export_design
