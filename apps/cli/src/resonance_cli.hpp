#pragma once
// The command-line side of what `tunekit resonance`, `tunekit shaper` and `tunekit belts`
// share: binding the accelerometer and ring-down options straight into the library's option
// structs (the defaults --help shows are read from them), the help on feeding the files a
// printer writes, and the JSON of options, modes and spectra.

#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "tunekit/calibration/results/context.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/analyses/resonance_common.hpp"
#include "tunekit/ident/ringdown.hpp"

namespace tunekit::cli {

using namespace calibration;

/// Adds the files, input, spectrum and mode options, then the output options.
void add_accel_files_options(CLI::App* sub, AccelFilesOptions& o, OutputOptions& output);
/// Adds the ring-down options (--channel, --min-strength, band) and, when `ringdown_flag` is
/// given, --ringdown setting it.
void add_ringdown_options(CLI::App* sub, ident::RingdownOptions& o, bool* ringdown_flag);
/// Help text: how to feed the files a Klipper or RepRapFirmware printer writes.
std::string klipper_files_help();

}  // namespace tunekit::cli
