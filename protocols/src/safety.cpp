#include "tunekit/protocols/safety.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <optional>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/core/text.hpp"
#include "tunekit/machine/trajectory.hpp"

namespace tunekit::protocols {
namespace {

constexpr double kLimitTolerance = 1e-6;
// The lowest hot-end temperature an M109 may wait for, degC: below the coolest room a printer
// runs in. A heater cannot cool below ambient, so Marlin's and RepRapFirmware's M109 R (which
// waits while cooling, Marlin/src/gcode/temp/M104_M109.cpp) would never return; a protocol
// temperature that rounds to 0 ("leave the heater alone") must not become such a wait.
constexpr double kMinHotendWait_c = 15;
constexpr double kGateJerkMmS3 = 1e8;  // duration estimates only: a near-trapezoidal profile

bool iequals_prefix(std::string_view s, std::string_view prefix) {
  if (s.size() < prefix.size()) return false;
  for (std::size_t i = 0; i < prefix.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(s[i])) != prefix[i]) return false;
  return true;
}

/// True when the value text `v` (what follows a word's letter or '=') is not a finite number:
/// inf/nan spelled out, or digits that overflow a double (1e999).
bool value_not_finite(std::string_view v) {
  std::string_view t = v;
  if (!t.empty() && (t.front() == '+' || t.front() == '-')) t.remove_prefix(1);
  if (iequals_prefix(t, "inf") || iequals_prefix(t, "nan")) return true;
  std::size_t n = 0;
  while (n < v.size() && (std::isdigit(static_cast<unsigned char>(v[n])) || v[n] == '.' || v[n] == '+' || v[n] == '-' ||
                          v[n] == 'e' || v[n] == 'E'))
    ++n;
  if (n == 0) return false;
  const std::string digits(v.substr(0, n));
  const double x = std::strtod(digits.c_str(), nullptr);
  return !std::isfinite(x);
}

/// The G-code body without N<line>, *<checksum> and comments.
std::string gcode_body(std::string_view line) {
  std::string text = machine::split_numbered(line).body;
  if (const auto semi = text.find(';'); semi != std::string::npos) text.resize(semi);
  for (auto open = text.find('('); open != std::string::npos; open = text.find('(')) {
    const auto close = text.find(')', open);
    text.erase(open, close == std::string::npos ? std::string::npos : close - open + 1);
  }
  return text;
}

void home_to_minimums(machine::GcodeInterpreter& in, const machine::MachineProfile& p) {
  machine::GcodeWords home;
  home.command = "G92";
  for (const char* a : {"x", "y", "z"})
    if (p.axes.count(a)) home.args[std::string(1, static_cast<char>(std::toupper(a[0])))] = p.axes.at(a).min_mm;
  in.apply(home);
}

/// Temperature, feed-rate and acceleration settings of one line against the profile.
template <class Add>
void check_settings(const machine::GcodeWords& w, const machine::GcodeInterpreter& in, const machine::MachineProfile& p,
                    Add add) {
  if ((w.command == "M104" || w.command == "M109") && in.hotend_c) {
    if (*in.hotend_c > p.temperature.hotend_max_c + kLimitTolerance)
      add(fmt::format("hot-end temperature {:g} degC exceeds hotend_max_c {:g}", *in.hotend_c,
                      p.temperature.hotend_max_c));
    if (*in.hotend_c < 0) add(fmt::format("hot-end temperature {:g} degC is negative", *in.hotend_c));
    else if (w.command == "M109" && *in.hotend_c < kMinHotendWait_c)
      add(
          fmt::format("M109 waits for a hot-end temperature of {:g} degC as written, below {:g} degC (ambient): the "
                      "wait would never end; give a melt temperature, or 0 without a wait to leave the heater alone",
                      *in.hotend_c, kMinHotendWait_c));
  }
  if ((w.command == "M140" || w.command == "M190") && in.bed_c) {
    if (*in.bed_c > p.temperature.bed_max_c + kLimitTolerance)
      add(fmt::format("bed temperature {:g} degC exceeds bed_max_c {:g}", *in.bed_c, p.temperature.bed_max_c));
    if (*in.bed_c < 0) add(fmt::format("bed temperature {:g} degC is negative", *in.bed_c));
  }
  if ((w.command == "G0" || w.command == "G1") && w.has("F") && !(w.get("F", 0) > 0))
    add(fmt::format("feed rate F{:g} is not positive", w.get("F", 0)));
  if ((w.command == "M204" || w.command == "SET_VELOCITY_LIMIT") && !(in.accel_mm_s2() > 0))
    add(fmt::format("acceleration {:g} mm/s^2 is not positive", in.accel_mm_s2()));
  if (w.command == "G4" && (!(in.dwell_s() >= 0))) add(fmt::format("dwell {:g} s is negative", in.dwell_s()));
}

/// Travel of one move against the profile (the part of the check the send guard repeats).
template <class Add>
void check_travel(const machine::GcodeMove& move, const machine::MachineProfile& p, Add add) {
  for (std::size_t k = 0; k < 3; ++k) {
    const std::string name = machine::kAxisNames[k];
    const double d = move.end[k] - move.start[k];
    if (std::abs(d) <= 1e-12 && !p.axes.count(name)) continue;
    if (!p.axes.count(name)) {
      add(fmt::format("moves axis {} which the profile does not have", name));
      continue;
    }
    const auto& a = p.axes.at(name);
    if (!(move.end[k] >= a.min_mm - kLimitTolerance && move.end[k] <= a.max_mm + kLimitTolerance))
      add(fmt::format("{} position {:g} mm is outside the travel {:g}..{:g} mm", name, move.end[k], a.min_mm,
                      a.max_mm));
  }
  if (!(move.feed_mm_s > 0)) add(fmt::format("feed rate {:g} mm/s is not positive", move.feed_mm_s));
}

}  // namespace

std::optional<std::string> non_finite_word(std::string_view line) {
  const std::string body = gcode_body(line);
  std::size_t i = 0;
  while (i < body.size() && std::isspace(static_cast<unsigned char>(body[i]))) ++i;
  std::size_t head_end = i;
  while (head_end < body.size() && !std::isspace(static_cast<unsigned char>(body[head_end]))) ++head_end;
  const std::string_view head(body.data() + i, head_end - i);
  if (head.empty()) return std::nullopt;
  for (const std::string_view text_command : {"m117", "m118", "respond"})
    if (head.size() == text_command.size() && iequals_prefix(head, text_command)) return std::nullopt;
  const bool classic = head.size() >= 2 && std::isalpha(static_cast<unsigned char>(head[0])) &&
                       std::isdigit(static_cast<unsigned char>(head[1])) && head.find('=') == std::string_view::npos;
  if (!classic) {
    // Extended commands (Klipper, RepRapFirmware's meta commands): KEY=VALUE words.
    std::size_t k = head_end;
    while (k < body.size()) {
      while (k < body.size() && std::isspace(static_cast<unsigned char>(body[k]))) ++k;
      std::size_t e = k;
      while (e < body.size() && !std::isspace(static_cast<unsigned char>(body[e]))) ++e;
      const std::string_view tok(body.data() + k, e - k);
      const auto eq = tok.find('=');
      if (eq != std::string_view::npos && value_not_finite(tok.substr(eq + 1))) return std::string(tok);
      k = e;
    }
    return std::nullopt;
  }
  // Classic words: a letter and its value, possibly glued ("G1X10Yinf"); the command's own
  // letter and digits come first.
  std::size_t k = i + 1;
  while (k < body.size() && (std::isdigit(static_cast<unsigned char>(body[k])) || body[k] == '.')) ++k;
  while (k < body.size()) {
    const char c = body[k];
    if (!std::isalpha(static_cast<unsigned char>(c))) {
      ++k;
      continue;
    }
    const std::string_view rest(body.data() + k + 1, body.size() - k - 1);
    if (value_not_finite(rest)) {
      std::size_t e = k + 1;
      while (e < body.size() && !std::isspace(static_cast<unsigned char>(body[e]))) ++e;
      return body.substr(k, e - k);
    }
    ++k;
    while (k < body.size() && !std::isalpha(static_cast<unsigned char>(body[k])) &&
           !std::isspace(static_cast<unsigned char>(body[k])))
      ++k;
  }
  return std::nullopt;
}

namespace {

/// The speed two consecutive moves are joined at in the estimate, mm/s: moves without
/// extrusion going straight on at the lower of their speeds (as every planner joins them at
/// most), anything else at rest.
double estimate_junction(const machine::GcodeMove& a, const machine::GcodeMove& b) {
  if (a.end[3] != a.start[3] || b.end[3] != b.start[3]) return 0;
  const auto ua = a.unit(), ub = b.unit();
  double dot = 0;
  for (std::size_t k = 0; k < 3; ++k) dot += ua[k] * ub[k];
  return dot > 1 - 1e-9 ? std::min(a.feed_mm_s, b.feed_mm_s) : 0.0;
}

}  // namespace

double estimate_gcode_duration_s(const std::vector<std::string>& gcode) {
  machine::GcodeInterpreter in;
  double t = 0, entry = 0;
  std::optional<machine::GcodeMove> prev;
  auto run_prev = [&](double exit) {
    if (prev)
      t += machine::Profile::move_duration_s(prev->length_mm(), entry, prev->feed_mm_s, exit, prev->accel_mm_s2,
                                             kGateJerkMmS3);
    entry = exit;
  };
  for (const auto& l : gcode) {
    const auto w = machine::parse_gcode(l);
    if (!w) continue;
    const auto m = in.apply(*w);
    if (m) {
      if (!(m->feed_mm_s > 0) || !(m->accel_mm_s2 > 0) || !std::isfinite(m->length_mm()))
        return std::numeric_limits<double>::infinity();
      run_prev(prev ? estimate_junction(*prev, *m) : 0.0);
      prev = *m;
    } else if (w->command == "G4" || w->command == "M400" || w->command == "G28") {
      run_prev(0);  // the planner comes to rest
      prev.reset();
    }
    t += in.dwell_s();
  }
  run_prev(0);
  return t;
}

std::vector<Violation> check_protocol(const std::vector<std::string>& gcode, const machine::MachineProfile& p,
                                      const std::vector<std::string>& sensors, const ProtocolLimits& limits) {
  std::vector<Violation> out;
  for (const auto& s : sensors) {
    const bool present = s == "accelerometer"      ? p.sensors.accelerometer
                         : s == "load_cell"        ? p.sensors.load_cell
                         : s == "filament_encoder" ? p.sensors.filament_encoder
                         : s == "camera"           ? p.sensors.camera
                         : s == "heater"           ? true  // every hot end has its thermistor
                                                   : false;
    if (!present)
      out.push_back({0, "",
                     fmt::format("the protocol needs {} {} and the profile has none ([sensors] {} = true)",
                                 s.find_first_of("aeiou") == 0 ? "an" : "a", s, s)});
  }
  // Size first: a protocol beyond the caps is not interpreted line by line.
  std::size_t bytes = 0;
  for (const auto& l : gcode) bytes += l.size() + 1;
  if (gcode.size() > limits.max_lines)
    out.push_back(
        {0, "", fmt::format("{} G-code lines exceed the limit of {} (--max-lines)", gcode.size(), limits.max_lines)});
  if (bytes > limits.max_bytes)
    out.push_back({0, "", fmt::format("{} bytes of G-code exceed the limit of {} bytes", bytes, limits.max_bytes)});
  if (!out.empty() && (gcode.size() > limits.max_lines || bytes > limits.max_bytes)) return out;
  // One element, one line: a line break inside one (a comment carrying a profile's text) would
  // print or send lines the gate never saw.
  const std::size_t before = out.size();
  for (std::size_t i = 0; i < gcode.size(); ++i)
    if (std::any_of(gcode[i].begin(), gcode[i].end(), [](char c) { return c == '\n' || c == '\r' || c == '\0'; }))
      out.push_back({i + 1, core::comment_safe(gcode[i]), "a G-code line holds a line break or NUL"});
  if (out.size() > before) return out;  // the other violations are listed with the rest

  machine::GcodeInterpreter in;
  home_to_minimums(in, p);
  const double tol = kLimitTolerance;
  for (std::size_t i = 0; i < gcode.size(); ++i) {
    auto add = [&](std::string what) { out.push_back({i + 1, gcode[i], std::move(what)}); };
    if (const auto bad = non_finite_word(gcode[i])) {
      add(fmt::format("'{}' is not a finite number", *bad));
      continue;
    }
    const auto w = machine::parse_gcode(gcode[i]);
    if (!w) continue;
    if (w->command == "G28") {
      home_to_minimums(in, p);
      continue;
    }
    const auto move = in.apply(*w);
    check_settings(*w, in, p, add);
    if (!move) continue;
    check_travel(*move, p, add);
    const auto u = move->unit();
    for (std::size_t k = 0; k < 3; ++k) {
      const std::string name = machine::kAxisNames[k];
      if (!p.axes.count(name)) continue;
      const auto& a = p.axes.at(name);
      const double v = move->feed_mm_s * std::abs(u[k]);
      if (v > a.max_velocity_mm_s + tol)
        add(fmt::format("{} speed {:.6g} mm/s exceeds max_velocity_mm_s {:g}", name, v, a.max_velocity_mm_s));
      const double acc = move->accel_mm_s2 * std::abs(u[k]);
      if (acc > a.max_accel_mm_s2 + tol)
        add(fmt::format("{} acceleration {:.6g} mm/s^2 exceeds max_accel_mm_s2 {:g}", name, acc, a.max_accel_mm_s2));
    }
    if (std::abs(move->end[3] - move->start[3]) > 1e-12) {
      const double ve = move->feed_mm_s * std::abs(u[3]);
      const double ae = move->accel_mm_s2 * std::abs(u[3]);
      const double flow = ve * p.filament_area_mm2();
      if (ve > p.extruder.max_velocity_mm_s + tol)
        add(fmt::format("filament feed {:.6g} mm/s exceeds [extruder] max_velocity_mm_s {:g}", ve,
                        p.extruder.max_velocity_mm_s));
      if (flow > p.extruder.max_flow_mm3_s + tol)
        add(fmt::format("volumetric flow {:.6g} mm^3/s exceeds max_flow_mm3_s {:g}", flow, p.extruder.max_flow_mm3_s));
      if (ae > p.extruder.max_accel_mm_s2 + tol)
        add(fmt::format("filament acceleration {:.6g} mm/s^2 exceeds [extruder] max_accel_mm_s2 {:g}", ae,
                        p.extruder.max_accel_mm_s2));
    }
  }
  if (out.empty()) {
    const double t = estimate_gcode_duration_s(gcode);
    if (!(t <= limits.max_duration_s))
      out.push_back(
          {0, "",
           fmt::format("the protocol takes {:.4g} s of machine time, more than the limit of {:g} s (--max-duration)", t,
                       limits.max_duration_s)});
  }
  return out;
}

void require_within_limits(const std::vector<std::string>& gcode, const machine::MachineProfile& profile,
                           const std::vector<std::string>& sensors, const ProtocolLimits& limits) {
  const auto v = check_protocol(gcode, profile, sensors, limits);
  if (v.empty()) return;
  constexpr std::size_t kListed = 20;
  std::string msg =
      fmt::format("refused: the protocol exceeds the machine profile in {} place{} (nothing was sent): ", v.size(),
                  v.size() == 1 ? "" : "s");
  for (std::size_t i = 0; i < v.size() && i < kListed; ++i) {
    if (i) msg += "; ";
    if (v[i].line) msg += fmt::format("G-code line {} '{}': ", v[i].line, v[i].gcode);
    msg += v[i].what;
  }
  if (v.size() > kListed) msg += fmt::format("; and {} more", v.size() - kListed);
  throw InputError(msg, profile.source_path);
}

SendGuard::SendGuard(const machine::MachineProfile& profile) : profile_(profile) { home_to_minimums(state_, profile_); }

std::optional<std::string> SendGuard::refuse(std::string_view line) {
  if (const auto bad = non_finite_word(line)) return fmt::format("'{}' is not a finite number", *bad);
  const auto w = machine::parse_gcode(line);
  if (!w) return std::nullopt;
  machine::GcodeInterpreter next = state_;
  if (w->command == "G28") {
    home_to_minimums(next, profile_);
  } else {
    std::vector<std::string> why;
    auto add = [&](std::string what) { why.push_back(std::move(what)); };
    const auto move = next.apply(*w);
    check_settings(*w, next, profile_, add);
    if (move) check_travel(*move, profile_, add);
    if (!why.empty()) {
      std::string all;
      for (const auto& x : why) all += (all.empty() ? "" : "; ") + x;
      return all;
    }
  }
  state_ = next;
  return std::nullopt;
}

}  // namespace tunekit::protocols
