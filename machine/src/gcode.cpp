#include "tunekit/machine/gcode.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>

#include <fmt/format.h>

namespace tunekit::machine {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

// strtod's syntax (what firmware's own number parsing accepts), without a heap copy for the
// short values G-code carries: the gate and the simulator parse every line of a protocol.
std::optional<double> to_number(std::string_view s) {
  if (s.empty()) return std::nullopt;
  constexpr std::size_t kShort = 64;
  char buf[kShort];
  std::string long_copy;
  const char* text = buf;
  if (s.size() < kShort) {
    std::copy(s.begin(), s.end(), buf);
    buf[s.size()] = '\0';
  } else {
    long_copy.assign(s);
    text = long_copy.c_str();
  }
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (end != text + s.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

bool is_space(char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; }
bool is_alpha(char c) { return std::isalpha(static_cast<unsigned char>(c)) != 0; }
char upper(char c) { return static_cast<char>(std::toupper(static_cast<unsigned char>(c))); }

/// The line without its comments (';' to the end, and parenthesised ones); `storage` holds the
/// text only when a parenthesised comment had to be cut out of the middle.
std::string_view strip_comments(std::string_view s, std::string& storage) {
  if (const auto semi = s.find(';'); semi != std::string_view::npos) s = s.substr(0, semi);
  if (s.find('(') == std::string_view::npos) return s;
  storage.assign(s);
  for (auto open = storage.find('('); open != std::string::npos; open = storage.find('(')) {
    const auto close = storage.find(')', open);
    storage.erase(open, close == std::string::npos ? std::string::npos : close - open + 1);
  }
  return storage;
}

/// Marlin's words after the command ("X10 Y5", also "X10Y5"): a letter, then its value up to the
/// next letter or space.
void parse_classic_words(std::string_view rest, GcodeWords& w) {
  std::size_t j = 0;
  while (j < rest.size()) {
    if (!is_alpha(rest[j])) {
      ++j;
      continue;
    }
    std::size_t k = j + 1;
    while (k < rest.size() && !is_alpha(rest[k]) && !is_space(rest[k])) ++k;
    const std::string key(1, upper(rest[j]));
    const auto value_text = rest.substr(j + 1, k - j - 1);
    if (const auto v = to_number(value_text)) w.args[key] = *v;
    else if (value_text.empty()) w.args[key] = 0;  // a bare flag such as "G28 X"
    else w.text_args[key] = std::string(value_text);
    j = k;
  }
}

/// Extended commands' KEY=VALUE words (Klipper's SET_VELOCITY_LIMIT ACCEL=3000).
void parse_extended_words(std::string_view rest, GcodeWords& w) {
  std::size_t i = 0;
  while (i < rest.size()) {
    while (i < rest.size() && is_space(rest[i])) ++i;
    const std::size_t b = i;
    while (i < rest.size() && !is_space(rest[i])) ++i;
    const auto token = rest.substr(b, i - b);
    const auto eq = token.find('=');
    if (token.empty() || eq == std::string_view::npos) continue;
    std::string key;
    for (char c : token.substr(0, eq)) key.push_back(upper(c));
    const auto value_text = token.substr(eq + 1);
    if (const auto v = to_number(value_text)) w.args[key] = *v;
    else w.text_args[key] = std::string(value_text);
  }
}

}  // namespace

double GcodeWords::get(const std::string& k, double fallback) const {
  const double* v = args.find(k);
  return v == nullptr ? fallback : *v;
}

int gcode_checksum(std::string_view text) {
  unsigned char cs = 0;
  for (char c : text) cs ^= static_cast<unsigned char>(c);
  return cs;
}

std::string numbered_line(long n, std::string_view command) {
  const std::string body = fmt::format("N{} {}", n, command);
  return fmt::format("{}*{}", body, gcode_checksum(body));
}

NumberedLine split_numbered(std::string_view raw) {
  NumberedLine out;
  std::string_view s = trim(raw);
  const auto star = s.rfind('*');
  if (star != std::string_view::npos) {
    const auto cs_text = trim(s.substr(star + 1));
    int cs = -1;
    const auto [p, ec] = std::from_chars(cs_text.data(), cs_text.data() + cs_text.size(), cs);
    out.checksum = (ec == std::errc() && p == cs_text.data() + cs_text.size()) ? cs : -1;
    out.checksum_ok = *out.checksum == gcode_checksum(s.substr(0, star));
    s = s.substr(0, star);
  }
  if (!s.empty() && (s[0] == 'N' || s[0] == 'n')) {
    std::size_t i = 1;
    while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]))) ++i;
    long n = 0;
    std::from_chars(s.data() + 1, s.data() + i, n);
    out.number = n;
    s = s.substr(i);
  }
  out.body = std::string(trim(s));
  return out;
}

std::optional<GcodeWords> parse_gcode(std::string_view line) {
  const NumberedLine numbered = split_numbered(line);
  std::string storage;
  const std::string_view s = trim(strip_comments(numbered.body, storage));
  if (s.empty()) return std::nullopt;
  GcodeWords w;
  std::size_t head_end = 0;
  while (head_end < s.size() && !is_space(s[head_end])) ++head_end;
  const std::string_view head = s.substr(0, head_end);
  const bool classic = head.size() >= 2 && is_alpha(head[0]) && std::isdigit(static_cast<unsigned char>(head[1])) &&
                       head.find('=') == std::string_view::npos;
  w.command.reserve(head.size());
  for (char c : head) w.command.push_back(upper(c));
  const std::string_view rest = s.substr(head_end);
  if (classic) parse_classic_words(rest, w);
  else parse_extended_words(rest, w);
  return w;
}

double GcodeMove::length_mm() const {
  const double dx = end[0] - start[0], dy = end[1] - start[1], dz = end[2] - start[2];
  const double l = std::sqrt(dx * dx + dy * dy + dz * dz);
  return l > 1e-12 ? l : std::abs(end[3] - start[3]);
}

bool GcodeMove::extruder_only() const {
  const double dx = end[0] - start[0], dy = end[1] - start[1], dz = end[2] - start[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz) <= 1e-12;
}

std::array<double, 4> GcodeMove::unit() const {
  std::array<double, 4> u{};
  const double l = length_mm();
  if (l <= 0) return u;
  for (std::size_t i = 0; i < 4; ++i) u[i] = (end[i] - start[i]) / l;
  return u;
}

GcodeInterpreter::GcodeInterpreter() = default;

std::optional<GcodeMove> GcodeInterpreter::apply(const GcodeWords& w) {
  dwell_s_ = 0;
  const std::string& c = w.command;
  if (c == "G0" || c == "G1") {
    if (w.has("F")) feed_mm_s_ = w.get("F", 0) / 60.0;
    GcodeMove m;
    m.start = pos_;
    m.end = pos_;
    for (std::size_t i = 0; i < 4; ++i) {
      const std::string key(1, static_cast<char>(std::toupper(static_cast<unsigned char>(kAxisNames[i][0]))));
      if (!w.has(key)) continue;
      const bool absolute = i < 3 ? absolute_xyz_ : absolute_e_;
      m.end[i] = absolute ? w.get(key, 0) : pos_[i] + w.get(key, 0);
    }
    pos_ = m.end;
    m.feed_mm_s = feed_mm_s_;
    if (m.length_mm() <= 1e-12) return std::nullopt;
    // The acceleration the firmware applies to this kind of move: extrude-only moves take the
    // retract acceleration (Marlin M204 R) or the extruder's M201 E (RepRapFirmware applies M204
    // to XY moves only), moves without E the travel acceleration (M204 T), others the print
    // acceleration; each is capped by the M201 maxima of the axes that move.
    double a = accel_mm_s2_;
    if (m.extruder_only()) {
      if (retract_accel_) a = *retract_accel_;
      else if (max_accel_[3]) a = *max_accel_[3];
    } else if (m.end[3] == m.start[3]) {
      a = travel_accel_;
    }
    const auto u = m.unit();
    for (std::size_t k = 0; k < 4; ++k)
      if (max_accel_[k] && u[k] > 1e-12) a = std::min(a, *max_accel_[k] / u[k]);
    m.accel_mm_s2 = a;
    return m;
  }
  if (c == "G4") dwell_s_ = w.has("S") ? w.get("S", 0) : w.get("P", 0) / 1000.0;
  else if (c == "G90") absolute_xyz_ = absolute_e_ = true;
  else if (c == "G91") absolute_xyz_ = absolute_e_ = false;
  else if (c == "M82") absolute_e_ = true;
  else if (c == "M83") absolute_e_ = false;
  else if (c == "G92") {
    for (std::size_t i = 0; i < 4; ++i) {
      const std::string key(1, static_cast<char>(std::toupper(static_cast<unsigned char>(kAxisNames[i][0]))));
      if (w.has(key)) pos_[i] = w.get(key, 0);
    }
  } else if (c == "M204") {
    if (w.has("S")) accel_mm_s2_ = travel_accel_ = w.get("S", accel_mm_s2_);
    if (w.has("P")) accel_mm_s2_ = w.get("P", accel_mm_s2_);
    if (w.has("T")) travel_accel_ = w.get("T", travel_accel_);
    if (w.has("P") && !w.has("T")) travel_accel_ = accel_mm_s2_;
    if (w.has("R")) retract_accel_ = w.get("R", 0);
  } else if (c == "M201") {
    for (std::size_t i = 0; i < 4; ++i) {
      const std::string key(1, static_cast<char>(std::toupper(static_cast<unsigned char>(kAxisNames[i][0]))));
      if (w.has(key)) max_accel_[i] = w.get(key, 0);
    }
  } else if (c == "SET_VELOCITY_LIMIT") {
    if (w.has("ACCEL")) accel_mm_s2_ = travel_accel_ = w.get("ACCEL", accel_mm_s2_);
  } else if (c == "M104" || c == "M109") {
    if (w.has("S")) hotend_c = w.get("S", 0);
    else if (w.has("R")) hotend_c = w.get("R", 0);
  } else if (c == "M140" || c == "M190") {
    if (w.has("S")) bed_c = w.get("S", 0);
  }
  return std::nullopt;
}

}  // namespace tunekit::machine
