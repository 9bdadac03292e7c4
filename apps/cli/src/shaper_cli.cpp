// tunekit shaper: the command line of the command (options bound straight into the library's
// option structs, so --help shows the library's defaults); the work is done by the
// calibration library's compute function.

#include "resonance_cli.hpp"
#include "tunekit/cli/command.hpp"
#include "tunekit/cli/analysis_commands.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/option_binding.hpp"
#include "tunekit/calibration/analyses/shaper_command.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/firmware/firmware_limits.hpp"
#include "tunekit/ident/klipper_spectrum.hpp"
#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <memory>
#include <set>
#include <utility>

namespace tunekit::cli {

using namespace calibration;

namespace {
struct ShaperCommand {
  ShaperOptions options;
  OutputOptions output;
};
}  // namespace

CLI::App* add_shaper_command(CLI::App& app, ShaperOptions& o, OutputOptions& output) {
  auto* sub = app.add_subcommand("shaper", "Input shaper design and recommendation from accelerometer data");
  add_accel_files_options(sub, o.accel, output);
  sub->add_flag("--klipper-compatible", o.klipper_compatible,
                "Select exactly as Klipper's calibrate_shaper.py does (assumed damping 0.1, vibrations pessimized "
                "over 0.075/0.1/0.15, Klipper's shaper list and tie-breaking) instead of using the identified damping");
  sub->add_option_function<std::vector<std::string>>(
      "--shapers",
      [&o](const std::vector<std::string>& names) {
        o.shapers.clear();
        for (const auto& n : names) o.shapers.push_back(design::parse_shaper_type(n));
      },
      "Shaper types to consider: zv mzv zvd zvdd ei 2hump_ei 3hump_ei (default: all that the --firmware "
      "has, Klipper's without it; with --klipper-compatible: zv mzv ei 2hump_ei 3hump_ei)");
  sub->add_option("--scv", o.selection.scv_mm_s,
                  fmt::format("Square-corner velocity for smoothing, mm/s (default {:g})", o.selection.scv_mm_s));
  sub->add_option("--max-smoothing", o.selection.max_smoothing_mm,
                  "Largest acceptable smoothing, mm (default: no limit)");
  sub->add_option_function<double>(
      "--max-vibrations", [&o](double pct) { o.selection.max_vibrations = pct / 100; },
      "Remaining vibrations to stay under, per cent: above it a shaper with fewer vibrations is preferred to a "
      "better score, as Klipper's calibrate_shaper.py -v (default: no limit)");
  sub->add_option("--damping-ratio", o.damping_ratio,
                  fmt::format("Design damping ratio (dimensionless; default: identified, or {:g} with "
                              "--klipper-compatible)",
                              o.selection.design_damping_ratio));
  sub->add_option("--max-shaper-freq", o.max_shaper_freq_hz,
                  fmt::format("Shaper frequencies tried stay below this, Hz (default {:g}; with --klipper-compatible "
                              "{:g}, as Klipper)",
                              o.selection.max_shaper_freq_hz, kKlipperMaxShaperFreqHz));
  sub->add_option("--max-freq", o.selection.max_freq_hz,
                  fmt::format("Highest PSD frequency the shapers are scored on, Hz (default {:g}; never below the "
                              "highest shaper frequency tried, as in Klipper's calibrate_shaper.py --max_freq)",
                              o.selection.max_freq_hz));
  sub->add_option("--accel-limit", o.accel_limit_mm_s2,
                  "The printer's acceleration limit (mm/s^2): the proposed maximum acceleration never exceeds it");
  sub->add_option("--klipper-csv", o.klipper_csv,
                  "Also write each axis's spectrum and shaper responses in Klipper's calibration_data layout "
                  "(freq,psd_x,psd_y,psd_z,psd_xyz,shapers:,...), readable by Klipper's calibrate_shaper.py; "
                  "'{axis}' in the name becomes x/y/z");
  sub->add_option_function<std::string>(
      "--firmware", [&o](const std::string& s) { o.firmware = firmware::parse_export_firmware(s); },
      "Recommend among this firmware's shapers only (klipper, kalico, marlin or rrf), each within the "
      "firmware's damping bound for it (default: Klipper's, unless --shapers names the shapers to compare)");
  sub->footer(
      klipper_files_help() +
      "\nExamples:\n"
      "  tunekit shaper /tmp/raw_data_x_*.csv /tmp/raw_data_y_*.csv\n"
      "  tunekit shaper /tmp/raw_data_x_*.csv --klipper-compatible --json   # compare with calibrate_shaper.py\n"
      "  tunekit shaper /tmp/calibration_data_y_20240101.csv --max-smoothing 0.2\n"
      "  tunekit shaper /tmp/resonances_x_20240101.csv --klipper-compatible   # same as calibrate_shaper.py\n"
      "  tunekit shaper /tmp/raw_data_x_*.csv --klipper-csv calibration_data_{axis}.csv\n"
      "  tunekit shaper log.csv --axis x --accel ax --excitation ax_cmd --json -o shaper.json");
  return sub;
}

void register_shaper(CLI::App& app, CliContext& ctx) {
  auto cmd = std::make_shared<ShaperCommand>();
  add_shaper_command(app, cmd->options, cmd->output)->callback([cmd, &ctx] {
    cmd->options.accel.digest_inputs = envelope_leaves_process(cmd->output);
    set_exit_code(report_outcome(compute_shaper(cmd->options), cmd->output, ctx));
  });
}

}  // namespace tunekit::cli
