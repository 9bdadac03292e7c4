#include "tunekit/firmware/dialect.hpp"
#include "text_util.hpp"
#include "tunekit/core/error.hpp"

#include <algorithm>
#include <cctype>
#include <cstdlib>

#include <cmath>

#include <fmt/format.h>

namespace tunekit::firmware {
namespace {

/// Value after "KEY:" up to the next " UPPERCASE_KEY:" token.
std::string field(const std::string& line, const std::string& key) {
  const auto p = line.find(key + ":");
  if (p == std::string::npos) return {};
  std::size_t b = p + key.size() + 1;
  while (b < line.size() && line[b] == ' ') ++b;
  std::size_t e = b;
  while (e < line.size()) {
    if (line[e] == ' ') {
      std::size_t k = e + 1;
      while (k < line.size() && (std::isupper(static_cast<unsigned char>(line[k])) || line[k] == '_')) ++k;
      if (k > e + 1 && k < line.size() && line[k] == ':') break;
    }
    ++e;
  }
  return line.substr(b, e - b);
}

}  // namespace

std::string to_string(Firmware f) {
  switch (f) {
    case Firmware::marlin: return "marlin";
    case Firmware::prusa: return "prusa";
    case Firmware::klipper: return "klipper";
    case Firmware::reprapfirmware: return "rrf";
    default: return "unknown";
  }
}

Firmware firmware_from_name(const std::string& name) {
  const std::string n = core::lower(name);
  if (n == "marlin") return Firmware::marlin;
  if (n == "prusa") return Firmware::prusa;
  if (n == "klipper") return Firmware::klipper;
  if (n == "rrf" || n == "reprapfirmware") return Firmware::reprapfirmware;
  return Firmware::unknown;
}

bool FirmwareInfo::sensor_stream() const {
  const auto it = capabilities.find("TUNEKIT_SENSOR_STREAM");
  return it != capabilities.end() && it->second;
}

FirmwareInfo parse_m115(const std::vector<std::string>& lines) {
  FirmwareInfo info;
  for (const auto& raw : lines) {
    std::string line = raw;
    if (line.rfind("ok ", 0) == 0) line = line.substr(3);
    if (line.rfind("Cap:", 0) == 0) {
      const auto colon = line.rfind(':');
      if (colon > 4) info.capabilities[line.substr(4, colon - 4)] = line.substr(colon + 1) == "1";
      continue;
    }
    if (line.find("FIRMWARE_NAME:") == std::string::npos || info.firmware != Firmware::unknown) continue;
    info.name = field(line, "FIRMWARE_NAME");
    info.version = field(line, "FIRMWARE_VERSION");
    const std::string n = core::lower(info.name);
    if (n.find("prusa") != std::string::npos) info.firmware = Firmware::prusa;
    else if (n.find("klipper") != std::string::npos) info.firmware = Firmware::klipper;
    else if (n.find("reprapfirmware") != std::string::npos) info.firmware = Firmware::reprapfirmware;
    else if (n.find("marlin") != std::string::npos) info.firmware = Firmware::marlin;
    if (info.version.empty()) {
      // Marlin and Prusa put the version after the name: "Marlin 2.1.2.1 (...)".
      const auto sp = info.name.find(' ');
      if (sp != std::string::npos) {
        auto v = info.name.substr(sp + 1);
        info.version = v.substr(0, v.find(' '));
      }
    }
  }
  return info;
}

std::string Dialect::set_accel(double a) const {
  // Whole mm/s^2, rounded down: the acceleration set never exceeds the one the protocol was
  // checked with (a limit of 332.6 is written 332, not 333).
  const double w = std::floor(a);
  switch (fw_) {
    case Firmware::klipper: return fmt::format("SET_VELOCITY_LIMIT ACCEL={:.0f}", w);
    case Firmware::reprapfirmware: return fmt::format("M204 P{0:.0f} T{0:.0f}", w);
    // Marlin: P (printing moves) and T (travel moves, those without E); M204 S is deprecated.
    default: return fmt::format("M204 P{0:.0f} T{0:.0f}", w);
  }
}

std::string Dialect::set_hotend(double t, bool wait) const {
  if (!wait) return fmt::format("M104 S{:.0f}", t);
  // Marlin and RepRapFirmware: M109 S waits only while heating, M109 R also while cooling
  // (Marlin/src/gcode/temp/M104_M109.cpp). Klipper's M109 waits from either side.
  if (fw_ == Firmware::klipper) return fmt::format("M109 S{:.0f}", t);
  return fmt::format("M109 R{:.0f}", t);
}

std::vector<std::string> Dialect::safe_state(bool heaters_off) const {
  std::vector<std::string> out;
  switch (fw_) {
    case Firmware::klipper:
      // Klipper has no quick stop short of an emergency shutdown; M112 stops motion at once.
      out.push_back("M112");
      break;
    // RepRapFirmware has no M410 (GCodes2.cpp has no case 410: it falls through to a macro
    // lookup and answers "not supported"); M112 is its documented emergency stop.
    case Firmware::reprapfirmware: out.push_back("M112"); break;
    default: out.push_back("M410"); break;  // Marlin/Prusa quickstop: stop all steppers now
  }
  if (heaters_off)
    for (auto& l : this->heaters_off()) out.push_back(std::move(l));
  return out;
}

std::vector<std::string> Dialect::heaters_off() const {
  if (fw_ == Firmware::klipper) return {"TURN_OFF_HEATERS"};
  return {"M104 S0", "M140 S0"};
}

std::string klipper_param_value(const std::string& value) {
  // A line break or other control character would end or corrupt the G-code line it is sent in:
  // such a value (a machine's answer, a profile's text) is refused before anything is sent.
  if (std::any_of(value.begin(), value.end(), [](char c) { return std::iscntrl(static_cast<unsigned char>(c)); }))
    throw InputError("a Klipper parameter value holds a line break or another control character; it is not sent");
  const bool plain = !value.empty() && std::none_of(value.begin(), value.end(), [](char c) {
    return std::isspace(static_cast<unsigned char>(c)) || c == '"' || c == '\'' || c == '\\' || c == '#' || c == ';';
  });
  if (plain) return value;
  std::string q = "\"";
  for (char c : value) {
    if (c == '"' || c == '\\') q += '\\';
    q += c;
  }
  return q + "\"";
}

std::string Dialect::sensor_stream(const std::string& sensor, bool on) const {
  if (fw_ == Firmware::klipper) return {};
  const char* code = sensor == "accelerometer" ? "A" : sensor == "load_cell" ? "L" : sensor == "heater" ? "H" : "F";
  return fmt::format("M4100 {}{}", code, on ? 1 : 0);
}

}  // namespace tunekit::firmware
