#pragma once
// The thermal side of `tunekit export` (export_thermal.cpp): the hot end's model from the results
// of `tunekit thermal` or --thermal-model, and what is reported of the controller designed from it.
// Private to calibration.

#include <optional>

#include <nlohmann/json.hpp>

#include "tunekit/calibration/commands/design_inputs.hpp"
#include "tunekit/calibration/commands/export_command.hpp"
#include "tunekit/firmware/firmware_export.hpp"

namespace tunekit::calibration::export_thermal {

/// The thermal export the options and inputs ask for; nullopt with --no-thermal or without a model.
/// InputError for a --thermal-model that is not P:C:R:A:F[:H] numbers, or one given beside thermal
/// results.
std::optional<firmware::ThermalExport> thermal_settings(const ExportOptions& a, const DesignInputs& d);

/// The model and what each firmware gets from it: the PID with its rule and margins (Klipper,
/// Kalico with --kalico-pid), Klipper's scaled gains, RRF's M307 values, Marlin's M306 line.
nlohmann::json thermal_results_json(firmware::ExportFirmware fw, const firmware::ThermalExport& t);

}  // namespace tunekit::calibration::export_thermal
