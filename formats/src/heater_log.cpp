#include "tunekit/formats/heater_log.hpp"

#include <cmath>
#include <cstdlib>
#include <map>
#include <optional>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::formats {
namespace {

/// Splits text into lines without their "\n" / "\r\n".
std::vector<std::string_view> lines_of(std::string_view text) {
  std::vector<std::string_view> out;
  std::size_t b = 0;
  while (b < text.size()) {
    std::size_t e = text.find('\n', b);
    if (e == std::string_view::npos) e = text.size();
    std::string_view l = text.substr(b, e - b);
    if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
    out.push_back(l);
    b = e + 1;
  }
  return out;
}

/// The number at the start of `s` (after `key`), with the rest; nullopt when there is none or it
/// does not end at a blank or the end of the text (a cut-off "temp=20" at a file's end ends there,
/// and is taken: only a value with no digit is refused).
std::optional<double> number_after(std::string_view line, std::size_t at) {
  if (at >= line.size()) return std::nullopt;
  const std::string s(line.substr(at, 32));
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (end == s.c_str() || !std::isfinite(v)) return std::nullopt;
  return v;
}

/// "<key>=<number>" searched from `from`; the position after it in `next`.
std::optional<double> field(std::string_view line, std::string_view key, std::size_t from, std::size_t& next) {
  const std::size_t p = line.find(key, from);
  if (p == std::string_view::npos) return std::nullopt;
  next = p + key.size();
  return number_after(line, next);
}

void add_sample(HeaterLog& log, double t, double target, double temp, double duty, double max_gap_s) {
  if (log.t_s.empty() || t <= log.t_s.back() || t - log.t_s.back() > max_gap_s)
    log.run_starts.push_back(log.t_s.size());
  log.t_s.push_back(t);
  log.target_c.push_back(target);
  log.temp_c.push_back(temp);
  log.duty.push_back(duty);
}

/// The heaters a Stats line names ("<name>: target="), for the message when the asked one is absent.
void collect_heaters(std::string_view line, std::map<std::string, int>& names) {
  std::size_t p = 0;
  while ((p = line.find(": target=", p)) != std::string_view::npos) {
    std::size_t b = line.rfind(' ', p);
    b = b == std::string_view::npos ? 0 : b + 1;
    names[std::string(line.substr(b, p - b))]++;
    p += 9;
  }
}

}  // namespace

std::vector<HeaterRun> heater_runs(const HeaterLog& log) {
  std::vector<HeaterRun> out;
  for (std::size_t i = 0; i < log.run_starts.size(); ++i)
    out.push_back({log.run_starts[i], i + 1 < log.run_starts.size() ? log.run_starts[i + 1] : log.t_s.size()});
  return out;
}

HeaterLog read_klippy_heater_log(std::string_view text, const std::string& heater, double max_gap_s) {
  if (heater.empty()) throw InputError("the heater's name is empty (e.g. extruder, extruder1, heater_bed)");
  HeaterLog log;
  log.heater = heater;
  std::map<std::string, int> seen;
  const std::string key = " " + heater + ": target=";
  for (const std::string_view line : lines_of(text)) {
    if (line.rfind("Stats ", 0) != 0) continue;
    ++log.lines_read;
    collect_heaters(line, seen);
    const auto t = number_after(line, 6);
    const std::size_t colon = line.find(':');
    const std::size_t h = line.find(key);
    std::size_t next = 0;
    if (!t || colon == std::string_view::npos || h == std::string_view::npos) {
      ++log.lines_skipped;
      continue;
    }
    const auto target = number_after(line, h + key.size());
    const auto temp = field(line, "temp=", h + key.size(), next);
    const auto pwm = temp ? field(line, "pwm=", next, next) : std::nullopt;
    if (!target || !temp || !pwm || *pwm < 0 || *pwm > 1) {
      ++log.lines_skipped;
      continue;
    }
    add_sample(log, *t, *target, *temp, *pwm, max_gap_s);
  }
  if (log.lines_read == 0)
    throw InputError("no Klipper \"Stats\" line: this is not a klippy.log (Klipper writes one a second while it runs)");
  if (log.t_s.empty()) {
    std::string names;
    for (const auto& [n, c] : seen) names += (names.empty() ? "" : ", ") + n;
    throw InputError(fmt::format(
        "no Stats line of {} lines holds the heater '{}' with its target, temperature and PWM{} (Klipper prints a "
        "heater only while it has a target or reads above 50 degC)",
        log.lines_read, heater, names.empty() ? std::string(" (no heater at all)") : ": the log has " + names));
  }
  return log;
}

HeaterLog read_marlin_temperature_reports(std::string_view text, double interval_s, const std::string& tool) {
  if (!(interval_s > 0) || !std::isfinite(interval_s))
    throw InputError(fmt::format("the report interval must be above 0 s, not {}", interval_s));
  if (tool.empty() || tool[0] != 'T')
    throw InputError(fmt::format("the hot end is named T, T0, T1, ... in Marlin's reports, not '{}'", tool));
  HeaterLog log;
  log.heater = tool;
  const std::string temp_key = " " + tool + ":", power_key = " @" + tool.substr(1) + ":";
  std::size_t index = 0;
  for (const std::string_view raw : lines_of(text)) {
    // "ok T:..." (M105's reply) or " T:..." (M155); a leading blank makes the first key findable.
    const std::string line = " " + std::string(raw);
    const std::size_t p = line.find(temp_key);
    if (p == std::string::npos) continue;
    ++log.lines_read;
    const double t = static_cast<double>(index++) * interval_s;
    std::size_t next = 0;
    const auto temp = number_after(line, p + temp_key.size());
    const std::size_t slash = line.find('/', p);
    const auto target = slash == std::string::npos ? std::nullopt : number_after(line, slash + 1);
    const auto power = field(line, power_key, 0, next);
    if (!temp || !target || !power || *power < 0 || *power > 127) {
      ++log.lines_skipped;
      continue;
    }
    add_sample(log, t, *target, *temp, *power / 127.0, 1.5 * interval_s);
  }
  if (log.t_s.empty())
    throw InputError(fmt::format(
        "no temperature report with {}'s temperature, target and power '@': Marlin prints them for M105 and for "
        "the auto-report M155 S<seconds> ({} lines named {})",
        tool, log.lines_read, tool));
  return log;
}

}  // namespace tunekit::formats
