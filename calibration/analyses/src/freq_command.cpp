// tunekit freq: liquefier frequency response (Holtrup 2019 ch. 4.3.3, appendices D-E): sine dwell at
// a known frequency, broadband H1 estimate with coherence, transfer-function fits to the
// frequency response and by output error to the record.
#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <numeric>

#include <fmt/format.h>

#include "tunekit/calibration/analyses/freq_command.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/fitting/transfer_function.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/ident/sine_dwell.hpp"
#include "tunekit/ident/spectrum.hpp"
#include "tunekit/core/file_bytes.hpp"

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

BodeCurve bode_curve(const std::vector<double>& f, const std::vector<std::complex<double>>& h) {
  BodeCurve b;
  b.freq_hz = f;
  for (const auto& v : h) {
    b.magnitude.push_back(std::abs(v));
    b.magnitude_db.push_back(20 * std::log10(std::max(std::abs(v), 1e-300)));
  }
  b.phase_deg = unwrap_deg(h);
  return b;
}

nlohmann::json bode_json(const std::vector<double>& f, const std::vector<std::complex<double>>& h,
                         const std::vector<double>* coherence) {
  const BodeCurve b = bode_curve(f, h);
  nlohmann::json j{
      {"freq_hz", b.freq_hz}, {"magnitude", b.magnitude}, {"magnitude_db", b.magnitude_db}, {"phase_deg", b.phase_deg}};
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

// The model fitted when none is named: the liquefier's, first order with dead time (Bellini,
// Guceri and Bertoldi, Liquefier dynamics in fused deposition, J. Manuf. Sci. Eng., 2004).
constexpr const char* kLiquefierTf = "1,0";

// Default Welch segments put bins a sixteenth of the excited band's top apart: a liquefier
// chirp ends at five times the corner it was planned for, so about three bins lie below the
// corner (Holtrup, 2019, ch. 4.3.3, resolves the corner with several bins below it).
constexpr double kBinsBelowBandTop = 16;
// ... at most a quarter of the record each, leaving seven half-overlapping segments for the
// coherence to average over.
constexpr std::size_t kMaxSegmentFraction = 4;

// The mode run: automatic is a dwell when the frequency is given, else the output-error analysis.
FreqMode resolved_mode(const FreqOptions& a) {
  if (a.mode != FreqMode::automatic) return a.mode;
  if (a.freq_hz > 0) return FreqMode::dwell;
  if (a.input_column.empty())
    throw InputError("give --freq-hz F for a sine dwell, or the input column --input COL for the broadband analysis");
  return FreqMode::oe;
}

// The structure fitted: --fit-tf, or in mode oe the liquefier model; none in h1 without --fit-tf.
std::optional<fitting::TfStructure> fit_structure(const FreqOptions& a, FreqMode mode) {
  if (a.fit_tf.empty() && mode != FreqMode::oe) return std::nullopt;
  auto st = fitting::parse_tf_structure(a.fit_tf.empty() ? kLiquefierTf : a.fit_tf);
  st.delay = a.fit_tf.empty() || a.tf_delay;
  return st;
}

// About 16 half-overlapping segments: a power of two, at most 65536 samples.
std::size_t sixteen_segments(std::size_t samples) {
  std::size_t seg = 16;
  while (seg * 2 <= samples / 8 && seg < 65536) seg *= 2;
  return seg;
}

// Welch segment length without --segment: the shortest power of two whose bins lie at most a
// sixteenth of the excited band's top apart, no coarser than sixteen_segments(), and at most a
// quarter of the record.
std::size_t band_segment(std::size_t samples, double fs, const ident::ExcitedBand& band) {
  const double want = kBinsBelowBandTop * fs / band.hi_hz;
  std::size_t seg = 16;
  while (static_cast<double>(seg) < want && seg * 2 <= samples / kMaxSegmentFraction) seg *= 2;
  return std::max(seg, sixteen_segments(samples));
}

// First sample analysed: from --tmin, else where the excitation leaves its steady hold.
std::size_t analysis_first(const std::vector<double>& t, std::span<const double> u, const FreqOptions& a) {
  if (a.tmin_s) return static_cast<std::size_t>(std::lower_bound(t.begin(), t.end(), *a.tmin_s) - t.begin());
  return ident::excitation_onset(t, u);
}

// Welch options and the upper frequency: the options given, the rest from the input's band.
void size_from_band(const FreqOptions& a, std::span<const double> u, double fs, ident::WelchOptions& wo,
                    FreqBroadband& bb) {
  wo = a.welch;
  if (wo.segment_length > 0 && a.fmax_hz > 0) {
    bb.fmax_hz = a.fmax_hz;
    return;
  }
  ident::WelchOptions probe = a.welch;
  probe.segment_length = sixteen_segments(u.size());
  bb.excited = ident::excited_band(ident::welch_psd(u, fs, probe));
  if (wo.segment_length == 0) wo.segment_length = band_segment(u.size(), fs, bb.excited);
  bb.fmax_hz = a.fmax_hz > 0 ? a.fmax_hz : bb.excited.hi_hz;
}

// The transfer-function fits: to the coherent H1 points, then (mode oe) by output error to the
// analysed record u, y, started from the first.
void freq_fits(FreqOutcome& o, const FreqOptions& a, const std::vector<double>& u, const std::vector<double>& y) {
  const auto st = fit_structure(a, o.mode);
  if (!st) return;
  o.structure = *st;
  const auto& bb = *o.broadband;
  std::vector<double> ff, sg;
  std::vector<std::complex<double>> hh;
  for (std::size_t i = 0; i < bb.freq_hz.size(); ++i) {
    if (bb.coherence[i] < a.min_coherence) continue;
    ff.push_back(bb.freq_hz[i]);
    hh.push_back(bb.h[i]);
    sg.push_back(fitting::h1_sigma(bb.h[i], bb.coherence[i], bb.segments));
  }
  if (ff.size() < 4)
    throw InputError(fmt::format("only {} frequency points have coherence >= {}; lower --min-coherence or excite "
                                 "more",
                                 ff.size(), a.min_coherence),
                     a.file);
  const std::string gain_unit = o.output_unit + "/(" + o.input_unit + ")";
  freq_located(a.file, [&] { o.tf_fit = fitting::fit_tf_frf(ff, hh, sg, *st, gain_unit); });
  o.tf_points_used = ff.size();
  for (const auto& w : o.tf_fit->warnings) o.warnings.push_back("tf fit: " + w);
  if (o.mode != FreqMode::oe) return;
  const double dt = 1.0 / bb.sample_rate_hz;
  freq_located(a.file, [&] {
    o.oe_fit = fitting::fit_tf_output_error(u, y, dt, *st, *o.tf_fit, gain_unit, {}, a.inter_sample);
  });
  for (const auto& w : o.oe_fit->warnings) o.warnings.push_back("output-error fit: " + w);
}

}  // namespace

std::string freq_mode_name(FreqMode mode) {
  switch (mode) {
    case FreqMode::automatic: return "auto";
    case FreqMode::dwell: return "dwell";
    case FreqMode::h1: return "h1";
    case FreqMode::oe: return "oe";
  }
  return "?";
}

namespace {

// The broadband analyses (h1, oe) of the record from its first analysed sample on: the H1
// estimate, then the fits. o has the table's units; table holds the columns.
void freq_broadband(FreqOutcome& o, const FreqOptions& a, const formats::CsvTable& table) {
  const std::string mode = freq_mode_name(o.mode);
  if (a.input_column.empty()) throw InputError("--mode " + mode + " needs the input column: --input COL");
  const auto& t_all = table.column(table.time_column).values;
  const auto& u_all = table.column(a.input_column).values;
  const auto first = static_cast<std::ptrdiff_t>(analysis_first(t_all, u_all, a));
  const std::vector<double> t(t_all.begin() + first, t_all.end());
  const std::vector<double> u(u_all.begin() + first, u_all.end());
  const std::vector<double> y(table.column(a.output_column).values.begin() + first,
                              table.column(a.output_column).values.end());
  if (t.size() < 16)
    throw InputError(fmt::format("too few samples ({}) for a spectral estimate from {:g} s on", t.size(),
                                 t.empty() ? t_all.back() : t.front()),
                     a.file);
  for (const auto* col : {&u, &y}) {
    const auto [lo, hi] = std::minmax_element(col->begin(), col->end());
    if (!(*hi > *lo))
      throw InputError(std::string(col == &u ? "the input" : "the output") + " column is constant", a.file);
  }
  const double fs = uniform_rate(t, a.file);
  FreqBroadband bb;
  bb.start_s = t.front();
  ident::WelchOptions wo;
  freq_located(a.file, [&] { size_from_band(a, u, fs, wo, bb); });
  ident::FrequencyResponse fr;
  freq_located(a.file, [&] { fr = ident::h1_estimate(u, y, fs, wo); });
  bb.sample_rate_hz = fs;
  bb.segment_length = wo.segment_length;
  bb.segments = fr.segments;
  for (std::size_t i = 0; i < fr.freq_hz.size(); ++i) {
    if (fr.freq_hz[i] <= 0 || fr.freq_hz[i] < a.fmin_hz || fr.freq_hz[i] > bb.fmax_hz) continue;
    bb.freq_hz.push_back(fr.freq_hz[i]);
    bb.h.push_back(fr.h[i]);
    bb.coherence.push_back(fr.coherence[i]);
  }
  if (bb.freq_hz.empty()) throw InputError("no frequency bins inside --fmin/--fmax", a.file);
  o.broadband = bb;
  freq_fits(o, a, u, y);
}

// The sine dwell at the known frequency (any sampling).
void freq_dwell(FreqOutcome& o, const FreqOptions& a, const formats::CsvTable& table) {
  if (!(a.freq_hz > 0)) throw InputError("sine dwell needs the excitation frequency: --freq-hz F (Hz)");
  if (!a.fit_tf.empty()) throw InputError("--fit-tf needs broadband data: use --mode h1 or --mode oe");
  const auto& t_all = table.column(table.time_column).values;
  const auto& ycol = table.column(a.output_column);
  freq_located(a.file, [&] {
    o.dwell =
        ident::sine_dwell(t_all, ycol.values, a.freq_hz,
                          a.input_column.empty() ? std::span<const double>() : table.column(a.input_column).values,
                          o.output_unit, o.input_unit);
  });
  for (const auto& w : o.dwell->output.warnings) o.warnings.push_back("output: " + w);
  if (o.dwell->input)
    for (const auto& w : o.dwell->input->warnings) o.warnings.push_back("input: " + w);
}

// The whole-record model beside the per-frequency results, fitted to the record from --tmin on
// (without --tmin: from where the frequency response is analysed, the excitation's onset, when
// there is one, else all of it; the model starts from any state, V0 is one of its parameters, but
// a record that starts from rest begins at flows below any the excitation reaches).
void freq_whole_record(FreqOutcome& o, const FreqOptions& a, const formats::CsvTable& table) {
  if (a.input_column.empty()) {
    o.whole_record.error = "the record has no input column (--input COL), and the model is driven by the input";
    o.warnings.push_back("whole-record model not fitted: " + o.whole_record.error);
    return;
  }
  const std::span<const double> t = table.column(table.time_column).values;
  const std::optional<double> from = a.tmin_s      ? a.tmin_s
                                     : o.broadband ? std::optional(o.broadband->start_s)
                                                   : std::nullopt;
  const std::size_t first =
      from ? static_cast<std::size_t>(std::lower_bound(t.begin(), t.end(), *from) - t.begin()) : 0;
  const std::span<const double> u = table.column(a.input_column).values;
  const std::span<const double> y = table.column(a.output_column).values;
  std::optional<InputFile> track_file;
  if (const std::string path = feed_track_for(a.feed_track, a.file); !path.empty()) {
    track_file = InputFile::read(path);
    o.feed_track_input = track_file->digest();
  }
  const auto track = aligned_feed_track(track_file ? &*track_file : nullptr, t, u);  // on the whole record
  o.whole_record =
      ident::fit_whole_record(t.subspan(first), u.subspan(first), y.subspan(first), o.input_unit, o.output_unit,
                              nullptr, a.profile_intervals, o.warnings, track ? &*track : nullptr);
}

}  // namespace

FreqOutcome compute_freq(const FreqOptions& a) {
  FreqOutcome o;
  o.options = a;
  o.mode = resolved_mode(a);
  const InputFile file = InputFile::read(a.file);
  const std::string_view bytes = file.bytes();
  formats::CsvOptions copt;
  copt.columns = {a.output_column};
  if (!a.input_column.empty()) copt.columns.push_back(a.input_column);
  copt.time_column = a.time_column;
  copt.find_time_column = a.time_column.empty();
  const auto table = formats::parse_csv(bytes, a.file, copt);
  o.time_column = table.time_column;
  o.input_sha256 = file.digest().sha256;
  o.input_size_bytes = bytes.size();
  const auto& t_all = table.column(table.time_column).values;
  o.samples = t_all.size();
  const auto& ycol = table.column(a.output_column);
  o.output_unit = unit_or_1(a.output_unit.empty() ? ycol.unit : a.output_unit);
  o.input_unit = a.input_column.empty() ? "1" : unit_or_1(table.column(a.input_column).unit);
  if (!a.input_unit.empty()) o.input_unit = a.input_unit;
  if (formats::is_volumetric_flow_unit(o.input_unit)) o.input_unit = "mm^3/s";
  o.warnings = table.warnings;
  if (!a.input_column.empty()) {
    const auto& u = table.column(a.input_column).values;
    if (!u.empty()) {
      const auto [lo, hi] = std::minmax_element(u.begin(), u.end());
      o.input_min = *lo;
      o.input_max = *hi;
      o.input_mean = std::accumulate(u.begin(), u.end(), 0.0) / static_cast<double>(u.size());
    }
  }

  if (o.mode == FreqMode::dwell) freq_dwell(o, a, table);
  else freq_broadband(o, a, table);
  freq_whole_record(o, a, table);
  return o;
}

BodeCurve measured_bode(const FreqOutcome& o) {
  if (!o.broadband) return {};
  return bode_curve(o.broadband->freq_hz, o.broadband->h);
}

std::optional<BodeCurve> reported_fit_bode(const FreqOutcome& o) {
  const fitting::FitResult* fit = o.reported_fit();
  if (fit == nullptr || !o.broadband) return std::nullopt;
  const auto& f = o.broadband->freq_hz;
  return bode_curve(f, freq_model_response(o.structure, *fit, f));
}

const fitting::FitResult* FreqOutcome::reported_fit() const {
  if (oe_fit) return &*oe_fit;
  return tf_fit ? &*tf_fit : nullptr;
}

std::string FreqOutcome::reported_fit_key() const { return oe_fit ? "tf_oe_fit" : "tf_fit"; }

std::string FreqOutcome::reported_fit_method() const {
  return oe_fit ? "output-error fit to the record" : "fit to the H1 frequency response";
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
                   {"intersample", fitting::to_string(a.inter_sample)},
                   {"segment", a.welch.segment_length},
                   {"window", ident::to_string(a.welch.window)},
                   {"fmin_hz", a.fmin_hz},
                   {"fmax_hz", a.fmax_hz},
                   {"tmin_s", a.tmin_s ? nlohmann::json(*a.tmin_s) : nlohmann::json(nullptr)},
                   {"min_coherence", a.min_coherence},
                   {"profile_intervals", a.profile_intervals}});
  env.add_input_digest(a.file, o.input_sha256, o.input_size_bytes);
  for (const auto& w : o.warnings) env.warn(w);
  auto& res = env.results();
  if (std::isfinite(o.input_mean))
    res["input_range"] = {{"min", o.input_min}, {"max", o.input_max}, {"mean", o.input_mean}, {"unit", o.input_unit}};
  if (o.dwell) res["sine_dwell"] = ident::to_json(*o.dwell);
  if (o.broadband) {
    const auto& bb = *o.broadband;
    res["h1"] = {{"sample_rate_hz", bb.sample_rate_hz},
                 {"segment_length", bb.segment_length},
                 {"segments", bb.segments},
                 {"window", ident::to_string(a.welch.window)},
                 {"start_s", bb.start_s},
                 {"fmax_hz", bb.fmax_hz},
                 {"bode", bode_json(bb.freq_hz, bb.h, &bb.coherence)}};
    if (bb.excited.hi_hz > 0) res["h1"]["excited_band_hz"] = {bb.excited.lo_hz, bb.excited.hi_hz};
    if (o.tf_fit) {
      res["tf_fit"] = fitting::to_json(*o.tf_fit);
      res["tf_fit"]["points_used"] = o.tf_points_used;
      res["tf_fit"]["weighting"] = "1/sigma from coherence: sigma = |H| sqrt((1-g2)/(2 n_segments g2))";
      res["tf_fit"]["bode"] = bode_json(bb.freq_hz, freq_model_response(o.structure, *o.tf_fit, bb.freq_hz), nullptr);
    }
    if (o.oe_fit) {
      res["tf_oe_fit"] = fitting::to_json(*o.oe_fit);
      res["tf_oe_fit"]["bode"] =
          bode_json(bb.freq_hz, freq_model_response(o.structure, *o.oe_fit, bb.freq_hz), nullptr);
    }
    if (const auto* fit = o.reported_fit()) {
      // The one model this analysis reports (its parameters are the frequency-response tau,
      // theta and K that the report, history and export read); the full result, with its
      // model's Bode data, is under `source`.
      res["fit"] = fitting::to_json(*fit);
      res["fit"]["source"] = o.reported_fit_key();
      res["fit"]["method"] = o.reported_fit_method();
    }
  }
  add_whole_record(env, o.whole_record);
  return env;
}

namespace {

void print_dwell(const FreqOutcome& o, std::ostream& os) {
  const auto& sd = *o.dwell;
  auto line = [&](const char* what, const fitting::FitResult& f, const std::string& unit) {
    os << fmt::format("  {:<7} amplitude {:.4g} +- {:.2g} {}  phase {:.2f} +- {:.2f} deg  offset {:.4g} {}\n", what,
                      f.value("amplitude"), f.param("amplitude").std_error, unit, f.value("phase_deg"),
                      f.param("phase_deg").std_error, f.value("offset"), unit);
  };
  os << fmt::format("{}: sine dwell at {:.6g} Hz, {} samples\n", o.options.file, o.options.freq_hz, o.samples);
  line("output", sd.output, o.output_unit);
  if (sd.input) {
    line("input", *sd.input, o.input_unit);
    os << fmt::format("  gain {:.4g} +- {:.2g}   phase lag {:.2f} +- {:.2f} deg (positive: output lags)\n",
                      sd.gain.value, sd.gain.std_error, sd.phase_lag_deg.value, sd.phase_lag_deg.std_error);
  }
}

void print_broadband(const FreqOutcome& o, std::ostream& os) {
  const auto& bb = *o.broadband;
  os << fmt::format("{}: H1 estimate, {:.6g} Hz sampling, {} segments of {} samples, {} bins {:.4g}-{:.4g} Hz\n",
                    o.options.file, bb.sample_rate_hz, bb.segments, bb.segment_length, bb.freq_hz.size(),
                    bb.freq_hz.front(), bb.freq_hz.back());
  auto print_fit = [&](const char* label, const fitting::FitResult& r) {
    os << fmt::format("  {} {}:", label, r.model);
    for (const auto& p : r.params) os << fmt::format("  {} = {:.5g} +- {:.2g}", p.name, p.value, p.std_error);
    os << fmt::format("   r2 {:.4f}\n", r.diagnostics.r2);
  };
  if (o.tf_fit) print_fit("frequency-domain fit", *o.tf_fit);
  if (o.oe_fit) print_fit("output-error fit", *o.oe_fit);
  if (o.reported_fit() != nullptr)
    os << fmt::format("  reported: the {} (from {:.4g} s, up to {:.4g} Hz)\n",
                      o.oe_fit ? "output-error fit" : "frequency-domain fit", bb.start_s, bb.fmax_hz);
}

}  // namespace

void print_text(const FreqOutcome& o, std::ostream& os) {
  if (o.dwell) print_dwell(o, os);
  else if (o.broadband) print_broadband(o, os);
  // Its tau at the mean input: the operating point the frequency response linearises about.
  print_whole_record(os, o.whole_record, o.input_mean);
}

}  // namespace tunekit::calibration
