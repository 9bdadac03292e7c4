#include "tunekit/ident/klipper_spectrum.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/interpolate.hpp"
#include "tunekit/fitting/stats.hpp"
#include "tunekit/core/text.hpp"
#include "tunekit/formats/csv.hpp"

namespace tunekit::ident {

using core::iequals;
using formats::CsvOptions;
using formats::CsvTable;
using formats::parse_csv;
namespace {

std::string_view spectrum_trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

// The header line (first non-blank line not starting with '#') and its 1-based number.
std::pair<std::string_view, std::size_t> spectrum_header_line(std::string_view bytes) {
  if (bytes.size() >= 3 && std::memcmp(bytes.data(), "\xEF\xBB\xBF", 3) == 0) bytes.remove_prefix(3);
  std::size_t line_no = 0;
  while (!bytes.empty()) {
    const auto nl = bytes.find('\n');
    const std::string_view line = spectrum_trim(bytes.substr(0, nl));
    ++line_no;
    if (!line.empty() && line.front() != '#') return {line, line_no};
    if (nl == std::string_view::npos) break;
    bytes.remove_prefix(nl + 1);
  }
  return {{}, 0};
}

// Header fields, honouring Klipper's quoting of dataset names ("a,b" and "" for a quote).
std::vector<std::string> spectrum_header_fields(std::string_view line) {
  std::vector<std::string> out;
  std::string cur;
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        cur += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        cur += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      out.emplace_back(spectrum_trim(cur));
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.emplace_back(spectrum_trim(cur));
  return out;
}

std::string csv_escape_name(const std::string& name) {
  std::string s;
  for (char c : name) {
    if (c == '"') s += '"';
    s += c;
  }
  return name.find(',') != std::string::npos ? "\"" + s + "\"" : s;
}

}  // namespace

bool is_klipper_spectrum(std::string_view bytes) {
  const auto [line, no] = spectrum_header_line(bytes);
  return line.size() >= 5 && iequals(line.substr(0, 5), "freq,");
}

KlipperSpectrumFile read_klipper_spectrum(const std::string& path, std::string_view bytes, char axis) {
  const auto [line, header_no] = spectrum_header_line(bytes);
  const auto fields = spectrum_header_fields(line);
  if (fields.size() < 2 || !iequals(fields.front(), "freq"))
    throw InputError("not a Klipper spectrum file: the header does not start with 'freq,'", path);
  KlipperSpectrumFile out;
  // Dataset columns end at `shapers:`; the shaper response columns follow it.
  std::vector<std::string> names;
  for (std::size_t i = 1; i < fields.size(); ++i) {
    if (iequals(fields[i], "shapers:")) {
      out.has_shapers = true;
      out.shaper_columns.assign(fields.begin() + static_cast<std::ptrdiff_t>(i) + 1, fields.end());
      break;
    }
    names.push_back(fields[i]);
  }
  const bool one_dataset = names.size() >= 4 && iequals(names[0], "psd_x") && iequals(names[1], "psd_y") &&
                           iequals(names[2], "psd_z") && iequals(names[3], "psd_xyz");
  if (names.empty()) throw InputError("the spectrum file has a 'freq' column but no PSD column", path);
  if (!one_dataset)
    for (std::size_t i = 0; i < names.size(); ++i)
      for (std::size_t k = 0; k < i; ++k)
        if (iequals(names[i], names[k]))
          throw InputError(fmt::format("two datasets are both named '{}'; rename one in the header", names[i]),
                           fmt::format("{}:{}", path, header_no));

  CsvOptions co;
  co.time_column = "freq";
  co.columns = {"freq"};
  if (one_dataset) {
    for (const char* c : {"psd_x", "psd_y", "psd_z", "psd_xyz"}) co.columns.emplace_back(c);
  } else {
    co.columns.insert(co.columns.end(), names.begin(), names.end());
  }
  const CsvTable t = parse_csv(bytes, path, co);
  if (t.rows < 8)
    throw InputError(fmt::format("the spectrum file has {} frequencies; at least 8 are needed", t.rows), path);
  const auto& f = t.columns[0].values;
  if (f.front() < 0) throw InputError("the spectrum file has a negative frequency", path);
  for (std::size_t c = 1; c < t.columns.size(); ++c)
    for (std::size_t r = 0; r < t.rows; ++r)
      if (t.columns[c].values[r] < 0)
        throw InputError(
            fmt::format("negative PSD {} in column '{}' at {} Hz", t.columns[c].values[r], t.columns[c].name, f[r]),
            path);

  // Klipper writes the bins rounded to 0.1 Hz: the bin width is the median step.
  std::vector<double> df(f.size() - 1);
  for (std::size_t i = 1; i < f.size(); ++i) df[i - 1] = f[i] - f[i - 1];
  const double bin = fitting::median(df);

  auto make = [&](const std::string& name) {
    AxisSpectrum s;
    s.axis = axis != 0 ? axis : axis_from_filename(path);
    s.files = {one_dataset ? path : name};  // Klipper names a dataset column's data by the column
    s.freq_hz = f;
    s.klipper_normalized = out.has_shapers;
    s.welch = klipper_welch_options();
    s.segment_length = 2048;  // Klipper's window at ~3.2 kHz
    s.sample_rate_hz = bin * static_cast<double>(s.segment_length);
    for (const auto& w : t.warnings) s.warnings.push_back(w);
    return s;
  };
  auto check_signal = [&](const std::vector<double>& p, const std::string& name) {
    if (!(*std::max_element(p.begin(), p.end()) > 0))
      throw InputError(
          fmt::format("the PSD in column '{}' is zero everywhere; the accelerometer recorded nothing", name), path);
  };
  if (one_dataset) {
    AxisSpectrum s = make("psd_xyz");
    s.psd_x = t.columns[1].values;
    s.psd_y = t.columns[2].values;
    s.psd_z = t.columns[3].values;
    s.psd_sum = t.columns[4].values;
    check_signal(s.psd_sum, "psd_xyz");
    out.datasets.push_back(std::move(s));
    out.dataset_names.emplace_back("psd_xyz");
  } else {
    for (std::size_t k = 0; k < names.size(); ++k) {
      AxisSpectrum s = make(names[k]);
      s.psd_sum = t.columns[k + 1].values;
      check_signal(s.psd_sum, names[k]);
      out.datasets.push_back(std::move(s));
      out.dataset_names.push_back(names[k]);
    }
  }
  return out;
}

std::vector<double> klipper_spectrum_grid(const std::vector<KlipperSpectrumColumn>& datasets, double max_freq_hz) {
  if (datasets.empty()) throw InputError("no spectrum to write");
  std::vector<double> grid;
  if (datasets.size() == 1) {
    for (double x : datasets.front().spectrum->freq_hz)
      if (x < max_freq_hz) grid.push_back(x);
    return grid;
  }
  double lo = max_freq_hz;
  for (const auto& d : datasets) lo = std::min(lo, d.spectrum->freq_hz.front());
  for (std::size_t i = 0;; ++i) {
    const double x = lo + 0.2 * static_cast<double>(i);
    if (x >= max_freq_hz) break;
    grid.push_back(x);
  }
  return grid;
}

std::string write_klipper_spectrum(const std::vector<KlipperSpectrumColumn>& datasets,
                                   const std::vector<KlipperShaperColumn>& shapers, double max_freq_hz) {
  const auto grid = klipper_spectrum_grid(datasets, max_freq_hz);
  for (const auto& s : shapers)
    if (s.response.size() < grid.size())
      throw InputError(
          fmt::format("shaper {} has {} response values for {} rows", s.name, s.response.size(), grid.size()));
  std::vector<std::vector<double>> cols;
  std::string out = "freq,";
  if (datasets.size() == 1) {
    const AxisSpectrum& s = *datasets.front().spectrum;
    const std::size_t n = grid.size();
    auto or_zero = [n](const std::vector<double>& v) { return v.empty() ? std::vector<double>(n, 0.0) : v; };
    cols = {or_zero(s.psd_x), or_zero(s.psd_y), or_zero(s.psd_z), s.psd_sum};
    out += "psd_x,psd_y,psd_z,psd_xyz";
  } else {
    for (std::size_t k = 0; k < datasets.size(); ++k) {
      if (k > 0) out += ',';
      out += csv_escape_name(datasets[k].name);
      cols.push_back(fitting::interp_linear(datasets[k].spectrum->freq_hz, datasets[k].spectrum->psd_sum, grid));
    }
  }
  if (!shapers.empty()) {
    out += ",shapers:";
    for (const auto& s : shapers) out += fmt::format(",{}({:.1f})", s.name, s.freq_hz);
  }
  out += '\n';
  for (std::size_t i = 0; i < grid.size(); ++i) {
    out += fmt::format("{:.1f}", grid[i]);
    for (const auto& c : cols) {
      if (!std::isfinite(c[i])) throw InputError(fmt::format("non-finite PSD at {} Hz; nothing written", grid[i]));
      out += fmt::format(",{:.3e}", c[i]);
    }
    if (!shapers.empty()) {
      out += ',';
      for (const auto& s : shapers) out += fmt::format(",{:.3f}", s.response[i]);
    }
    out += '\n';
  }
  return out;
}

}  // namespace tunekit::ident
