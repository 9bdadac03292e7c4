#include "tunekit/ident/rrf_accelerometer.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::ident {
namespace {

std::vector<std::string_view> rrf_split_fields(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t b = 0;
  for (;;) {
    const auto e = line.find(',', b);
    out.push_back(line.substr(b, e == std::string_view::npos ? std::string_view::npos : e - b));
    if (e == std::string_view::npos) break;
    b = e + 1;
  }
  return out;
}

bool rrf_parse_number(std::string_view s, double& v) {
  while (!s.empty() && s.front() == ' ') s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\r')) s.remove_suffix(1);
  if (s.empty()) return false;
  const std::string tmp(s);
  char* end = nullptr;
  v = std::strtod(tmp.c_str(), &end);
  return end == tmp.c_str() + tmp.size() && std::isfinite(v);
}

}  // namespace

bool is_rrf_accelerometer_csv(std::string_view bytes) {
  if (bytes.rfind("\xEF\xBB\xBF", 0) == 0) bytes.remove_prefix(3);
  return bytes.rfind("Sample,", 0) == 0;
}

AccelRecord load_rrf_accelerometer_csv(const std::string& path, std::string_view bytes, const AccelInputOptions& o) {
  if (bytes.rfind("\xEF\xBB\xBF", 0) == 0) bytes.remove_prefix(3);
  std::vector<std::string_view> lines;
  for (std::size_t b = 0; b < bytes.size();) {
    auto e = bytes.find('\n', b);
    if (e == std::string_view::npos) e = bytes.size();
    auto l = bytes.substr(b, e - b);
    if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
    lines.push_back(l);
    b = e + 1;
  }
  while (!lines.empty() && lines.back().empty()) lines.pop_back();
  if (lines.empty()) throw InputError("empty file", path);

  // Header: Sample and the recorded axes.
  const auto head = rrf_split_fields(lines[0]);
  std::vector<char> axes;
  for (std::size_t k = 1; k < head.size(); ++k) {
    if (head[k] != "X" && head[k] != "Y" && head[k] != "Z")
      throw InputError(fmt::format("RepRapFirmware accelerometer header column '{}' is not X, Y or Z", head[k]),
                       source_location(path, 1));
    axes.push_back(static_cast<char>(head[k][0] - 'X' + 'x'));
  }
  if (axes.empty())
    throw InputError("RepRapFirmware accelerometer header 'Sample' lists no axis", source_location(path, 1));

  AccelRecord r;
  r.path = path;
  r.axis = o.axis;
  // RRF names files <board>_<date>_<time>.csv unless M956 F"name" gives one: Klipper-style names tell the axis.
  if (r.axis == 0) r.axis = axis_from_filename(path);
  std::vector<std::vector<double>> ch(axes.size());
  double rate = 0;
  long overflows = 0;
  bool trailer = false;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const auto l = lines[i];
    const std::string where = source_location(path, i + 1);
    if (trailer) {
      if (l.empty()) continue;
      throw InputError(fmt::format("text after the 'Rate' line: '{}'", l), where);
    }
    if (l.rfind("Rate ", 0) == 0) {
      unsigned rate_u = 0, ov = 0;
      if (std::sscanf(std::string(l).c_str(), "Rate %u, overflows %u", &rate_u, &ov) != 2 || rate_u == 0)
        throw InputError(fmt::format("a bad trailer '{}' (RepRapFirmware writes 'Rate <Hz>, overflows <n>')", l),
                         where);
      rate = rate_u;
      overflows = ov;
      trailer = true;
      continue;
    }
    if (l.rfind("Failed", 0) == 0 || l.rfind("Received", 0) == 0)
      throw InputError(fmt::format("the accelerometer run failed on the printer: '{}'; record again", l), where);
    const auto f = rrf_split_fields(l);
    double sample = 0;
    if (f.size() != axes.size() + 1 || !rrf_parse_number(f[0], sample))
      throw InputError(fmt::format("expected 'sample,{}' values, got '{}'", axes.size() == 3 ? "X,Y,Z" : "axes", l),
                       where);
    if (std::lround(sample) != static_cast<long>(ch[0].size()))
      throw InputError(fmt::format("sample number {} out of order (expected {})", f[0], ch[0].size()), where);
    for (std::size_t k = 0; k < axes.size(); ++k) {
      double v = 0;
      if (!rrf_parse_number(f[k + 1], v)) throw InputError(fmt::format("'{}' is not a number", f[k + 1]), where);
      ch[k].push_back(v * kStandardGravityMmS2);
    }
  }
  if (!trailer)
    throw InputError(
        "no 'Rate <Hz>, overflows <n>' line at the end: the recording did not finish (RepRapFirmware writes "
        "it last), so the sample rate is unknown",
        source_location(path, lines.size()));
  if (ch[0].size() < 16)
    throw InputError(fmt::format("{} rows of accelerometer data; far too few for a spectrum", ch[0].size()), path);
  if (overflows > 0)
    r.warnings.push_back(
        fmt::format("{}: the accelerometer's FIFO overflowed {} time(s) during the run; samples are "
                    "missing and the spectrum is smeared",
                    path, overflows));
  bool any_signal = false;
  for (const auto& c : ch) any_signal |= *std::max_element(c.begin(), c.end()) > *std::min_element(c.begin(), c.end());
  if (!any_signal)
    throw InputError(
        "the acceleration columns are constant: the accelerometer recorded nothing; check its wiring and "
        "that the test moved the axis",
        path);
  for (std::size_t k = 0; k < axes.size(); ++k) {
    r.channel_names.push_back(std::string("accel_") + axes[k]);
    r.channels.push_back(std::move(ch[k]));
  }
  auto& s = r.sampling;
  s.samples = r.channels[0].size();
  s.sample_rate_hz = rate;
  s.duration_s = static_cast<double>(s.samples - 1) / rate;
  return r;
}

}  // namespace tunekit::ident
