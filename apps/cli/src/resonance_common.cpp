#include "resonance_common.hpp"

#include <algorithm>
#include <cmath>
#include <future>
#include <map>
#include <filesystem>
#include <numbers>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/ident/csv.hpp"
#include "tunekit/ident/klipper_spectrum.hpp"
#include "tunekit/ident/rrf_accelerometer.hpp"
#include "tunekit/ident/shaketune_stdata.hpp"

namespace tunekit::cli {
namespace {

ident::Detrend parse_detrend(const std::string& s) {
  if (ident::iequals(s, "none")) return ident::Detrend::none;
  if (ident::iequals(s, "constant") || ident::iequals(s, "mean")) return ident::Detrend::constant;
  if (ident::iequals(s, "linear")) return ident::Detrend::linear;
  throw InputError("unknown detrend '" + s + "' (none, constant, linear)");
}

char parse_axis(const std::string& s) {
  if (s.empty()) return 0;
  if (s.size() == 1 && (s[0] == 'x' || s[0] == 'y' || s[0] == 'z' || s[0] == 'X' || s[0] == 'Y' || s[0] == 'Z'))
    return static_cast<char>(std::tolower(static_cast<unsigned char>(s[0])));
  throw InputError("--axis must be x, y or z, not '" + s + "'");
}

std::vector<double> two(double a, double b) { return {a, b}; }

}  // namespace

std::string klipper_files_help() {
  return "Feeding Klipper's files:\n"
         "  Raw accelerometer data (TEST_RESONANCES AXIS=X OUTPUT=raw_data, or ACCELEROMETER_MEASURE) is written as\n"
         "  /tmp/raw_data_x_<name>.csv with the header '#time,accel_x,accel_y,accel_z' (s, mm/s^2). Pass one or more\n"
         "  of them; the axis comes from 'raw_data_x_' / 'raw_data_y_' in the name (or --axis), several files of one\n"
         "  axis are averaged for the modes (for the shaper, each counts separately, as in Klipper's calibrate_shaper.py).\n"
         "  Klipper's spectrum files are read as its calibrate_shaper.py reads them: TEST_RESONANCES' resonances_x_<name>.csv\n"
         "  and SHAPER_CALIBRATE's calibration_data_x_<name>.csv (freq,psd_x,psd_y,psd_z,psd_xyz), or several datasets\n"
         "  (freq,<name>,<name>...). Without 'shapers:' columns the PSD is as measured and gets Klipper's normalization\n"
         "  (divided by f + 0.1 Hz, damped below 10 Hz) before a shaper is chosen; with them it already has it.\n"
         "  Shake&Tune's measurement files (ShakeTune_results/*/<name>.stdata: Zstandard-compressed JSON lines of\n"
         "  [t, accel_x, accel_y, accel_z] samples) are read directly; an input-shaper measurement (axis_X_...) gives its\n"
         "  axis, any other measurement is reported under its name.\n"
         "Feeding RepRapFirmware's files:\n"
         "  M956 P0 S<samples> A0 X Y Z F\"raw_data_x_run1.csv\" writes 0:/sys/accelerometer/<name>.csv: 'Sample,X,Y,Z', rows of\n"
         "  g, and a last line 'Rate <Hz>, overflows <n>' that gives the time base. Name the file raw_data_<axis>_*.csv\n"
         "  in M956 (or pass --axis).\n"
         "  Other loggers: --time COL --accel COL [--accel COL...] (mm/s^2); a commanded-acceleration column\n"
         "  --excitation COL adds the frequency response H1 and coherence, and the modes are fitted to it.\n";
}

void add_resonance_options(CLI::App* sub, ResonanceCliArgs& a) {
  sub->add_option("files", a.files,
                  "Accelerometer CSVs: Klipper raw_data_<axis>_*.csv (#time,accel_x,accel_y,accel_z in s and mm/s^2), "
                  "Klipper spectrum files (resonances_<axis>_*.csv, calibration_data_<axis>_*.csv), Shake&Tune .stdata "
                  "files, or generic CSVs "
                  "with --time/--accel")
      ->required();
  sub->add_option("--axis", a.axis,
                  "Axis of every file: x, y or z (default: from the Klipper file name; a file whose name names no "
                  "axis is reported under its file stem, and needs --axis only to be exported)");
  sub->add_option("--time", a.time_column, "Time column (s), strictly increasing (default: time)");
  sub->add_option("--accel", a.accel_columns,
                  "Acceleration column(s) in mm/s^2, PSDs summed over them (default: accel_x accel_y accel_z)");
  sub->add_option("--excitation", a.excitation_column,
                  "Commanded-acceleration column (mm/s^2): adds the H1 frequency response and coherence, and the modes "
                  "are fitted to the FRF");
  sub->add_option("--window", a.window, "Welch window: kaiser (default, Klipper), hann, hamming, rect");
  sub->add_option("--kaiser-beta", a.kaiser_beta, "Kaiser window beta (dimensionless, default 6 as Klipper)");
  sub->add_option("--segment", a.segment,
                  "Welch segment length in samples (default 2^ceil(log2(fs * 0.5 s)), Klipper's choice)");
  sub->add_option("--overlap", a.overlap, "Welch segment overlap, fraction 0..0.95 (default 0.5)");
  sub->add_option("--detrend", a.detrend, "Per-segment detrending: constant (default, Klipper), linear, none");
  sub->add_option("--fit-min", a.fit_min_hz, "Lowest frequency searched for modes, Hz (default 10)");
  sub->add_option("--fit-max", a.fit_max_hz,
                  "Highest frequency searched for modes, Hz (default 133.33, where Klipper's sweep ends)");
  sub->add_option("--max-modes", a.max_modes, "Most modes fitted per axis (default 3)");
  sub->add_option("--peak-threshold", a.peak_threshold,
                  "Ignore peaks lower than this fraction of the highest (whitened PSD), 0..1 (default 0.05)");
  sub->add_option("--excitation-exponent", a.excitation_exponent,
                  "p in the excitation spectrum shape f^p (dimensionless; default 2 for raw sweeps with amplitude "
                  "accel_per_hz*f, 1 for spectra Klipper normalized)");
  sub->add_option("--full-scale", a.full_scale_mm_s2,
                  "Accelerometer range in mm/s^2 for clipping detection (default: detect flat-topped extremes; "
                  "ADXL345 at +-16 g is 156906)");
  sub->add_option("--plot-max", a.max_plot_hz, "Highest frequency of the PSD arrays in the JSON, Hz (default 200)");
  sub->add_flag("--no-frf", a.no_frf, "Fit the PSD even when an excitation column gives the FRF");
  add_output_options(sub, a.output);
}

nlohmann::json resonance_options_json(const ResonanceCliArgs& a) {
  return {{"axis", a.axis},
          {"time_column", a.time_column},
          {"accel_columns", a.accel_columns},
          {"excitation_column", a.excitation_column},
          {"window", a.window},
          {"kaiser_beta", a.kaiser_beta},
          {"segment", a.segment},
          {"overlap", a.overlap},
          {"detrend", a.detrend},
          {"fit_min_hz", a.fit_min_hz},
          {"fit_max_hz", a.fit_max_hz},
          {"max_modes", a.max_modes},
          {"peak_threshold", a.peak_threshold},
          {"excitation_exponent", a.excitation_exponent},
          {"full_scale_mm_s2", a.full_scale_mm_s2},
          {"no_frf", a.no_frf},
          {"ringdown", a.ringdown},
          {"channel", a.ringdown_channel},
          {"min_strength", a.min_strength},
          {"ringdown_min_hz", a.ringdown_min_hz},
          {"ringdown_max_hz", a.ringdown_max_hz}};
}

std::string record_label(char axis, const std::string& path) {
  if (axis != 0) return std::string(1, axis);
  return std::filesystem::path(path).stem().string();
}

ident::RingdownOptions ringdown_options(const ResonanceCliArgs& a) {
  ident::RingdownOptions o;
  o.channel = a.ringdown_channel;
  o.min_strength = a.min_strength;
  o.min_hz = a.ringdown_min_hz;
  o.max_hz = a.ringdown_max_hz;
  if (!(o.min_strength > 0)) throw InputError("--min-strength must be positive");
  return o;
}

void add_ringdown_options(CLI::App* sub, ResonanceCliArgs& a, bool with_flag) {
  if (with_flag)
    sub->add_flag("--ringdown", a.ringdown,
                  "Analyse each file as a free decay (a plucked belt, a tapped toolhead): fundamental frequency and "
                  "damping ratio from a time-domain fit of damped sinusoids. Chosen automatically for a record too "
                  "short for Welch's method");
  sub->add_option("--channel", a.ringdown_channel, "Ring-down: analyse this channel (default: the strongest)");
  sub->add_option("--min-strength", a.min_strength,
                  "Ring-down: refuse a record whose decay RMS is below this multiple of the noise floor (default 3)");
  sub->add_option("--ringdown-min", a.ringdown_min_hz,
                  fmt::format("Ring-down: lowest fundamental considered, Hz (default {:g})", a.ringdown_min_hz));
  sub->add_option("--ringdown-max", a.ringdown_max_hz,
                  a.ringdown_max_hz > 0
                      ? fmt::format("Ring-down: highest line considered, Hz (default {:g})", a.ringdown_max_hz)
                      : std::string("Ring-down: highest line considered, Hz (default 0.45 x the sample rate)"));
}

std::vector<AxisResult> run_resonance_pipeline(const ResonanceCliArgs& a, Envelope& env,
                                               std::vector<ident::AccelRecord>* ringdown_records) {
  ident::WelchOptions welch = ident::klipper_welch_options();
  welch.window = ident::parse_window(a.window);
  welch.kaiser_beta = a.kaiser_beta;
  welch.segment_length = a.segment;
  if (!(a.overlap >= 0 && a.overlap <= 0.95)) throw InputError(fmt::format("--overlap {} must be in [0, 0.95]", a.overlap));
  welch.overlap = a.overlap;
  welch.detrend = parse_detrend(a.detrend);
  if (!(a.fit_max_hz > a.fit_min_hz) || !(a.fit_min_hz >= 0))
    throw InputError(fmt::format("--fit-min {} Hz must be below --fit-max {} Hz", a.fit_min_hz, a.fit_max_hz));
  if (a.max_modes < 1) throw InputError("--max-modes must be at least 1");
  if (!(a.peak_threshold > 0 && a.peak_threshold < 1)) throw InputError("--peak-threshold must be in (0, 1)");

  ident::AccelInputOptions in;
  in.time_column = a.time_column;
  in.accel_columns = a.accel_columns;
  in.excitation_column = a.excitation_column;
  in.axis = parse_axis(a.axis);
  in.full_scale_mm_s2 = a.full_scale_mm_s2;

  std::map<std::string, std::vector<ident::AxisSpectrum>> by_axis;
  for (const auto& path : a.files) {
    const std::string bytes = ident::read_file_bytes(path);
    // The input's digest (tens of ms for a 20 MB raw file) is computed on a second core while
    // the file is parsed and its spectrum estimated.
    auto digest = std::async(std::launch::async, [&bytes] { return sha256_hex(bytes); });
    std::vector<ident::AxisSpectrum> file_spectra;
    if (ident::is_klipper_spectrum(bytes)) {
      // Klipper's spectrum files: one or several datasets; measured PSDs unless the file has
      // shaper columns (then Klipper normalized them before writing).
      file_spectra = std::move(ident::read_klipper_spectrum(path, bytes, in.axis).datasets);
    } else if (ident::is_shaketune_stdata(bytes)) {
      // Shake&Tune's .stdata: every measurement is a record; one without an axis in its name
      // (a belt, a vibration run) is its own group under its measurement name.
      for (auto& m : ident::load_shaketune_stdata(path, bytes, in)) {
        auto s = ident::record_spectrum(m.record, welch);
        by_axis[m.record.axis != 0 ? std::string(1, m.record.axis) : m.name].push_back(std::move(s));
      }
      env.add_input_digest(path, digest.get(), bytes.size());
      continue;
    } else if (ident::is_rrf_accelerometer_csv(bytes)) {
      file_spectra.push_back(ident::record_spectrum(ident::load_rrf_accelerometer_csv(path, bytes, in), welch));
    } else {
      auto rec = ident::load_accel_csv(path, bytes, in);
      if (ringdown_records &&
          (a.ringdown || rec.sampling.samples < 2 * ident::resolve_segment_length(welch, rec.sampling.sample_rate_hz))) {
        if (!a.ringdown)
          env.warn(fmt::format("{}: {:.3f} s at {:.0f} Hz is too short for Welch's method; analysed as a ring-down",
                               path, rec.sampling.duration_s, rec.sampling.sample_rate_hz));
        env.add_input_digest(path, digest.get(), bytes.size());
        ringdown_records->push_back(std::move(rec));
        continue;
      }
      file_spectra.push_back(ident::record_spectrum(rec, welch));
    }
    env.add_input_digest(path, digest.get(), bytes.size());
    for (auto& s : file_spectra) by_axis[record_label(s.axis, path)].push_back(std::move(s));
  }
  ident::ResonanceOptions ro;
  ro.fit_min_hz = a.fit_min_hz;
  ro.fit_max_hz = a.fit_max_hz;
  ro.max_modes = a.max_modes;
  ro.peak_threshold = a.peak_threshold;
  ro.excitation_exponent = a.excitation_exponent;
  ro.use_frf = !a.no_frf;
  std::vector<AxisResult> out;
  for (auto& [label, spectra] : by_axis) {
    // Spectra Klipper normalized (files with shaper columns) and measured ones (raw data, files
    // without them) of one axis are brought to Klipper's normalization before they are averaged,
    // as calibrate_shaper.py does; the datasets are kept as read.
    AxisResult r;
    r.axis = spectra.front().axis;
    r.label = label;
    const std::string& axis = label;
    const bool any_normalized = std::any_of(spectra.begin(), spectra.end(), [](const auto& s) { return s.klipper_normalized; });
    const bool all_normalized = std::all_of(spectra.begin(), spectra.end(), [](const auto& s) { return s.klipper_normalized; });
    if (any_normalized && !all_normalized) {
      std::vector<ident::AxisSpectrum> same = spectra;
      for (auto& s : same)
        if (!s.klipper_normalized) {
          for (auto* p : {&s.psd_sum, &s.psd_x, &s.psd_y, &s.psd_z})
            if (!p->empty()) *p = ident::klipper_normalize(s.freq_hz, *p);
          s.klipper_normalized = true;
        }
      r.spectrum = ident::average_spectra(same);
    } else {
      r.spectrum = ident::average_spectra(spectra);
    }
    r.datasets = std::move(spectra);
    for (const auto& w : r.spectrum.warnings) env.warn(w);
    r.modes = ident::identify_modes(r.spectrum, ro);
    for (const auto& w : r.modes.warnings) env.warn(fmt::format("axis {}: {}", axis, w));
    out.push_back(std::move(r));
  }
  return out;
}

nlohmann::json modes_json(const ident::AxisModes& m) {
  nlohmann::json arr = nlohmann::json::array();
  for (const auto& e : m.modes)
    arr.push_back({{"freq_hz", e.freq_hz},
                   {"zeta", e.zeta},
                   {"freq_ci95", two(e.freq_ci95_lo, e.freq_ci95_hi)},
                   {"zeta_ci95", two(e.zeta_ci95_lo, e.zeta_ci95_hi)},
                   {"freq_stderr_hz", e.freq_stderr_hz},
                   {"zeta_stderr", e.zeta_stderr},
                   {"gain", e.gain}});
  return arr;
}

nlohmann::json spectrum_json(const ident::AxisSpectrum& s, double max_hz) {
  nlohmann::json j;
  std::vector<double> f, p, px, py, pz;
  for (std::size_t b = 0; b < s.freq_hz.size(); ++b) {
    if (s.freq_hz[b] > max_hz) break;
    f.push_back(s.freq_hz[b]);
    p.push_back(s.psd_sum[b]);
    if (!s.psd_x.empty()) px.push_back(s.psd_x[b]);
    if (!s.psd_y.empty()) py.push_back(s.psd_y[b]);
    if (!s.psd_z.empty()) pz.push_back(s.psd_z[b]);
  }
  j["freq_hz"] = f;
  j["psd"] = p;
  if (!px.empty()) j["psd_x"] = px;
  if (!py.empty()) j["psd_y"] = py;
  if (!pz.empty()) j["psd_z"] = pz;
  j["unit"] = s.klipper_normalized ? "(mm/s^2)^2/Hz/Hz (Klipper-normalized)" : "(mm/s^2)^2/Hz";
  j["klipper_normalized"] = s.klipper_normalized;
  j["window"] = ident::to_string(s.welch.window);
  j["segment_length"] = s.segment_length;
  j["segments"] = s.segments;
  j["sample_rate_hz"] = s.sample_rate_hz;
  j["resolution_hz"] = s.segment_length > 0 ? s.sample_rate_hz / static_cast<double>(s.segment_length) : 0.0;
  j["files"] = s.files;
  if (s.frf && s.frf->h.size() >= f.size()) {
    std::vector<double> mag, ph, coh;
    for (std::size_t b = 0; b < f.size(); ++b) {
      mag.push_back(std::abs(s.frf->h[b]));
      ph.push_back(std::arg(s.frf->h[b]) * 180.0 / std::numbers::pi);
      coh.push_back(s.frf->coherence[b]);
    }
    j["frf"] = {{"freq_hz", f}, {"magnitude", mag}, {"phase_deg", ph}, {"coherence", coh}};
  }
  return j;
}

nlohmann::json fit_json(const ident::AxisModes& m) {
  nlohmann::json j;
  j["method"] = m.method.empty() ? "none" : m.method;
  j["band_hz"] = two(m.band_lo_hz, m.band_hi_hz);
  nlohmann::json peaks = nlohmann::json::array();
  for (const auto& p : m.peaks) peaks.push_back({{"freq_hz", p.freq_hz}, {"half_power_zeta", p.half_power_zeta}});
  j["peaks"] = peaks;
  if (m.fit) {
    j["diagnostics"] = fitting::to_json(m.fit->fit.diagnostics);
    j["variance_inflation"] = m.fit->variance_inflation;
    j["direct_term"] = m.fit->direct_term;
    if (m.method == "psd") j["noise_floor"] = m.fit->noise_floor;
  }
  j["dominant_mode"] = m.dominant;
  return j;
}

}  // namespace tunekit::cli
