// tunekit freq: liquefier frequency response (Holtrup 2019 ch. 4.3.3, appendices D-E): sine dwell at
// a known frequency, broadband H1 estimate with coherence, transfer-function fits to the
// frequency response and by output error to the record.
#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>

#include <fmt/format.h>

#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/envelope.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/fitting/transfer_function.hpp"
#include "tunekit/ident/csv.hpp"
#include "tunekit/ident/sine_dwell.hpp"
#include "tunekit/ident/spectrum.hpp"

namespace tunekit::cli {
namespace {

struct FreqArgs {
  std::string file;
  std::string time_column;  // empty: found by name
  std::string input_column;
  std::string output_column;
  std::string input_unit, output_unit;  // override the units in the column names
  std::string mode = "dwell";
  double freq_hz = 0;
  std::string fit_tf;
  bool tf_delay = false;
  std::size_t segment = 0;
  std::string window = "hann";
  double fmin_hz = 0;
  double fmax_hz = 0;
  double tmin_s = 0;
  double min_coherence = 0.8;
  OutputOptions output;
};


// Uniform sampling rate of a time column; InputError when the sampling is irregular.
double uniform_rate(const std::vector<double>& t, const std::string& file) {
  const double mean_dt = (t.back() - t.front()) / static_cast<double>(t.size() - 1);
  double worst = 0;
  for (std::size_t i = 1; i < t.size(); ++i) worst = std::max(worst, std::abs((t[i] - t[i - 1]) - mean_dt));
  if (worst > 0.01 * mean_dt)
    throw InputError(fmt::format("broadband analysis needs uniform sampling; the interval varies by up to {:.3g} s "
                                 "around its mean {:.3g} s",
                                 worst, mean_dt),
                     file);
  return 1.0 / mean_dt;
}

std::vector<double> unwrap_deg(const std::vector<std::complex<double>>& h) {
  std::vector<double> ph;
  double offset = 0, prev = 0;
  for (std::size_t i = 0; i < h.size(); ++i) {
    const double p = std::arg(h[i]) * 180.0 / std::numbers::pi;
    if (i > 0) {
      const double d = p + offset - prev;
      if (d > 180) offset -= 360 * std::round(d / 360);
      else if (d < -180) offset += 360 * std::round(-d / 360);
    }
    prev = p + offset;
    ph.push_back(prev);
  }
  return ph;
}

nlohmann::json bode_json(const std::vector<double>& f, const std::vector<std::complex<double>>& h,
                         const std::vector<double>* coherence) {
  std::vector<double> mag, db;
  for (const auto& v : h) {
    mag.push_back(std::abs(v));
    db.push_back(20 * std::log10(std::max(std::abs(v), 1e-300)));
  }
  nlohmann::json j{{"freq_hz", f}, {"magnitude", mag}, {"magnitude_db", db}, {"phase_deg", unwrap_deg(h)}};
  if (coherence != nullptr) j["coherence"] = *coherence;
  return j;
}

int run_freq(const FreqArgs& a, CliContext& ctx) {
  const std::string bytes = ident::read_file_bytes(a.file);
  ident::CsvOptions copt;
  copt.columns = {a.output_column};
  if (!a.input_column.empty()) copt.columns.push_back(a.input_column);
  copt.time_column = a.time_column;
  copt.find_time_column = a.time_column.empty();
  const auto table = ident::parse_csv(bytes, a.file, copt);
  const auto& t_all = table.column(table.time_column).values;
  const auto& ycol = table.column(a.output_column);
  const std::string y_unit = unit_or_1(a.output_unit.empty() ? ycol.unit : a.output_unit);
  std::string u_unit = a.input_column.empty() ? "1" : unit_or_1(table.column(a.input_column).unit);
  if (!a.input_unit.empty()) u_unit = a.input_unit;
  if (ident::is_volumetric_flow_unit(u_unit)) u_unit = "mm^3/s";

  Envelope env("freq");
  env.set_options({{"time_column", table.time_column},
                   {"input_unit", a.input_unit},
                   {"output_unit", a.output_unit},
                   {"input_column", a.input_column},
                   {"output_column", a.output_column},
                   {"mode", a.mode},
                   {"freq_hz", a.freq_hz},
                   {"fit_tf", a.fit_tf},
                   {"tf_delay", a.tf_delay},
                   {"segment", a.segment},
                   {"window", a.window},
                   {"fmin_hz", a.fmin_hz},
                   {"fmax_hz", a.fmax_hz},
                   {"tmin_s", a.tmin_s},
                   {"min_coherence", a.min_coherence}});
  env.add_input(a.file, bytes);
  for (const auto& w : table.warnings) env.warn(w);
  auto& res = env.results();
  auto located = [&](auto&& fn) {
    try {
      fn();
    } catch (const Error& e) {
      if (!e.location().empty()) throw;
      if (e.code() == ExitCode::bad_input) throw InputError(e.message(), a.file);
      if (e.code() == ExitCode::fit_failed) throw FitError(e.message(), a.file);
      throw;
    }
  };

  if (a.mode == "dwell") {
    if (!(a.freq_hz > 0)) throw InputError("sine dwell needs the excitation frequency: --freq-hz F (Hz)");
    if (!a.fit_tf.empty()) throw InputError("--fit-tf needs broadband data: use --mode h1 or --mode oe");
    ident::SineDwell sd;
    located([&] {
      sd = ident::sine_dwell(t_all, ycol.values, a.freq_hz,
                             a.input_column.empty() ? std::span<const double>() : table.column(a.input_column).values,
                             y_unit, u_unit);
    });
    res["sine_dwell"] = ident::to_json(sd);
    for (const auto& w : sd.output.warnings) env.warn("output: " + w);
    if (sd.input)
      for (const auto& w : sd.input->warnings) env.warn("input: " + w);
    if (!a.output.json) {
      auto line = [&](const char* what, const fitting::FitResult& f, const std::string& unit) {
        ctx.out << fmt::format("  {:<7} amplitude {:.4g} +- {:.2g} {}  phase {:.2f} +- {:.2f} deg  offset {:.4g} {}\n",
                               what, f.value("amplitude"), f.param("amplitude").std_error, unit, f.value("phase_deg"),
                               f.param("phase_deg").std_error, f.value("offset"), unit);
      };
      ctx.out << fmt::format("{}: sine dwell at {:.6g} Hz, {} samples\n", a.file, a.freq_hz, t_all.size());
      line("output", sd.output, y_unit);
      if (sd.input) {
        line("input", *sd.input, u_unit);
        ctx.out << fmt::format("  gain {:.4g} +- {:.2g}   phase lag {:.2f} +- {:.2f} deg (positive: output lags)\n",
                               sd.gain.value, sd.gain.std_error, sd.phase_lag_deg.value, sd.phase_lag_deg.std_error);
      }
    }
    return emit(env, a.output, ctx);
  }

  if (a.mode != "h1" && a.mode != "oe") throw InputError("--mode must be dwell, h1 or oe (got '" + a.mode + "')");
  if (a.input_column.empty()) throw InputError("--mode " + a.mode + " needs the input column: --input COL");
  if (a.mode == "oe" && a.fit_tf.empty()) throw InputError("--mode oe needs the model structure: --fit-tf P,Z");
  // The broadband analyses use the record from --tmin on (a start-up transient left out).
  const auto first = static_cast<std::ptrdiff_t>(std::lower_bound(t_all.begin(), t_all.end(), a.tmin_s) - t_all.begin());
  const std::vector<double> t(t_all.begin() + first, t_all.end());
  const std::vector<double> u(table.column(a.input_column).values.begin() + first, table.column(a.input_column).values.end());
  const std::vector<double> y(ycol.values.begin() + first, ycol.values.end());
  if (t.size() < 16)
    throw InputError(fmt::format("too few samples ({}) for a spectral estimate{}", t.size(),
                                 a.tmin_s > 0 ? fmt::format(" from --tmin {:g} s on", a.tmin_s) : std::string()),
                     a.file);
  for (const auto* col : {&u, &y}) {
    const auto [lo, hi] = std::minmax_element(col->begin(), col->end());
    if (!(*hi > *lo))
      throw InputError(std::string(col == &u ? "the input" : "the output") + " column is constant", a.file);
  }
  const double fs = uniform_rate(t, a.file);
  ident::WelchOptions wo;
  wo.window = ident::parse_window(a.window);
  if (a.segment > 0) {
    wo.segment_length = a.segment;
  } else {  // about 16 half-overlapping segments, a power of two, at most 65536 samples
    std::size_t seg = 16;
    while (seg * 2 <= t.size() / 8 && seg < 65536) seg *= 2;
    wo.segment_length = seg;
  }
  ident::FrequencyResponse fr;
  located([&] { fr = ident::h1_estimate(u, y, fs, wo); });
  std::vector<double> f;
  std::vector<std::complex<double>> h;
  std::vector<double> coh;
  const double fmax = a.fmax_hz > 0 ? a.fmax_hz : fs / 2;
  for (std::size_t i = 0; i < fr.freq_hz.size(); ++i) {
    if (fr.freq_hz[i] <= 0 || fr.freq_hz[i] < a.fmin_hz || fr.freq_hz[i] > fmax) continue;
    f.push_back(fr.freq_hz[i]);
    h.push_back(fr.h[i]);
    coh.push_back(fr.coherence[i]);
  }
  if (f.empty()) throw InputError("no frequency bins inside --fmin/--fmax", a.file);
  res["h1"] = {{"sample_rate_hz", fs},
               {"segment_length", wo.segment_length},
               {"segments", fr.segments},
               {"window", ident::to_string(wo.window)},
               {"bode", bode_json(f, h, &coh)}};
  if (!a.output.json)
    ctx.out << fmt::format("{}: H1 estimate, {:.6g} Hz sampling, {} segments of {} samples, {} bins {:.4g}-{:.4g} Hz\n",
                           a.file, fs, fr.segments, wo.segment_length, f.size(), f.front(), f.back());

  if (!a.fit_tf.empty()) {
    auto st = fitting::parse_tf_structure(a.fit_tf);
    st.delay = a.tf_delay;
    std::vector<double> ff, sg;
    std::vector<std::complex<double>> hh;
    for (std::size_t i = 0; i < f.size(); ++i) {
      if (coh[i] < a.min_coherence) continue;
      ff.push_back(f[i]);
      hh.push_back(h[i]);
      sg.push_back(fitting::h1_sigma(h[i], coh[i], fr.segments));
    }
    if (ff.size() < 4)
      throw InputError(fmt::format("only {} frequency points have coherence >= {}; lower --min-coherence or excite "
                                   "more",
                                   ff.size(), a.min_coherence),
                       a.file);
    const std::string gain_unit = y_unit + "/(" + u_unit + ")";
    fitting::FitResult fit;
    located([&] { fit = fitting::fit_tf_frf(ff, hh, sg, st, gain_unit); });
    const auto tf = fitting::tf_from_fit(st, fit);
    std::vector<std::complex<double>> hm;
    for (double fi : f) hm.push_back(tf.response(fi));
    res["tf_fit"] = fitting::to_json(fit);
    res["tf_fit"]["points_used"] = ff.size();
    res["tf_fit"]["weighting"] = "1/sigma from coherence: sigma = |H| sqrt((1-g2)/(2 n_segments g2))";
    res["tf_fit"]["bode"] = bode_json(f, hm, nullptr);
    for (const auto& w : fit.warnings) env.warn("tf fit: " + w);
    auto print_fit = [&](const char* label, const fitting::FitResult& r) {
      ctx.out << fmt::format("  {} {}:", label, r.model);
      for (const auto& p : r.params) ctx.out << fmt::format("  {} = {:.5g} +- {:.2g}", p.name, p.value, p.std_error);
      ctx.out << fmt::format("   r2 {:.4f}\n", r.diagnostics.r2);
    };
    if (!a.output.json) print_fit("frequency-domain fit", fit);
    if (a.mode == "oe") {
      fitting::FitResult oe;
      located([&] { oe = fitting::fit_tf_output_error(u, y, 1.0 / fs, st, fit, gain_unit); });
      res["tf_oe_fit"] = fitting::to_json(oe);
      const auto tf_oe = fitting::tf_from_fit(st, oe);
      std::vector<std::complex<double>> hoe;
      for (double fi : f) hoe.push_back(tf_oe.response(fi));
      res["tf_oe_fit"]["bode"] = bode_json(f, hoe, nullptr);
      for (const auto& w : oe.warnings) env.warn("output-error fit: " + w);
      if (!a.output.json) print_fit("output-error fit", oe);
    }
  }
  return emit(env, a.output, ctx);
}

}  // namespace

void register_freq(CLI::App& app, CliContext& ctx) {
  auto args = std::make_shared<FreqArgs>();
  auto* sub = app.add_subcommand(
      "freq", "Liquefier frequency response: sine dwell, broadband H1 and transfer-function fits");
  sub->add_option("file", args->file, "CSV log (time in s; units in column names, e.g. 'width (mm)')")->required();
  sub->add_option("-t,--time", args->time_column,
                  "Time column (s; ms and us are converted), strictly increasing; default: found by name (time, t, "
                  "timestamp, time_s)");
  sub->add_option("--input-unit", args->input_unit, "Unit of the input column when its name does not say it");
  sub->add_option("--output-unit", args->output_unit, "Unit of the output column when its name does not say it");
  sub->add_option("-y,--output", args->output_column, "Output column (e.g. line width in mm, force in N)")
      ->required();
  sub->add_option("-i,--input", args->input_column, "Input column (e.g. set-point width in mm, feed in mm/s)");
  sub->add_option("--mode", args->mode,
                  "dwell: sine fit at --freq-hz (non-uniform sampling allowed); h1: broadband H1 estimate with "
                  "coherence; oe: h1, TF fit, then output-error refinement on the record")
      ->capture_default_str();
  sub->add_option("-f,--freq-hz", args->freq_hz, "Excitation frequency for --mode dwell (Hz)");
  sub->add_option("--fit-tf", args->fit_tf, "Fit a transfer function with P,Z poles and zeros (P 1-3, Z 0-2)");
  sub->add_flag("--tf-delay", args->tf_delay, "Include a dead time theta_s (s) in the fitted transfer function");
  sub->add_option("--segment", args->segment,
                  "Welch segment length (samples; default: a power of two giving about 16 segments)");
  sub->add_option("--window", args->window, "Welch window: hann, hamming, kaiser, rect")->capture_default_str();
  sub->add_option("--fmin", args->fmin_hz, "Lowest frequency reported and fitted (Hz)");
  sub->add_option("--fmax", args->fmax_hz, "Highest frequency reported and fitted (Hz; default Nyquist)");
  sub->add_option("--tmin", args->tmin_s,
                  "Broadband modes: leave out the record before this time (s), e.g. a start-up transient the "
                  "models do not describe");
  sub->add_option("--min-coherence", args->min_coherence,
                  "Frequency points with a lower coherence (0-1) are left out of the TF fit")
      ->capture_default_str();
  add_output_options(sub, args->output);
  sub->footer(
      "Examples:\n"
      "  tunekit freq datasets/liquefier/appendix_d/exp_07.csv --time time --output width \\\n"
      "      --input setpoint_width --freq-hz 0.05305165 --json    # Holtrup 2019 appendix D, experiment 7\n"
      "  tunekit freq datasets/liquefier/synthetic_chirp.csv --time time --input feed --output force \\\n"
      "      --mode h1 --fit-tf 2,0 --fmax 40 --json\n"
      "  tunekit freq datasets/liquefier/synthetic_chirp.csv --time time --input feed --output force \\\n"
      "      --mode oe --fit-tf 2,0 --fmax 40\n"
      "Sine dwell: y = offset + amplitude sin(2 pi f t + phase) by linear least squares; gain = output/input\n"
      "amplitude, phase_lag_deg = input phase - output phase in (-180, 180] (positive: the output lags).\n"
      "Appendix D frequencies: datasets/liquefier/appendix_d/design.csv (f = N v / (2 pi 30 mm)).");
  sub->callback([args, &ctx] { set_exit_code(run_freq(*args, ctx)); });
}

}  // namespace tunekit::cli
