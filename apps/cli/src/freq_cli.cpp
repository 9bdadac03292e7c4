// tunekit freq: the command line of the command (options bound straight into the library's
// option structs, so --help shows the library's defaults); the work is done by the
// calibration library's compute function.

#include "tunekit/cli/command.hpp"
#include "tunekit/cli/analysis_commands.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/analyses/freq_command.hpp"
#include "tunekit/cli/option_binding.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/fitting/transfer_function.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/ident/sine_dwell.hpp"
#include "tunekit/ident/spectrum.hpp"
#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <memory>
#include <numbers>

namespace tunekit::cli {

using namespace calibration;

namespace {
struct FreqCommand {
  FreqOptions options;
  OutputOptions output;
};
}  // namespace

CLI::App* add_freq_command(CLI::App& app, FreqOptions& o, OutputOptions& output) {
  auto* sub =
      app.add_subcommand("freq", "Liquefier frequency response: sine dwell, broadband H1 and transfer-function fits");
  sub->add_option("file", o.file, "CSV log (time in s; units in column names, e.g. 'width (mm)')")->required();
  sub->add_option("-t,--time", o.time_column,
                  "Time column (s; ms and us are converted), strictly increasing; default: found by name (time, t, "
                  "timestamp, time_s)");
  sub->add_option("--input-unit", o.input_unit, "Unit of the input column when its name does not say it");
  sub->add_option("--output-unit", o.output_unit, "Unit of the output column when its name does not say it");
  sub->add_option("-y,--output", o.output_column, "Output column (e.g. line width in mm, force in N)")->required();
  sub->add_option("-i,--input", o.input_column, "Input column (e.g. set-point width in mm, feed in mm/s)");
  add_choice_option<FreqMode>(
      sub, "--mode", o.mode,
      {{"auto", FreqMode::automatic}, {"dwell", FreqMode::dwell}, {"h1", FreqMode::h1}, {"oe", FreqMode::oe}},
      "dwell: sine fit at --freq-hz (non-uniform sampling allowed); h1: broadband H1 estimate with "
      "coherence; oe: h1, TF fit, then output-error refinement on the record; auto (default): dwell with "
      "--freq-hz, else oe");
  sub->add_option("-f,--freq-hz", o.freq_hz, "Excitation frequency for --mode dwell (Hz)");
  add_feed_track_option(sub, o.feed_track);
  sub->add_option("--fit-tf", o.fit_tf,
                  "Fit a transfer function with P,Z poles and zeros (P 1-3, Z 0-2); default for oe: the liquefier "
                  "model, 1,0 with dead time");
  sub->add_flag("--tf-delay", o.tf_delay, "Include a dead time theta_s (s) in the fitted transfer function");
  add_parsed_option(
      sub, "--intersample", o.inter_sample, fitting::parse_inter_sample,
      [](fitting::InterSample s) { return fitting::to_string(s); },
      "Output-error fit: the input between its samples. hold: held from each time stamp (a command "
      "applied when it was logged); centred: each sample stands for the interval around its time stamp "
      "(tunekit's feed column, a logger sampling a command); bandlimited: a smooth signal; auto "
      "(default): centred for a staircase, else bandlimited");
  sub->add_option("--segment", o.welch.segment_length,
                  "Welch segment length (samples; default: a power of two resolving the excited band in 16 bins, "
                  "at least about 16 segments' resolution, at most a quarter of the record)");
  add_parsed_option(
      sub, "--window", o.welch.window, ident::parse_window, [](ident::WindowType w) { return ident::to_string(w); },
      "Welch window: hann, hamming, kaiser, rect");
  sub->add_option("--fmin", o.fmin_hz, "Lowest frequency reported and fitted (Hz)");
  sub->add_option(
      "--fmax", o.fmax_hz,
      "Highest frequency reported and fitted (Hz; default: the top of the band the input excites, where its "
      "spectrum falls 30 dB below its peak)");
  sub->add_option("--tmin", o.tmin_s,
                  "Broadband modes: leave out the record before this time (s), e.g. a start-up transient the "
                  "models do not describe; default: the end of the steady hold before the excitation, if any");
  sub->add_option("--min-coherence", o.min_coherence,
                  "Frequency points with a lower coherence (0-1) are left out of the TF fit")
      ->capture_default_str();
  sub->add_flag("--profile-intervals", o.profile_intervals,
                "With --input: the whole-record model's 95 % intervals of b and theta_s by profile likelihood "
                "(several times slower; default: Wald intervals widened for correlated residuals)");
  add_output_options(sub, output);
  sub->footer(
      "Examples:\n"
      "  tunekit freq datasets/liquefier/appendix_d/exp_07.csv --time time --output width \\\n"
      "      --input setpoint_width --freq-hz 0.05305165 --json    # Holtrup 2019 appendix D, experiment 7\n"
      "  tunekit freq datasets/liquefier/synthetic_chirp.csv --time time --input feed --output force \\\n"
      "      --mode h1 --fit-tf 2,0 --fmax 40 --json\n"
      "  tunekit freq datasets/liquefier/synthetic_chirp.csv --time time --input feed --output force \\\n"
      "      --mode oe --fit-tf 2,0 --fmax 40\n"
      "  tunekit freq RUN_DIR/liquefier-chirp/feed_force.csv --input feed --output force\n"
      "      # a calibrate chirp: the liquefier model by output error, sized from the record as calibrate does\n"
      "Sine dwell: y = offset + amplitude sin(2 pi f t + phase) by linear least squares; gain = output/input\n"
      "amplitude, phase_lag_deg = input phase - output phase in (-180, 180] (positive: the output lags).\n"
      "Appendix D frequencies: datasets/liquefier/appendix_d/design.csv (f = N v / (2 pi 30 mm)).\n"
      "Beside these, every mode fits the whole-record liquefier model (stored melt V(Q) = a Q^(b+1)/(b+1),\n"
      "tau(Q) = a Q^b, dead time theta; as 'tunekit step' does) to the record from --tmin on, results\n"
      "'whole_record'; a record it cannot describe (no input column, an input below zero) is reported as not\n"
      "fitted with the reason and a warning, and freq's own results stand.");
  return sub;
}

void register_freq(CLI::App& app, CliContext& ctx) {
  auto cmd = std::make_shared<FreqCommand>();
  add_freq_command(app, cmd->options, cmd->output)->callback([cmd, &ctx] {
    set_exit_code(report_outcome(compute_freq(cmd->options), cmd->output, ctx));
  });
}

}  // namespace tunekit::cli
