#include "tunekit/ident/resonance.hpp"
#include "tunekit/fitting/interpolate.hpp"
#include "tunekit/fitting/stats.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <future>
#include <span>
#include <numbers>
#include <numeric>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/core/text.hpp"

namespace tunekit::ident {

using formats::CsvOptions;
using formats::CsvTable;
using formats::parse_csv;
namespace {

// Linear interpolation of (t, x) onto t0 + i dt, i < n.
std::vector<double> resample(const std::vector<double>& t, const std::vector<double>& x, double t0, double dt,
                             std::size_t n) {
  std::vector<double> y(n);
  for (std::size_t i = 0; i < n; ++i) y[i] = fitting::interp_linear(t, x, t0 + dt * static_cast<double>(i));
  return y;
}

// The smallest and largest value of a non-empty record without NaN. std::minmax_element
// branches on every comparison, which noisy data mispredicts about half the time; this takes
// a few times less on a 410k-sample channel.
std::pair<double, double> value_range(const std::vector<double>& v) {
  double lo = v.front(), hi = v.front();
  for (double x : v) {
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  }
  return {lo, hi};
}

// The extremes of a non-empty channel without NaN, how many samples sit on each and the longest
// run of consecutive samples there, in one pass over the channel: a new extreme restarts its
// counts. In a signal that is not clipped a sample is rarely at or beyond an extreme, so the two
// tests per sample are well-predicted branches.
struct Extremes {
  double value[2] = {0, 0};  // lowest, highest
  std::size_t count[2] = {0, 0}, longest[2] = {0, 0};
};

/// What one pass over an acceleration channel finds: its samples beyond `limit` (wild, not
/// physical) and its extremes.
struct ChannelScan {
  std::vector<std::size_t> wild;
  Extremes extremes;
};

ChannelScan scan_channel(const std::vector<double>& v, double limit) {
  ChannelScan s;
  Extremes& e = s.extremes;
  e.value[0] = e.value[1] = v.front();
  std::size_t run[2] = {0, 0}, last[2] = {0, 0};
  auto note = [&](int k, double x, std::size_t i) {
    if (x != e.value[k]) e.value[k] = x, e.count[k] = 0, e.longest[k] = 0;
    run[k] = e.count[k] > 0 && last[k] + 1 == i ? run[k] + 1 : 1;
    e.longest[k] = std::max(e.longest[k], run[k]);
    last[k] = i;
    ++e.count[k];
  };
  for (std::size_t i = 0; i < v.size(); ++i) {
    const double x = v[i];
    if (!(std::abs(x) <= limit)) s.wild.push_back(i);
    if (x <= e.value[0]) note(0, x, i);
    if (x >= e.value[1]) note(1, x, i);
  }
  return s;
}

// The extremes alone (of channels resampled or with samples replaced after their scan).
Extremes channel_extremes(const std::vector<double>& v) {
  return scan_channel(v, std::numeric_limits<double>::infinity()).extremes;
}

ClipReport detect_clipping(const std::string& name, const std::vector<double>& v, double full_scale,
                           const Extremes& e) {
  ClipReport c;
  c.channel = name;
  if (v.empty()) return c;
  if (full_scale > 0) {
    c.limit_mm_s2 = full_scale;
    for (double x : v)
      if (std::abs(x) >= 0.999 * full_scale) ++c.samples;
    return c;
  }
  // Without a declared range: the extremes are clipped when the signal sits flat on them
  // (three or more consecutive samples, or eight or more samples in all).
  if (!(e.value[1] > e.value[0])) return c;  // a constant channel carries no signal to clip
  for (int k = 0; k < 2; ++k)
    if (e.value[k] != 0 && (e.longest[k] >= 3 || e.count[k] >= 8)) {
      c.samples += e.count[k];
      c.limit_mm_s2 = std::max(c.limit_mm_s2, std::abs(e.value[k]));
    }
  return c;
}

double kernel_enbw_hz(WindowType w, double beta, std::size_t n, double fs) {
  const auto win = make_window(w, n, beta);
  double s1 = 0, s2 = 0;
  for (double x : win) {
    s1 += x;
    s2 += x * x;
  }
  return fs * s2 / (s1 * s1);
}

/// 1-based line of data row `row` (0-based) of a CSV whose header is on `header_line`:
/// rows are the non-blank lines after it that are not comments.
std::size_t resonance_row_line(std::string_view bytes, std::size_t header_line, std::size_t row) {
  std::size_t line = 1, pos = 0, seen = 0;
  while (pos < bytes.size()) {
    const auto end = bytes.find('\n', pos);
    const std::string_view l = bytes.substr(pos, end == std::string_view::npos ? std::string_view::npos : end - pos);
    if (line > header_line) {
      const auto first = l.find_first_not_of(" \t\r");
      if (first != std::string_view::npos && l[first] != '#') {
        if (seen == row) return line;
        ++seen;
      }
    }
    if (end == std::string_view::npos) break;
    pos = end + 1;
    ++line;
  }
  return 0;
}

/// The largest acceleration a sample may have before it is taken as wild, mm/s^2.
double wild_sample_limit(const AccelInputOptions& o) {
  return o.full_scale_mm_s2 > 0 ? 2 * o.full_scale_mm_s2 : kMaxAccelerometerReading_mm_s2;
}

/// Replaces non-physical samples of the acceleration columns (1..scans.size() of `table`, their
/// wild samples found by scan_channel) by the mean of the nearest good samples on either side,
/// with a located warning each (the first few listed); refuses a record with more than
/// options.max_wild_fraction of them. Returns whether any sample was replaced.
bool replace_wild_samples(CsvTable& table, std::string_view bytes, const std::vector<ChannelScan>& scans,
                          const AccelInputOptions& o, std::vector<std::string>& warnings) {
  const double limit = wild_sample_limit(o);
  constexpr std::size_t kListed = 5;
  bool replaced = false;
  for (std::size_t c = 1; c <= scans.size() && c < table.columns.size(); ++c) {
    auto& v = table.columns[c].values;
    const std::vector<std::size_t>& wild = scans[c - 1].wild;
    if (wild.empty()) continue;
    replaced = true;
    const std::string& name = table.columns[c].name;
    auto where = [&](std::size_t row) {
      const auto line = resonance_row_line(bytes, table.header_line, row);
      return line ? source_location(table.path, line) : table.path;
    };
    if (static_cast<double>(wild.size()) > o.max_wild_fraction * static_cast<double>(v.size()) && wild.size() > 1)
      throw InputError(
          fmt::format("{} samples of {} ({:.2g} %) are beyond any accelerometer's range (+-{:.6g} mm/s^2), "
                      "the first {} = {:g}; the record is corrupt (limit {:.2g} %)",
                      wild.size(), name, 100.0 * static_cast<double>(wild.size()) / static_cast<double>(v.size()),
                      limit, name, v[wild.front()], 100 * o.max_wild_fraction),
          where(wild.front()));
    std::vector<bool> bad(v.size(), false);
    for (const auto i : wild) bad[i] = true;
    for (std::size_t k = 0; k < wild.size(); ++k) {
      const std::size_t i = wild[k];
      if (k < kListed)
        warnings.push_back(
            fmt::format("{}: {} = {:g} mm/s^2 is beyond any accelerometer's range (+-{:.6g} mm/s^2); the "
                        "sample was replaced by the mean of its neighbours",
                        where(i), name, v[i], limit));
      double sum = 0;
      int count = 0;
      for (std::size_t j = i; j-- > 0;)
        if (!bad[j]) {
          sum += v[j];
          ++count;
          break;
        }
      for (std::size_t j = i + 1; j < v.size(); ++j)
        if (!bad[j]) {
          sum += v[j];
          ++count;
          break;
        }
      v[i] = count ? sum / count : 0.0;
    }
    if (wild.size() > kListed)
      warnings.push_back(fmt::format("{}: {} more samples of {} beyond the range were replaced", table.path,
                                     wild.size() - kListed, name));
  }
  return replaced;
}

}  // namespace

namespace {

/// The start of the grid t_i = start + i * interval closest to the times in the mean.
double grid_start(const std::vector<double>& t, double interval) {
  double offset = 0;
  for (std::size_t i = 0; i < t.size(); ++i) offset += t[i] - t.front() - static_cast<double>(i) * interval;
  return t.front() + offset / static_cast<double>(t.size());
}

}  // namespace

char axis_from_filename(const std::string& path) {
  std::string base = path;
  if (const auto slash = base.find_last_of('/'); slash != std::string::npos) base = base.substr(slash + 1);
  base = core::lower(base);
  for (const char* prefix : {"raw_data_", "calibration_data_", "resonances_"}) {
    const auto pos = base.find(prefix);
    if (pos == std::string::npos) continue;
    const std::size_t a = pos + std::char_traits<char>::length(prefix);
    if (a < base.size() && (base[a] == 'x' || base[a] == 'y' || base[a] == 'z') &&
        (a + 1 == base.size() || base[a + 1] == '_' || base[a + 1] == '.' || base[a + 1] == '-'))
      return base[a];
  }
  return 0;
}

namespace {

/// The median interval of the time column: the interval fitting::median of all of them gives
/// (the (n/2)-th smallest of n). A logger's clock gives a handful of distinct intervals (five
/// in a Klipper raw file at 3.2 kHz written to the microsecond), so they are counted in a small
/// table in one pass over t, without the 3 MB array of the intervals and a selection over it;
/// a time column with more distinct intervals takes that array.
double median_interval(const std::vector<double>& t) {
  constexpr std::size_t kSlots = 256, kMaxDistinct = 64;
  std::array<double, kSlots> value{};
  std::array<std::size_t, kSlots> count{};
  std::size_t distinct = 0;
  for (std::size_t i = 1; i < t.size() && distinct <= kMaxDistinct; ++i) {
    const double dt = t[i] - t[i - 1];  // the time column strictly increases: no zero, no NaN
    std::size_t h = static_cast<std::size_t>((std::bit_cast<std::uint64_t>(dt) * 0x9E3779B97F4A7C15ULL) >> 56);
    while (count[h] != 0 && value[h] != dt) h = (h + 1) % kSlots;
    if (count[h]++ == 0) {
      value[h] = dt;
      ++distinct;
    }
  }
  if (distinct > kMaxDistinct) {
    std::vector<double> dt(t.size() - 1);
    for (std::size_t i = 1; i < t.size(); ++i) dt[i - 1] = t[i] - t[i - 1];
    return fitting::median(std::move(dt));
  }
  std::vector<std::pair<double, std::size_t>> sorted;
  for (std::size_t h = 0; h < kSlots; ++h)
    if (count[h] != 0) sorted.emplace_back(value[h], count[h]);
  std::sort(sorted.begin(), sorted.end());
  const std::size_t k = (t.size() - 1) / 2;
  std::size_t below = 0;
  for (const auto& [v, c] : sorted) {
    below += c;
    if (below > k) return v;
  }
  return sorted.back().first;
}

/// Gaps (intervals above 1.5 median intervals), the samples they miss and the jitter of the
/// other intervals into `s`; InputError when the gaps exceed the options' limits.
void measure_sampling(const std::vector<double>& t, double med, const AccelInputOptions& o, const std::string& path,
                      SamplingReport& s) {
  const std::size_t n = t.size();
  double sum = 0, sum2 = 0;
  std::size_t regular = 0;
  double gap_at = 0;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const double dt = t[i + 1] - t[i];
    if (dt > 1.5 * med) {
      ++s.gaps;
      s.missing_samples += static_cast<std::size_t>(std::llround(dt / med)) - 1;
      if (dt > s.max_gap_s) {
        s.max_gap_s = dt;
        gap_at = t[i];
      }
      continue;
    }
    sum += dt;
    sum2 += dt * dt;
    ++regular;
  }
  const double mean_dt = regular > 0 ? sum / static_cast<double>(regular) : med;
  s.jitter = regular > 1 ? std::sqrt(std::max(0.0, sum2 / static_cast<double>(regular) - mean_dt * mean_dt)) / med : 0;
  if (s.max_gap_s > o.max_gap_s ||
      static_cast<double>(s.missing_samples) > o.max_missing_fraction * static_cast<double>(n))
    throw InputError(
        fmt::format("irregular sampling: {} gap(s) in the time column, {} samples missing ({:.2f} %), the "
                    "longest {:.4g} s after t = {:.6g} s (limits: {:.3g} s, {:.2g} %); record again or cut "
                    "the file at the gap",
                    s.gaps, s.missing_samples, 100.0 * static_cast<double>(s.missing_samples) / static_cast<double>(n),
                    s.max_gap_s, gap_at, o.max_gap_s, 100 * o.max_missing_fraction),
        path);
}

/// The record on a regular grid: resampled linearly at the median interval when it has gaps or
/// jitters beyond the limit, else its sample rate and the grid's start fitted to every sample.
void regular_grid(AccelRecord& r, CsvTable& table, const std::vector<double>& t, double med, const AccelInputOptions& o,
                  const std::string& path) {
  auto& s = r.sampling;
  const std::size_t n = t.size();
  const bool need_resample = s.gaps > 0 || s.jitter > o.max_jitter;
  if (need_resample) {
    s.sample_rate_hz = 1.0 / med;
    const std::size_t m = static_cast<std::size_t>(std::floor(s.duration_s / med)) + 1;
    s.resampled = true;
    r.warnings.push_back(
        fmt::format("{}: irregular sampling ({} gap(s), {} missing samples, interval jitter {:.2g} %); "
                    "resampled linearly at {:.6g} Hz",
                    path, s.gaps, s.missing_samples, 100 * s.jitter, s.sample_rate_hz));
    for (std::size_t c = 1; c < table.columns.size(); ++c)
      table.columns[c].values = resample(t, table.columns[c].values, t.front(), med, m);
  } else {
    s.sample_rate_hz = static_cast<double>(n - 1) / s.duration_s;
    // The grid's start from every sample, not from the first alone: loggers round their times
    // (Klipper writes microseconds), and an output-error fit against the commanded motion
    // (axis_response_fit.hpp) sees a tenth of a microsecond as a shift of the resonance by
    // several times its noise.
    r.start_time_s = grid_start(t, 1.0 / s.sample_rate_hz);
  }
}

/// InputError when every channel is constant (by its extremes) or the excitation column is.
void check_accel_signal(const AccelRecord& r, const AccelInputOptions& o, const std::string& path,
                        const std::vector<Extremes>& extremes) {
  bool any_signal = false;
  for (const auto& e : extremes)
    if (e.value[1] > e.value[0]) any_signal = true;
  if (!any_signal)
    throw InputError(
        "the acceleration columns are all zero (or constant): the accelerometer recorded nothing; check "
        "its wiring and that the test moved the axis",
        path);
  if (!r.excitation.empty()) {
    const auto [lo, hi] = value_range(r.excitation);
    if (!(hi > lo)) throw InputError("the excitation column '" + o.excitation_column + "' is constant", path);
  }
}

/// Clipped channels: InputError beyond the allowed fraction, else a warning and a report.
void check_clipping(AccelRecord& r, const AccelInputOptions& o, const std::string& path,
                    const std::vector<Extremes>& extremes) {
  for (std::size_t c = 0; c < r.channels.size(); ++c) {
    auto rep = detect_clipping(r.channel_names[c], r.channels[c], o.full_scale_mm_s2, extremes[c]);
    if (rep.samples == 0) continue;
    const double frac = static_cast<double>(rep.samples) / static_cast<double>(r.channels[c].size());
    if (frac > o.max_clipped_fraction)
      throw InputError(
          fmt::format("{} is clipped: {} samples ({:.2f} %) sit at the sensor limit +-{:.6g} mm/s^2 (limit "
                      "{:.2g} %); the resonance peaks would be cut off. Lower accel_per_hz or raise the "
                      "accelerometer's range",
                      rep.channel, rep.samples, 100 * frac, rep.limit_mm_s2, 100 * o.max_clipped_fraction),
          path);
    r.warnings.push_back(
        fmt::format("{}: {} has {} clipped samples ({:.3f} %) at +-{:.6g} mm/s^2; the strongest peak may "
                    "be underestimated",
                    path, rep.channel, rep.samples, 100 * frac, rep.limit_mm_s2));
    r.clipping.push_back(rep);
  }
}

}  // namespace

AccelRecord load_accel_csv(const std::string& path, std::string_view bytes, const AccelInputOptions& o,
                           const std::function<void()>& on_parsed) {
  AccelRecord r;
  r.path = path;
  r.axis = o.axis != 0 ? o.axis : axis_from_filename(path);
  std::vector<std::string> accel = o.accel_columns;
  if (accel.empty()) accel = {"accel_x", "accel_y", "accel_z"};
  CsvOptions co;
  co.time_column = o.time_column;
  co.columns.push_back(o.time_column);
  for (const auto& a : accel) co.columns.push_back(a);
  if (!o.excitation_column.empty()) co.columns.push_back(o.excitation_column);
  CsvTable table = parse_csv(bytes, path, co);
  if (on_parsed) on_parsed();
  for (const auto& w : table.warnings) r.warnings.push_back(w);
  if (table.rows < 16)
    throw InputError(fmt::format("{} rows of accelerometer data; far too few for a spectrum", table.rows), path);

  // The acceleration channels are scanned (wild samples, extremes: one pass each) on another
  // core while this one measures the time column; problems are then reported in the order of
  // the checks: wild samples, then the sampling.
  auto scanned = std::async(std::launch::async, [&table, n = accel.size(), limit = wild_sample_limit(o)] {
    std::vector<ChannelScan> scans;
    for (std::size_t c = 1; c <= n; ++c) scans.push_back(scan_channel(table.columns[c].values, limit));
    return scans;
  });
  std::vector<double> t = std::move(table.columns[0].values);
  const double med = median_interval(t);
  r.start_time_s = t.front();
  r.sampling.samples = t.size();
  r.sampling.duration_s = t.back() - t.front();
  std::exception_ptr sampling_error;
  try {
    measure_sampling(t, med, o, path, r.sampling);
  } catch (const InputError&) {
    sampling_error = std::current_exception();
  }
  const std::vector<ChannelScan> scans = scanned.get();
  const bool replaced = replace_wild_samples(table, bytes, scans, o, r.warnings);
  if (sampling_error) std::rethrow_exception(sampling_error);
  regular_grid(r, table, t, med, o, path);

  for (std::size_t c = 1; c <= accel.size(); ++c) {
    r.channel_names.push_back(core::lower(table.columns[c].name));
    r.channels.push_back(std::move(table.columns[c].values));
  }
  if (!o.excitation_column.empty()) {
    r.excitation_name = table.columns.back().name;
    r.excitation = std::move(table.columns.back().values);
  }
  // The extremes scanned hold unless samples were replaced or the channels resampled.
  std::vector<Extremes> extremes;
  for (std::size_t c = 0; c < r.channels.size(); ++c)
    extremes.push_back(replaced || r.sampling.resampled ? channel_extremes(r.channels[c]) : scans[c].extremes);
  check_accel_signal(r, o, path, extremes);
  check_clipping(r, o, path, extremes);
  return r;
}

AxisSpectrum record_spectrum(const AccelRecord& r, const WelchOptions& welch) {
  AxisSpectrum s;
  s.axis = r.axis;
  s.files = {r.path};
  s.welch = welch;
  s.sample_rate_hz = r.sampling.sample_rate_hz;
  s.warnings = r.warnings;
  // The channels' spectra are independent: all but the first on other threads.
  std::vector<std::span<const double>> channels(r.channels.begin(), r.channels.end());
  std::vector<Spectrum> spectra;
  try {
    spectra = welch_psds(channels, r.sampling.sample_rate_hz, welch);
  } catch (const InputError& e) {
    throw InputError(e.message(), r.path);
  }
  for (std::size_t c = 0; c < r.channels.size(); ++c) {
    Spectrum& sp = spectra[c];
    if (s.freq_hz.empty()) {
      s.freq_hz = sp.freq_hz;
      s.psd_sum.assign(sp.psd.size(), 0.0);
      s.segments = sp.segments;
      s.segment_length = sp.segment_length;
    }
    for (std::size_t b = 0; b < sp.psd.size(); ++b) s.psd_sum[b] += sp.psd[b];
    const auto& name = r.channel_names[c];
    if (name == "accel_x") s.psd_x = std::move(sp.psd);
    else if (name == "accel_y") s.psd_y = std::move(sp.psd);
    else if (name == "accel_z") s.psd_z = std::move(sp.psd);
  }
  if (!r.excitation.empty()) {
    // Output: the channel of the tested axis when known, else the first channel.
    std::size_t out = 0;
    for (std::size_t c = 0; c < r.channel_names.size(); ++c)
      if (r.axis != 0 && r.channel_names[c] == std::string("accel_") + r.axis) out = c;
    s.frf = h1_estimate(r.excitation, r.channels[out], r.sampling.sample_rate_hz, welch);
  }
  return s;
}

AxisSpectrum average_spectra(const std::vector<AxisSpectrum>& v) {
  if (v.empty()) throw InputError("no spectra to average");
  AxisSpectrum a = v.front();
  if (v.size() == 1) return a;
  auto add = [&](std::vector<double>& acc, const std::vector<double>& fx, const std::vector<double>& x) {
    if (acc.empty() || x.empty()) return;
    const auto y = fitting::interp_linear(fx, x, a.freq_hz);
    for (std::size_t i = 0; i < acc.size(); ++i) acc[i] += y[i];
  };
  for (std::size_t k = 1; k < v.size(); ++k) {
    if (v[k].klipper_normalized != a.klipper_normalized)
      throw InputError("cannot average raw accelerometer data with Klipper calibration data for the same axis",
                       v[k].files.front());
    add(a.psd_sum, v[k].freq_hz, v[k].psd_sum);
    add(a.psd_x, v[k].freq_hz, v[k].psd_x);
    add(a.psd_y, v[k].freq_hz, v[k].psd_y);
    add(a.psd_z, v[k].freq_hz, v[k].psd_z);
    a.files.insert(a.files.end(), v[k].files.begin(), v[k].files.end());
    a.warnings.insert(a.warnings.end(), v[k].warnings.begin(), v[k].warnings.end());
    a.segments += v[k].segments;
    if (!a.frf && v[k].frf) a.frf = v[k].frf;
  }
  const double inv = 1.0 / static_cast<double>(v.size());
  for (auto* p : {&a.psd_sum, &a.psd_x, &a.psd_y, &a.psd_z})
    for (double& x : *p) x *= inv;
  return a;
}

std::vector<double> klipper_normalize(const std::vector<double>& f, const std::vector<double>& psd) {
  std::vector<double> out(psd.size());
  for (std::size_t i = 0; i < psd.size(); ++i) {
    double v = psd[i] / (f[i] + 0.1);
    if (f[i] < 10.0) v *= std::exp(1.0 - std::pow(10.0 / (f[i] + 0.1), 2));
    out[i] = v;
  }
  return out;
}

fitting::SpectralKernel welch_kernel(WindowType window, double beta, std::size_t n, double fs, int per_bin,
                                     int half_width) {
  const auto w = make_window(window, n, beta);
  fitting::SpectralKernel k;
  const double N = static_cast<double>(n);
  double total = 0;
  for (int j = -half_width * per_bin; j <= half_width * per_bin; ++j) {
    const double u = static_cast<double>(j) / per_bin;  // offset in bins
    const std::complex<double> rot = std::polar(1.0, -2 * std::numbers::pi * u / N);
    std::complex<double> e(1, 0), sum(0, 0);
    for (std::size_t i = 0; i < n; ++i) {
      sum += w[i] * e;
      e *= rot;
    }
    const double val = std::norm(sum);
    k.offsets_hz.push_back(u * fs / N);
    k.weights.push_back(val);
    total += val;
  }
  for (double& x : k.weights) x /= total;
  return k;
}

std::vector<Peak> find_peaks(const std::vector<double>& f, const std::vector<double>& psd, double p, double lo,
                             double hi, double threshold, int max_modes, double enbw_hz) {
  std::vector<std::size_t> idx;
  for (std::size_t b = 0; b < f.size(); ++b)
    if (f[b] >= lo && f[b] <= hi && f[b] > 0) idx.push_back(b);
  std::vector<Peak> peaks;
  if (idx.size() < 5) return peaks;
  std::vector<double> fw(idx.size()), w(idx.size());
  for (std::size_t i = 0; i < idx.size(); ++i) {
    fw[i] = f[idx[i]];
    w[i] = psd[idx[i]] / std::pow(fw[i], p);
  }
  const double wmax = *std::max_element(w.begin(), w.end());
  if (!(wmax > 0)) return peaks;
  struct Cand {
    std::size_t i;
    double h;
  };
  std::vector<Cand> cands;
  for (std::size_t i = 1; i + 1 < w.size(); ++i)
    if (w[i] > w[i - 1] && w[i] >= w[i + 1] && w[i] >= threshold * wmax) cands.push_back({i, w[i]});
  std::sort(cands.begin(), cands.end(), [](const Cand& a, const Cand& b) { return a.h > b.h; });
  for (const auto& c : cands) {
    if (static_cast<int>(peaks.size()) >= max_modes) break;
    // Prominence: on each side, the lowest value before a higher peak (or the band edge).
    double lmin = c.h, rmin = c.h;
    double lcross = -1, rcross = -1;
    for (std::size_t j = c.i; j-- > 0;) {
      if (w[j] > c.h) break;
      lmin = std::min(lmin, w[j]);
      if (lcross < 0 && w[j] < 0.5 * c.h) lcross = fw[j] + (0.5 * c.h - w[j]) / (w[j + 1] - w[j]) * (fw[j + 1] - fw[j]);
    }
    for (std::size_t j = c.i + 1; j < w.size(); ++j) {
      if (w[j] > c.h) break;
      rmin = std::min(rmin, w[j]);
      if (rcross < 0 && w[j] < 0.5 * c.h)
        rcross = fw[j - 1] + (w[j - 1] - 0.5 * c.h) / (w[j - 1] - w[j]) * (fw[j] - fw[j - 1]);
    }
    if (std::max(lmin, rmin) > 0.7 * c.h) continue;  // a ripple on a slope, not a mode
    // Peak position by a parabola through the log of three bins.
    const double y0 = std::log(w[c.i - 1]), y1 = std::log(w[c.i]), y2 = std::log(w[c.i + 1]);
    const double den = y0 - 2 * y1 + y2;
    const double shift = den < 0 ? std::clamp(0.5 * (y0 - y2) / den, -0.5, 0.5) : 0.0;
    const double fp = fw[c.i] + shift * (fw[c.i + 1] - fw[c.i - 1]) * 0.5;
    double bw;
    if (lcross > 0 && rcross > 0) bw = rcross - lcross;
    else if (lcross > 0) bw = 2 * (fp - lcross);
    else if (rcross > 0) bw = 2 * (rcross - fp);
    else bw = 2 * (fw[c.i + 1] - fw[c.i - 1]);
    // Leakage widens the measured peak by about the window's noise bandwidth.
    bw = std::sqrt(std::max(bw * bw - enbw_hz * enbw_hz, 0.25 * bw * bw));
    peaks.push_back({fp, c.h, std::clamp(bw / (2 * fp), 0.003, 0.3)});
  }
  return peaks;
}

AxisModes identify_modes(const AxisSpectrum& s, const ResonanceOptions& o) {
  AxisModes out;
  const double p = o.excitation_exponent >= 0 ? o.excitation_exponent : (s.klipper_normalized ? 1.0 : 2.0);
  const auto kernel = welch_kernel(s.welch.window, s.welch.kaiser_beta, s.segment_length, s.sample_rate_hz);
  const double enbw = kernel_enbw_hz(s.welch.window, s.welch.kaiser_beta, s.segment_length, s.sample_rate_hz);
  out.peaks = find_peaks(s.freq_hz, s.psd_sum, p, o.fit_min_hz, o.fit_max_hz, o.peak_threshold, o.max_modes, enbw);
  if (out.peaks.empty()) {
    out.warnings.push_back(fmt::format("axis {}: no resonance peak between {} and {} Hz", s.axis == 0 ? '?' : s.axis,
                                       o.fit_min_hz, o.fit_max_hz));
    return out;
  }
  std::vector<Peak> peaks = out.peaks;  // strongest first
  fitting::ModalFitOptions mo;
  mo.excitation_exponent = p;
  std::string psd_error;
  while (!peaks.empty()) {
    double fmin = peaks.front().freq_hz, fmax = fmin;
    for (const auto& pk : peaks) {
      fmin = std::min(fmin, pk.freq_hz);
      fmax = std::max(fmax, pk.freq_hz);
    }
    out.band_lo_hz = std::max(o.fit_min_hz, 0.6 * fmin);
    out.band_hi_hz = std::min(o.fit_max_hz, 1.35 * fmax);
    std::vector<double> fb, pb;
    std::vector<std::complex<double>> hb;
    std::vector<double> cb;
    for (std::size_t b = 0; b < s.freq_hz.size(); ++b)
      if (s.freq_hz[b] >= out.band_lo_hz && s.freq_hz[b] <= out.band_hi_hz) {
        fb.push_back(s.freq_hz[b]);
        pb.push_back(s.psd_sum[b]);
        if (s.frf) {
          hb.push_back(s.frf->h[b]);
          cb.push_back(s.frf->coherence[b]);
        }
      }
    std::vector<fitting::ModeStart> starts;
    for (const auto& pk : peaks) starts.push_back({pk.freq_hz, pk.half_power_zeta, 1.0});
    try {
      if (s.frf && o.use_frf) {
        try {
          out.fit = fitting::fit_modal_frf(fb, hb, cb, o.min_coherence, starts, kernel, mo);
          out.method = "frf";
        } catch (const Error& e) {
          out.warnings.push_back(std::string("frequency-response fit failed, using the PSD: ") + e.message());
        }
      }
      if (!out.fit) {
        out.fit = fitting::fit_modal_psd(fb, pb, starts, kernel, mo);
        out.method = "psd";
      }
      break;
    } catch (const FitError& e) {
      psd_error = e.message();
      if (peaks.size() == 1) throw;
      out.warnings.push_back(fmt::format("modal fit with {} modes failed ({}); dropped the weakest peak at {:.1f} Hz",
                                         peaks.size(), e.message(), peaks.back().freq_hz));
      peaks.pop_back();
    }
  }
  out.modes = out.fit->modes;
  for (const auto& w : out.fit->warnings) out.warnings.push_back(w);
  // The dominant mode: nearest to the strongest peak.
  double best = 1e300;
  for (std::size_t k = 0; k < out.modes.size(); ++k) {
    const double d = std::abs(out.modes[k].freq_hz - out.peaks.front().freq_hz);
    if (d < best) {
      best = d;
      out.dominant = static_cast<int>(k);
    }
  }
  return out;
}

}  // namespace tunekit::ident
