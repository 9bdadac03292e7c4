// tunekit freq: liquefier frequency response (Holtrup 2019 ch. 4.3.3, appendices D-E): sine dwell at
// a known frequency, broadband H1 estimate with coherence, transfer-function fits to the
// frequency response and by output error to the record.
#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>

#include <fmt/format.h>

#include "tunekit/calibration/freq_command.hpp"
#include "tunekit/calibration/envelope.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/fitting/transfer_function.hpp"
#include "tunekit/ident/csv.hpp"
#include "tunekit/ident/sine_dwell.hpp"
#include "tunekit/ident/spectrum.hpp"

namespace tunekit::calibration {
namespace {

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

// Rethrows a library error without a location at the file.
template <class Fn>
void freq_located(const std::string& file, Fn&& fn) {
  try {
    fn();
  } catch (const Error& e) {
    if (!e.location().empty()) throw;
    if (e.code() == ExitCode::bad_input) throw InputError(e.message(), file);
    if (e.code() == ExitCode::fit_failed) throw FitError(e.message(), file);
    throw;
  }
}

std::vector<std::complex<double>> freq_model_response(const fitting::TfStructure& st, const fitting::FitResult& fit,
                                                      const std::vector<double>& f) {
  const auto tf = fitting::tf_from_fit(st, fit);
  std::vector<std::complex<double>> h;
  for (double fi : f) h.push_back(tf.response(fi));
  return h;
}

fitting::TfStructure freq_structure(const FreqOptions& a) {
  auto st = fitting::parse_tf_structure(a.fit_tf);
  st.delay = a.tf_delay;
  return st;
}

}  // namespace

std::string freq_mode_name(FreqMode mode) {
  switch (mode) {
    case FreqMode::dwell: return "dwell";
    case FreqMode::h1: return "h1";
    case FreqMode::oe: return "oe";
  }
  return "?";
}

FreqOutcome compute_freq(const FreqOptions& a) {
  FreqOutcome o;
  o.options = a;
  const std::string bytes = ident::read_file_bytes(a.file);
  ident::CsvOptions copt;
  copt.columns = {a.output_column};
  if (!a.input_column.empty()) copt.columns.push_back(a.input_column);
  copt.time_column = a.time_column;
  copt.find_time_column = a.time_column.empty();
  const auto table = ident::parse_csv(bytes, a.file, copt);
  o.time_column = table.time_column;
  o.input_sha256 = sha256_hex(bytes);
  o.input_size_bytes = bytes.size();
  const auto& t_all = table.column(table.time_column).values;
  o.samples = t_all.size();
  const auto& ycol = table.column(a.output_column);
  o.output_unit = unit_or_1(a.output_unit.empty() ? ycol.unit : a.output_unit);
  o.input_unit = a.input_column.empty() ? "1" : unit_or_1(table.column(a.input_column).unit);
  if (!a.input_unit.empty()) o.input_unit = a.input_unit;
  if (ident::is_volumetric_flow_unit(o.input_unit)) o.input_unit = "mm^3/s";
  o.warnings = table.warnings;

  if (a.mode == FreqMode::dwell) {
    if (!(a.freq_hz > 0)) throw InputError("sine dwell needs the excitation frequency: --freq-hz F (Hz)");
    if (!a.fit_tf.empty()) throw InputError("--fit-tf needs broadband data: use --mode h1 or --mode oe");
    freq_located(a.file, [&] {
      o.dwell =
          ident::sine_dwell(t_all, ycol.values, a.freq_hz,
                            a.input_column.empty() ? std::span<const double>() : table.column(a.input_column).values,
                            o.output_unit, o.input_unit);
    });
    for (const auto& w : o.dwell->output.warnings) o.warnings.push_back("output: " + w);
    if (o.dwell->input)
      for (const auto& w : o.dwell->input->warnings) o.warnings.push_back("input: " + w);
    return o;
  }

  const std::string mode = freq_mode_name(a.mode);
  if (a.input_column.empty()) throw InputError("--mode " + mode + " needs the input column: --input COL");
  if (a.mode == FreqMode::oe && a.fit_tf.empty()) throw InputError("--mode oe needs the model structure: --fit-tf P,Z");
  // The broadband analyses use the record from --tmin on (a start-up transient left out).
  const auto first =
      static_cast<std::ptrdiff_t>(std::lower_bound(t_all.begin(), t_all.end(), a.tmin_s) - t_all.begin());
  const std::vector<double> t(t_all.begin() + first, t_all.end());
  const std::vector<double> u(table.column(a.input_column).values.begin() + first,
                              table.column(a.input_column).values.end());
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
  ident::WelchOptions wo = a.welch;
  if (wo.segment_length == 0) {  // about 16 half-overlapping segments, a power of two, at most 65536 samples
    std::size_t seg = 16;
    while (seg * 2 <= t.size() / 8 && seg < 65536) seg *= 2;
    wo.segment_length = seg;
  }
  ident::FrequencyResponse fr;
  freq_located(a.file, [&] { fr = ident::h1_estimate(u, y, fs, wo); });
  FreqBroadband bb;
  bb.sample_rate_hz = fs;
  bb.segment_length = wo.segment_length;
  bb.segments = fr.segments;
  const double fmax = a.fmax_hz > 0 ? a.fmax_hz : fs / 2;
  for (std::size_t i = 0; i < fr.freq_hz.size(); ++i) {
    if (fr.freq_hz[i] <= 0 || fr.freq_hz[i] < a.fmin_hz || fr.freq_hz[i] > fmax) continue;
    bb.freq_hz.push_back(fr.freq_hz[i]);
    bb.h.push_back(fr.h[i]);
    bb.coherence.push_back(fr.coherence[i]);
  }
  if (bb.freq_hz.empty()) throw InputError("no frequency bins inside --fmin/--fmax", a.file);
  o.broadband = bb;
  if (a.fit_tf.empty()) return o;

  const auto st = freq_structure(a);
  std::vector<double> ff, sg;
  std::vector<std::complex<double>> hh;
  for (std::size_t i = 0; i < bb.freq_hz.size(); ++i) {
    if (bb.coherence[i] < a.min_coherence) continue;
    ff.push_back(bb.freq_hz[i]);
    hh.push_back(bb.h[i]);
    sg.push_back(fitting::h1_sigma(bb.h[i], bb.coherence[i], fr.segments));
  }
  if (ff.size() < 4)
    throw InputError(fmt::format("only {} frequency points have coherence >= {}; lower --min-coherence or excite "
                                 "more",
                                 ff.size(), a.min_coherence),
                     a.file);
  const std::string gain_unit = o.output_unit + "/(" + o.input_unit + ")";
  freq_located(a.file, [&] { o.tf_fit = fitting::fit_tf_frf(ff, hh, sg, st, gain_unit); });
  o.tf_points_used = ff.size();
  for (const auto& w : o.tf_fit->warnings) o.warnings.push_back("tf fit: " + w);
  if (a.mode == FreqMode::oe) {
    freq_located(a.file, [&] { o.oe_fit = fitting::fit_tf_output_error(u, y, 1.0 / fs, st, *o.tf_fit, gain_unit); });
    for (const auto& w : o.oe_fit->warnings) o.warnings.push_back("output-error fit: " + w);
  }
  return o;
}

Envelope to_envelope(const FreqOutcome& o) {
  const FreqOptions& a = o.options;
  Envelope env("freq");
  env.set_options({{"time_column", o.time_column},
                   {"input_unit", a.input_unit},
                   {"output_unit", a.output_unit},
                   {"input_column", a.input_column},
                   {"output_column", a.output_column},
                   {"mode", freq_mode_name(a.mode)},
                   {"freq_hz", a.freq_hz},
                   {"fit_tf", a.fit_tf},
                   {"tf_delay", a.tf_delay},
                   {"segment", a.welch.segment_length},
                   {"window", ident::to_string(a.welch.window)},
                   {"fmin_hz", a.fmin_hz},
                   {"fmax_hz", a.fmax_hz},
                   {"tmin_s", a.tmin_s},
                   {"min_coherence", a.min_coherence}});
  env.add_input_digest(a.file, o.input_sha256, o.input_size_bytes);
  for (const auto& w : o.warnings) env.warn(w);
  auto& res = env.results();
  if (o.dwell) res["sine_dwell"] = ident::to_json(*o.dwell);
  if (o.broadband) {
    const auto& bb = *o.broadband;
    res["h1"] = {{"sample_rate_hz", bb.sample_rate_hz},
                 {"segment_length", bb.segment_length},
                 {"segments", bb.segments},
                 {"window", ident::to_string(a.welch.window)},
                 {"bode", bode_json(bb.freq_hz, bb.h, &bb.coherence)}};
    if (o.tf_fit) {
      const auto st = freq_structure(a);
      res["tf_fit"] = fitting::to_json(*o.tf_fit);
      res["tf_fit"]["points_used"] = o.tf_points_used;
      res["tf_fit"]["weighting"] = "1/sigma from coherence: sigma = |H| sqrt((1-g2)/(2 n_segments g2))";
      res["tf_fit"]["bode"] = bode_json(bb.freq_hz, freq_model_response(st, *o.tf_fit, bb.freq_hz), nullptr);
      if (o.oe_fit) {
        res["tf_oe_fit"] = fitting::to_json(*o.oe_fit);
        res["tf_oe_fit"]["bode"] = bode_json(bb.freq_hz, freq_model_response(st, *o.oe_fit, bb.freq_hz), nullptr);
      }
    }
  }
  return env;
}

void print_text(const FreqOutcome& o, std::ostream& os) {
  const FreqOptions& a = o.options;
  if (o.dwell) {
    const auto& sd = *o.dwell;
    auto line = [&](const char* what, const fitting::FitResult& f, const std::string& unit) {
      os << fmt::format("  {:<7} amplitude {:.4g} +- {:.2g} {}  phase {:.2f} +- {:.2f} deg  offset {:.4g} {}\n", what,
                        f.value("amplitude"), f.param("amplitude").std_error, unit, f.value("phase_deg"),
                        f.param("phase_deg").std_error, f.value("offset"), unit);
    };
    os << fmt::format("{}: sine dwell at {:.6g} Hz, {} samples\n", a.file, a.freq_hz, o.samples);
    line("output", sd.output, o.output_unit);
    if (sd.input) {
      line("input", *sd.input, o.input_unit);
      os << fmt::format("  gain {:.4g} +- {:.2g}   phase lag {:.2f} +- {:.2f} deg (positive: output lags)\n",
                        sd.gain.value, sd.gain.std_error, sd.phase_lag_deg.value, sd.phase_lag_deg.std_error);
    }
    return;
  }
  if (!o.broadband) return;
  const auto& bb = *o.broadband;
  os << fmt::format("{}: H1 estimate, {:.6g} Hz sampling, {} segments of {} samples, {} bins {:.4g}-{:.4g} Hz\n",
                    a.file, bb.sample_rate_hz, bb.segments, bb.segment_length, bb.freq_hz.size(), bb.freq_hz.front(),
                    bb.freq_hz.back());
  auto print_fit = [&](const char* label, const fitting::FitResult& r) {
    os << fmt::format("  {} {}:", label, r.model);
    for (const auto& p : r.params) os << fmt::format("  {} = {:.5g} +- {:.2g}", p.name, p.value, p.std_error);
    os << fmt::format("   r2 {:.4f}\n", r.diagnostics.r2);
  };
  if (o.tf_fit) print_fit("frequency-domain fit", *o.tf_fit);
  if (o.oe_fit) print_fit("output-error fit", *o.oe_fit);
}

}  // namespace tunekit::calibration
