#pragma once
// tunekit thermal as a function: the hot end's thermal model (ident/thermal_fit.hpp: heater
// block, sensor lag, ambient and fan loss, the filament's heat) fitted to a thermal record,
// each parameter with its 95 % interval, the correlations that matter, the residuals' checks and
// the held-out part's prediction error. The record is the CSV a heater-identify run writes
// (thermal.csv: time, temperature, target, heater_duty, fan_duty, feed) or any CSV with a time,
// a temperature and a heater duty column, or a firmware's own log: Klipper's klippy.log, whose
// "Stats" lines give one heater's temperature, target and PWM once a second
// (formats/heater_log.hpp; neither the part fan nor the feed is in them: both are taken as zero).
// The shape of a command is described in docs/cpp-api.md.

#include <ostream>
#include <string>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/results/input_digest.hpp"
#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/ident/thermal_fit.hpp"
#include "tunekit/ident/thermal_record.hpp"

namespace tunekit::calibration {

struct ThermalOptions {
  std::string file;                 ///< the record (CSV) or a klippy.log
  std::string heater = "extruder";  ///< klippy.log: the heater whose Stats are read
  double until_s = fitting::kNaN;   ///< fit only the record's first seconds (NaN: all of it)
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
  std::string format;           ///< "csv" or "klippy.log"
};

/// True when `bytes` hold klippy.log Stats lines rather than a CSV.
bool looks_like_klippy_log(std::string_view bytes);

/// The record of `options.heater` from klippy.log text: its longest run with a target set
/// (ident/heater_log_record.hpp). InputError when the heater is not in the log.
ident::ThermalRecord read_klippy_thermal_record(std::string_view bytes, const std::string& heater);

/// Reads a thermal record CSV: the time column (by its usual names), "temperature" (or "temp"),
/// "heater_duty" (or "pwm", "duty"), and optional "fan_duty" (or "fan"), "feed" and "target".
/// InputError naming what is missing or wrong.
ident::ThermalRecord read_thermal_csv(const std::string& path, std::string_view bytes);

/// InputError (exit 2) for a bad record, FitError (exit 1) when the fit does not converge.
ThermalOutcome compute_thermal(const ThermalOptions& options);

Envelope to_envelope(const ThermalOutcome& outcome);
void print_text(const ThermalOutcome& outcome, std::ostream& os);

}  // namespace tunekit::calibration
