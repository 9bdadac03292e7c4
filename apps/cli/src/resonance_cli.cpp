// The command-line binding and JSON of the accelerometer options and results `tunekit
// resonance`, `tunekit shaper` and `tunekit belts` share (resonance_cli.hpp).
#include "resonance_cli.hpp"

#include <cmath>
#include <cstdlib>
#include <complex>
#include <numbers>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "tunekit/cli/option_binding.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/fitting/fit_result.hpp"

namespace tunekit::cli {
namespace {

// "kaiser (default, Klipper), hann, hamming, rect" with the library's default first.
std::string resonance_window_words(ident::WindowType def) {
  std::string s = ident::to_string(def) + " (default, Klipper)";
  for (auto w :
       {ident::WindowType::kaiser, ident::WindowType::hann, ident::WindowType::hamming, ident::WindowType::rectangular})
    if (w != def) s += ", " + ident::to_string(w);
  return s;
}

// "constant (default, Klipper), linear, none" with the library's default first.
std::string resonance_detrend_words(ident::Detrend def) {
  std::string s = detrend_name(def) + " (default, Klipper)";
  for (auto d : {ident::Detrend::constant, ident::Detrend::linear, ident::Detrend::none})
    if (d != def) s += ", " + detrend_name(d);
  return s;
}

}  // namespace

std::string klipper_files_help() {
  return "Feeding Klipper's files:\n"
         "  Raw accelerometer data (TEST_RESONANCES AXIS=X OUTPUT=raw_data, or ACCELEROMETER_MEASURE) is written as\n"
         "  /tmp/raw_data_x_<name>.csv with the header '#time,accel_x,accel_y,accel_z' (s, mm/s^2). Pass one or more\n"
         "  of them; the axis comes from 'raw_data_x_' / 'raw_data_y_' / 'raw_data_z_' in the name (or --axis; "
         "Klipper\n"
         "  writes raw_data_z_<name>.csv for TEST_RESONANCES AXIS=Z with accel_chip_z), several files of one\n"
         "  axis are averaged for the modes (for the shaper, each counts separately, as in Klipper's "
         "calibrate_shaper.py).\n"
         "  Klipper's spectrum files are read as its calibrate_shaper.py reads them: TEST_RESONANCES' "
         "resonances_x_<name>.csv\n"
         "  and SHAPER_CALIBRATE's calibration_data_x_<name>.csv (freq,psd_x,psd_y,psd_z,psd_xyz), or several "
         "datasets\n"
         "  (freq,<name>,<name>...). Without 'shapers:' columns the PSD is as measured and gets Klipper's "
         "normalization\n"
         "  (divided by f + 0.1 Hz, damped below 10 Hz) before a shaper is chosen; with them it already has it.\n"
         "  Shake&Tune's measurement files (ShakeTune_results/*/<name>.stdata: Zstandard-compressed JSON lines of\n"
         "  [t, accel_x, accel_y, accel_z] samples) are read directly; an input-shaper measurement (axis_X_...) gives "
         "its\n"
         "  axis, any other measurement is reported under its name.\n"
         "Feeding RepRapFirmware's files:\n"
         "  M956 P0 S<samples> A0 X Y Z F\"raw_data_x_run1.csv\" writes 0:/sys/accelerometer/<name>.csv: "
         "'Sample,X,Y,Z', rows of\n"
         "  g, and a last line 'Rate <Hz>, overflows <n>' that gives the time base. Name the file "
         "raw_data_<axis>_*.csv\n"
         "  in M956 (or pass --axis).\n"
         "  Other loggers: --time COL --accel COL [--accel COL...] (mm/s^2); a commanded-acceleration column\n"
         "  --excitation COL adds the frequency response H1 and coherence, and the modes are fitted to it.\n";
}

void add_accel_files_options(CLI::App* sub, AccelFilesOptions& o, OutputOptions& output) {
  sub->add_option("files", o.files,
                  "Accelerometer CSVs: Klipper raw_data_<axis>_*.csv (#time,accel_x,accel_y,accel_z in s and mm/s^2), "
                  "Klipper spectrum files (resonances_<axis>_*.csv, calibration_data_<axis>_*.csv), Shake&Tune .stdata "
                  "files, or generic CSVs "
                  "with --time/--accel")
      ->required();
  sub->add_option(
         "--refine-with", o.refine_files,
         "A raw record (raw_data_<axis>_*.csv with its commanded_motion_<axis>_*.csv beside it) whose fit "
         "against its commanded motion refines its axis' dominant mode, its spectrum not averaged with the files': "
         "calibrate's fine pass over the band of the mode its coarse sweep located (repeatable)")
      ->check(CLI::ExistingFile);
  sub->add_option_function<std::string>(
      "--axis", [&o](const std::string& s) { o.input.axis = parse_axis_name(s); },
      "Axis of every file: x, y or z (default: from the Klipper file name; a file whose name names no "
      "axis is reported under its file stem, and needs --axis only to be exported)");
  sub->add_option("--time", o.input.time_column,
                  fmt::format("Time column (s), strictly increasing (default: {})", o.input.time_column));
  sub->add_option("--accel", o.input.accel_columns,
                  "Acceleration column(s) in mm/s^2, PSDs summed over them (default: accel_x accel_y accel_z)");
  sub->add_option("--excitation", o.input.excitation_column,
                  "Commanded-acceleration column (mm/s^2): adds the H1 frequency response and coherence, and the modes "
                  "are fitted to the FRF");
  sub->add_option_function<std::string>(
      "--window", [&o](const std::string& s) { o.welch.window = ident::parse_window(s); },
      "Welch window: " + resonance_window_words(o.welch.window));
  sub->add_option("--kaiser-beta", o.welch.kaiser_beta,
                  fmt::format("Kaiser window beta (dimensionless, default {:g} as Klipper)", o.welch.kaiser_beta));
  sub->add_option("--segment", o.welch.segment_length,
                  "Welch segment length in samples (default 2^ceil(log2(fs * 0.5 s)), Klipper's choice)");
  sub->add_option("--overlap", o.welch.overlap,
                  fmt::format("Welch segment overlap, fraction 0..0.95 (default {:g})", o.welch.overlap));
  sub->add_option_function<std::string>(
      "--detrend", [&o](const std::string& s) { o.welch.detrend = parse_detrend_name(s); },
      "Per-segment detrending: " + resonance_detrend_words(o.welch.detrend));
  sub->add_option("--fit-min", o.modes.fit_min_hz,
                  fmt::format("Lowest frequency searched for modes, Hz (default {:g})", o.modes.fit_min_hz));
  sub->add_option("--fit-max", o.modes.fit_max_hz,
                  fmt::format("Highest frequency searched for modes, Hz (default {:g}, where Klipper's sweep ends)",
                              o.modes.fit_max_hz));
  sub->add_option("--max-modes", o.modes.max_modes,
                  fmt::format("Most modes fitted per axis (default {})", o.modes.max_modes));
  sub->add_option(
      "--peak-threshold", o.modes.peak_threshold,
      fmt::format("Ignore peaks lower than this fraction of the highest (whitened PSD), 0..1 (default {:g})",
                  o.modes.peak_threshold));
  sub->add_option("--excitation-exponent", o.modes.excitation_exponent,
                  "p in the excitation spectrum shape f^p (dimensionless; default 2 for raw sweeps with amplitude "
                  "accel_per_hz*f, 1 for spectra Klipper normalized)");
  sub->add_option("--full-scale", o.input.full_scale_mm_s2,
                  "Accelerometer range in mm/s^2 for clipping detection (default: detect flat-topped extremes; "
                  "ADXL345 at +-16 g is 156906)");
  sub->add_option("--plot-max", o.max_plot_hz,
                  fmt::format("Highest frequency of the PSD arrays in the JSON, Hz (default {:g})", o.max_plot_hz));
  sub->add_flag_callback(
      "--no-frf", [&o] { o.modes.use_frf = false; }, "Fit the PSD even when an excitation column gives the FRF");
  sub->add_flag_callback(
      "--no-commanded-motion", [&o] { o.modes.use_commanded_motion = false; },
      "Fit the spectrum alone even when the record's commanded motion lies beside it "
      "(commanded_motion_<axis>_<name>.csv beside raw_data_<axis>_<name>.csv)");
  add_output_options(sub, output);
}

void add_ringdown_options(CLI::App* sub, ident::RingdownOptions& o, bool* ringdown_flag) {
  if (ringdown_flag)
    sub->add_flag("--ringdown", *ringdown_flag,
                  "Analyse each file as a free decay (a plucked belt, a tapped toolhead): fundamental frequency and "
                  "damping ratio from a time-domain fit of damped sinusoids. Chosen automatically for a record too "
                  "short for Welch's method");
  sub->add_option("--channel", o.channel, "Ring-down: analyse this channel (default: the strongest)");
  sub->add_option("--min-strength", o.min_strength,
                  fmt::format("Ring-down: refuse a record whose decay RMS is below this multiple of the noise floor "
                              "(default {:g})",
                              o.min_strength));
  sub->add_option("--ringdown-min", o.min_hz,
                  fmt::format("Ring-down: lowest fundamental considered, Hz (default {:g})", o.min_hz));
  sub->add_option("--ringdown-max", o.max_hz,
                  fmt::format("Ring-down: highest line considered, harmonics too, Hz (default {:g}, at most 0.45 x "
                              "the sample rate; 0: that limit)",
                              o.max_hz))
      ->check(CLI::Validator(
          [](std::string& v) {
            char* end = nullptr;
            const double x = v.empty() ? -1.0 : std::strtod(v.c_str(), &end);
            return v.empty() || *end != '\0' || !(x >= 0) ? "'" + v + "' is not a frequency in Hz (0 or more)"
                                                          : std::string();
          },
          "HZ"));
}

}  // namespace tunekit::cli
