#pragma once
// tunekit thermal as a function: the hot end's thermal model (ident/thermal_fit.hpp: heater
// block, sensor lag, ambient and fan loss, the filament's heat) fitted to a thermal record,
// each parameter with its 95 % interval, the correlations that matter, the residuals' checks and
// the held-out part's prediction error. The record is the CSV a heater-identify run writes
// (thermal.csv: time, temperature, target, heater_duty, fan_duty, feed) or any CSV with a time,
// a temperature and a heater duty column. The shape of a command is described in docs/cpp-api.md.

#include <ostream>
#include <string>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/results/input_digest.hpp"
#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/ident/thermal_fit.hpp"
#include "tunekit/ident/thermal_record.hpp"

namespace tunekit::calibration {

struct ThermalOptions {
  std::string file;  ///< the record (CSV)
  /// P, the held-out part and the confidence (ident::ThermalFitOptions). A held-out start left
  /// NaN is read from the run.json beside the record when a heater-identify run wrote it.
  ident::ThermalFitOptions fit;
};

struct ThermalOutcome {
  ThermalOptions options;
  InputDigest input;
  ident::ThermalRecord record;
  ident::ThermalFit fit;
  std::string held_out_source;  ///< "option", "run.json" or "none"
};

/// Reads a thermal record CSV: the time column (by its usual names), "temperature" (or "temp"),
/// "heater_duty" (or "pwm", "duty"), and optional "fan_duty" (or "fan"), "feed" and "target".
/// InputError naming what is missing or wrong.
ident::ThermalRecord read_thermal_csv(const std::string& path, std::string_view bytes);

/// InputError (exit 2) for a bad record, FitError (exit 1) when the fit does not converge.
ThermalOutcome compute_thermal(const ThermalOptions& options);

Envelope to_envelope(const ThermalOutcome& outcome);
void print_text(const ThermalOutcome& outcome, std::ostream& os);

}  // namespace tunekit::calibration
