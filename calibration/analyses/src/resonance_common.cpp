// The accelerometer pipeline `tunekit resonance` and `tunekit shaper` share: files -> per-axis
// Welch spectra -> modes (tunekit/calibration/analyses/resonance_common.hpp).
#include "tunekit/calibration/analyses/resonance_common.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <future>
#include <map>
#include <memory>

#include <fmt/format.h>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/text.hpp"
#include "tunekit/ident/axis_response_fit.hpp"
#include "tunekit/ident/commanded_motion.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/ident/klipper_spectrum.hpp"
#include "tunekit/ident/rrf_accelerometer.hpp"
#include "tunekit/ident/shaketune_stdata.hpp"
#include "tunekit/core/file_bytes.hpp"

namespace tunekit::calibration {

std::string detrend_name(ident::Detrend d) {
  switch (d) {
    case ident::Detrend::none: return "none";
    case ident::Detrend::constant: return "constant";
    case ident::Detrend::linear: return "linear";
  }
  return "?";
}

ident::Detrend parse_detrend_name(const std::string& s) {
  if (core::iequals(s, "none")) return ident::Detrend::none;
  if (core::iequals(s, "constant") || core::iequals(s, "mean")) return ident::Detrend::constant;
  if (core::iequals(s, "linear")) return ident::Detrend::linear;
  throw InputError("unknown detrend '" + s + "' (none, constant, linear)");
}

char parse_axis_name(const std::string& s) {
  if (s.empty()) return 0;
  if (s.size() == 1 && (s[0] == 'x' || s[0] == 'y' || s[0] == 'z' || s[0] == 'X' || s[0] == 'Y' || s[0] == 'Z'))
    return static_cast<char>(std::tolower(static_cast<unsigned char>(s[0])));
  throw InputError("--axis must be x, y or z, not '" + s + "'");
}

std::string record_label(char axis, const std::string& path) {
  if (axis != 0) return std::string(1, axis);
  return std::filesystem::path(path).stem().string();
}

namespace {

/// A raw record whose commanded motion was recorded beside it, and the output-error fit's input
/// from them, prepared on another core while the record's modes are identified.
struct TimedRecord {
  ident::AccelRecord record;
  std::future<ident::AxisResponseInput> input;
  /// A record of refine_files: a sweep over the dominant mode's band only, which cannot tell the
  /// spectrum's other modes; it refines the dominant one, the others stay the spectrum's.
  bool dominant_band = false;
};

/// `m`'s modes refined by the fit of `t` against its motion: all of them, or with
/// t.dominant_band the dominant one alone (the others as the spectrum found them).
void refine_modes(ident::AxisModes& m, TimedRecord& t) {
  if (!t.dominant_band || m.modes.size() <= 1 || m.dominant < 0) {
    ident::refine_modes_with_motion(m, t.input);
    return;
  }
  ident::AxisModes one = m;
  one.modes = {m.modes[static_cast<std::size_t>(m.dominant)]};
  one.dominant = 0;
  one.warnings.clear();
  ident::refine_modes_with_motion(one, t.input);
  for (const auto& w : one.warnings) m.warnings.push_back(w);
  if (one.method != "output_error") return;
  m.modes[static_cast<std::size_t>(m.dominant)] = one.modes.front();
  const double f = one.modes.front().freq_hz;
  std::sort(m.modes.begin(), m.modes.end(), [](const auto& a, const auto& b) { return a.freq_hz < b.freq_hz; });
  for (std::size_t k = 0; k < m.modes.size(); ++k)
    if (m.modes[k].freq_hz == f) m.dominant = static_cast<int>(k);
  m.method = one.method;
  m.time_fit = std::move(one.time_fit);
  m.time_fit_variance_inflation = one.time_fit_variance_inflation;
}

// InputError for Welch and mode options outside their ranges (named as the command line names them).
void check_accel_options(const ident::WelchOptions& welch, const ident::ResonanceOptions& ro) {
  if (!(welch.overlap >= 0 && welch.overlap <= 0.95))
    throw InputError(fmt::format("--overlap {} must be in [0, 0.95]", welch.overlap));
  if (!(ro.fit_max_hz > ro.fit_min_hz) || !(ro.fit_min_hz >= 0))
    throw InputError(fmt::format("--fit-min {} Hz must be below --fit-max {} Hz", ro.fit_min_hz, ro.fit_max_hz));
  if (ro.max_modes < 1) throw InputError("--max-modes must be at least 1");
  if (!(ro.peak_threshold > 0 && ro.peak_threshold < 1)) throw InputError("--peak-threshold must be in (0, 1)");
}

// The axis `label`'s result from its spectra: averaged, its modes identified and refined with
// the commanded motion where a record has it; warnings into `warnings`.
AxisResult axis_result(const std::string& label, std::vector<ident::AxisSpectrum>& spectra,
                       const ident::ResonanceOptions& ro, std::map<std::string, TimedRecord>& timed,
                       std::vector<std::string>& warnings, const BesideModes& beside) {
  // Spectra Klipper normalized (files with shaper columns) and measured ones (raw data, files
  // without them) of one axis are brought to Klipper's normalization before they are averaged,
  // as calibrate_shaper.py does; the datasets are kept as read.
  AxisResult r;
  r.axis = spectra.front().axis;
  r.label = label;
  const bool any_normalized =
      std::any_of(spectra.begin(), spectra.end(), [](const auto& s) { return s.klipper_normalized; });
  const bool all_normalized =
      std::all_of(spectra.begin(), spectra.end(), [](const auto& s) { return s.klipper_normalized; });
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
  for (const auto& w : r.spectrum.warnings) warnings.push_back(w);
  // The future's destructor waits for `beside` when the mode fit throws.
  std::future<void> beside_done =
      beside ? std::async(std::launch::async, [&beside, &r] { beside(r); }) : std::future<void>{};
  r.modes = ident::identify_modes(r.spectrum, ro);
  if (const auto it = timed.find(label); it != timed.end()) refine_modes(r.modes, it->second);
  for (const auto& w : r.modes.warnings) warnings.push_back(fmt::format("axis {}: {}", label, w));
  if (beside_done.valid()) beside_done.wait();  // before r is moved to the caller
  return r;
}

/// A record of `refine_files` and its commanded motion, into `timed` (InputError when it has no
/// motion beside it or is not a raw record of x or y); both inputs recorded with their digests.
void load_refine_record(const std::string& path, const ident::AccelInputOptions& in, bool digest_inputs,
                        std::vector<std::unique_ptr<const formats::InputFileBytes>>& files,
                        std::vector<std::future<std::string>>& digests, std::map<std::string, TimedRecord>& timed,
                        AccelAnalysis& result) {
  const std::string motion = ident::commanded_motion_beside(path);
  if (motion.empty())
    throw InputError("a record that refines the modes needs its commanded motion beside it (commanded_motion.csv)",
                     path);
  for (const auto& p : {path, motion}) {
    files.push_back(std::make_unique<const formats::InputFileBytes>(p));
    const std::string_view bytes = files.back()->view();
    result.inputs.push_back({p, {}, bytes.size()});
    digests.push_back(digest_inputs ? std::async(std::launch::async, [bytes] { return sha256_hex(bytes); })
                                    : std::future<std::string>{});
  }
  auto rec = ident::load_accel_csv(path, files[files.size() - 2]->view(), in, [] {});
  if (rec.axis != 'x' && rec.axis != 'y') throw InputError("a record that refines the modes must be of x or y", path);
  auto pieces = ident::load_commanded_motion_csv(motion, files.back()->view(), rec.axis);
  const std::string label = record_label(rec.axis, path);
  auto input = ident::prepare_axis_response(rec, [pieces = std::move(pieces)] { return pieces; });
  timed.emplace(label, TimedRecord{std::move(rec), std::move(input), true});
}

/// The output-error fit's input from `rec` and its commanded motion (the CSV `path`, in `bytes`),
/// read and laid on the record's clock on another core (ident::prepare_axis_response); `read`
/// becomes ready when the file has been read, or holds the error that reading it raised.
std::future<ident::AxisResponseInput> read_motion_beside(const ident::AccelRecord& rec, const std::string& path,
                                                         std::string_view bytes, std::future<void>& read) {
  auto done = std::make_shared<std::promise<void>>();
  read = done->get_future();
  return ident::prepare_axis_response(rec, [done, path, bytes, axis = rec.axis] {
    try {
      auto pieces = ident::load_commanded_motion_csv(path, bytes, axis);
      done->set_value();
      return pieces;
    } catch (...) {
      done->set_exception(std::current_exception());
      throw;
    }
  });
}

}  // namespace

AccelAnalysis analyze_accel_files(const AccelFilesOptions& a, RingdownDiversion ringdown, const BesideModes& beside) {
  const ident::WelchOptions& welch = a.welch;
  const ident::ResonanceOptions& ro = a.modes;
  check_accel_options(welch, ro);
  const ident::AccelInputOptions& in = a.input;

  AccelAnalysis result;
  std::map<std::string, std::vector<ident::AxisSpectrum>> by_axis;
  std::map<std::string, TimedRecord> timed;  // raw records with their commanded motion, per axis
  // The inputs' digests (about 10 ms for a 20 MB raw file) are computed on another core while
  // the analysis goes on, and collected at the end; the files stay mapped until then.
  std::vector<std::unique_ptr<const formats::InputFileBytes>> files;
  std::vector<std::future<std::string>> digests;
  // The records that refine their axis' modes first: the first record of a label with its motion wins.
  for (const auto& path : a.refine_files) load_refine_record(path, in, a.digest_inputs, files, digests, timed, result);
  for (const auto& path : a.files) {
    // Mapped, not copied: a fresh 20 MB buffer costs more in page faults than the parse.
    files.push_back(std::make_unique<const formats::InputFileBytes>(path));
    const std::string_view bytes = files.back()->view();
    std::future<std::string> digest;
    auto start_digest = [&] {
      if (a.digest_inputs && !digest.valid())
        digest = std::async(std::launch::async, [bytes] { return sha256_hex(bytes); });
    };
    auto record_input = [&] {
      start_digest();
      result.inputs.push_back({path, {}, bytes.size()});
      digests.push_back(std::move(digest));
    };
    // A raw accelerometer CSV is parsed on both cores: its digest starts after the parse, beside
    // the record's checks.
    const bool raw_csv = !ident::is_klipper_spectrum(bytes) && !ident::is_shaketune_stdata(bytes) &&
                         !ident::is_rrf_accelerometer_csv(bytes);
    if (!raw_csv) start_digest();
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
      record_input();
      continue;
    } else if (ident::is_rrf_accelerometer_csv(bytes)) {
      file_spectra.push_back(ident::record_spectrum(ident::load_rrf_accelerometer_csv(path, bytes, in), welch));
    } else {
      auto rec = ident::load_accel_csv(path, bytes, in, start_digest);
      const bool too_short =
          rec.sampling.samples < 2 * ident::resolve_segment_length(welch, rec.sampling.sample_rate_hz);
      if (ringdown == RingdownDiversion::all || (ringdown == RingdownDiversion::too_short && too_short)) {
        if (ringdown != RingdownDiversion::all)
          result.warnings.push_back(
              fmt::format("{}: {:.3f} s at {:.0f} Hz is too short for Welch's method; analysed as "
                          "a ring-down",
                          path, rec.sampling.duration_s, rec.sampling.sample_rate_hz));
        record_input();
        result.ringdown_records.push_back(std::move(rec));
        continue;
      }
      // The commanded motion beside the record is read and laid on the record's clock on another
      // core while the spectrum is computed and its modes identified (a motion file that cannot
      // be read is still an error of the command).
      const std::string motion = ro.use_commanded_motion ? ident::commanded_motion_beside(path) : std::string{};
      const bool timed_axis =
          !motion.empty() && (rec.axis == 'x' || rec.axis == 'y') && !timed.count(record_label(rec.axis, path));
      std::string_view mbytes;
      std::future<void> motion_read;
      std::future<ident::AxisResponseInput> input;
      if (timed_axis) {
        files.push_back(std::make_unique<const formats::InputFileBytes>(motion));
        mbytes = files.back()->view();
        input = read_motion_beside(rec, motion, mbytes, motion_read);
      }
      file_spectra.push_back(ident::record_spectrum(rec, welch));
      record_input();
      if (timed_axis) {
        motion_read.get();  // a motion file that cannot be read is an error of the command
        result.inputs.push_back({motion, {}, mbytes.size()});
        digests.push_back(a.digest_inputs ? std::async(std::launch::async, [mbytes] { return sha256_hex(mbytes); })
                                          : std::future<std::string>{});
        timed.emplace(record_label(rec.axis, path), TimedRecord{std::move(rec), std::move(input)});
      }
      for (auto& s : file_spectra) by_axis[record_label(s.axis, path)].push_back(std::move(s));
      continue;
    }
    record_input();
    for (auto& s : file_spectra) by_axis[record_label(s.axis, path)].push_back(std::move(s));
  }
  for (auto& [label, spectra] : by_axis) {
    result.axes.push_back(axis_result(label, spectra, ro, timed, result.warnings, beside));
  }
  for (std::size_t i = 0; i < digests.size(); ++i)
    if (digests[i].valid()) result.inputs[i].sha256 = digests[i].get();
  return result;
}

}  // namespace tunekit::calibration
