// tunekit belts: compare the two belts of a CoreXY machine from one pluck recording of each,
// as the belt-comparison tools report it: each belt's fundamental frequency (ring-down
// analysis, ident/ringdown.hpp), their difference, and the tension ratio (fA / fB)^2 (a
// string's tension is proportional to its frequency squared at equal length and mass).
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "resonance_common.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/envelope.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/ident/csv.hpp"
#include "tunekit/ident/ringdown.hpp"

namespace tunekit::cli {
namespace {

struct BeltsArgs {
  std::string file_a, file_b;
  ResonanceCliArgs in;  // input columns and ring-down options
};

int run_belts(const BeltsArgs& a, CliContext& ctx) {
  Envelope env("belts");
  nlohmann::json opts = {{"time_column", a.in.time_column},
                         {"accel_columns", a.in.accel_columns},
                         {"channel", a.in.ringdown_channel},
                         {"min_strength", a.in.min_strength},
                         {"ringdown_min_hz", a.in.ringdown_min_hz},
                         {"ringdown_max_hz", a.in.ringdown_max_hz}};
  env.set_options(opts);
  const auto ro = ringdown_options(a.in);
  ident::AccelInputOptions in;
  in.time_column = a.in.time_column;
  in.accel_columns = a.in.accel_columns;
  in.axis = 'x';  // not used: a belt record is not an axis measurement
  in.full_scale_mm_s2 = a.in.full_scale_mm_s2;
  auto analyse = [&](const std::string& path) {
    const std::string bytes = ident::read_file_bytes(path);
    env.add_input(path, bytes);
    const auto rec = ident::load_accel_csv(path, bytes, in);
    for (const auto& w : rec.warnings) env.warn(path + ": " + w);
    auto r = ident::analyze_ringdown(rec, ro);
    for (const auto& w : r.warnings) env.warn(path + ": " + w);
    return r;
  };
  const auto ra = analyse(a.file_a);
  const auto rb = analyse(a.file_b);
  const double fa = ra.damped_freq_hz, fb = rb.damped_freq_hz;
  const double sa = ra.freq_stderr_hz, sb = rb.freq_stderr_hz;
  const double diff = fa - fb, diff_se = std::hypot(sa, sb);
  const double ratio = (fa / fb) * (fa / fb);
  // Delta method: d ln(ratio) = 2 (d fa / fa - d fb / fb).
  const double ratio_se = ratio * 2 * std::hypot(sa / fa, sb / fb);
  auto& res = env.results();
  res["a"] = ident::to_json(ra);
  res["b"] = ident::to_json(rb);
  res["freq_a_hz"] = fa;
  res["freq_b_hz"] = fb;
  res["difference_hz"] = diff;
  res["difference_stderr_hz"] = diff_se;
  res["difference_ci95"] = {diff - 1.96 * diff_se, diff + 1.96 * diff_se};
  res["tension_ratio"] = ratio;
  res["tension_ratio_stderr"] = ratio_se;
  res["tension_ratio_ci95"] = {ratio - 1.96 * ratio_se, ratio + 1.96 * ratio_se};
  res["units"] = {{"freq", "Hz"}, {"tension_ratio", "1"}};
  if (!a.in.output.json) {
    ctx.out << fmt::format("belt A ({}): {:.2f} Hz +- {:.2g} ({}, strength {:.1f})\n", a.file_a, fa, sa, ra.channel,
                           ra.strength);
    ctx.out << fmt::format("belt B ({}): {:.2f} Hz +- {:.2g} ({}, strength {:.1f})\n", a.file_b, fb, sb, rb.channel,
                           rb.strength);
    ctx.out << fmt::format("difference A - B: {:+.2f} Hz [{:+.2f}, {:+.2f}]   tension ratio (fA/fB)^2: {:.3f}\n", diff,
                           diff - 1.96 * diff_se, diff + 1.96 * diff_se, ratio);
  }
  return emit(env, a.in.output, ctx);
}

}  // namespace

void register_belts(CLI::App& app, CliContext& ctx) {
  auto args = std::make_shared<BeltsArgs>();
  // Printer belts ring at some 40-200 Hz; their second harmonic stays below 400 Hz, and the
  // band keeps out lines of the machine's electronics (an ADXL345 channel can show one near 1.1 kHz).
  args->in.ringdown_min_hz = 40;
  args->in.ringdown_max_hz = 400;
  auto* sub = app.add_subcommand("belts", "Compare two belts from a pluck recording of each: frequencies, difference, "
                                          "tension ratio");
  sub->add_option("belt_a", args->file_a, "Accelerometer CSV of belt A's pluck (#time,accel_x,accel_y,accel_z)")
      ->required();
  sub->add_option("belt_b", args->file_b, "Accelerometer CSV of belt B's pluck")->required();
  sub->add_option("--time", args->in.time_column, "Time column (s), strictly increasing (default: time)");
  sub->add_option("--accel", args->in.accel_columns,
                  "Acceleration column(s) in mm/s^2 (default: accel_x accel_y accel_z)");
  add_ringdown_options(sub, args->in, false);
  add_output_options(sub, args->in.output);
  sub->footer(
      "Each recording holds one pluck: the belt is plucked like a string with the accelerometer on the toolhead\n"
      "(Klipper: ACCELEROMETER_MEASURE, or a belt-tension tool's recorder). The fundamental is found harmonic-aware\n"
      "(a line at 2f with a weaker line at f is f's harmonic) and fitted as a damped sinusoid in the time domain.\n"
      "A pluck whose decay is below --min-strength times the noise floor is refused with exit 1.\n"
      "The tension ratio (fA/fB)^2 holds for belts of equal free length and mass per length.\n"
      "Examples:\n"
      "  tunekit belts /tmp/adxl345-belt_A.csv /tmp/adxl345-belt_B.csv\n"
      "  tunekit belts a.csv b.csv --json --require 'difference_hz<2' --require 'difference_hz>-2'");
  sub->callback([args, &ctx] { set_exit_code(run_belts(*args, ctx)); });
}

}  // namespace tunekit::cli
