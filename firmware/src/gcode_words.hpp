#pragma once
// Internal: reading the words of a sliced G-code line, shared by the G-code post-processors
// (gcode_advance.cpp, bed_mass_export.cpp).

#include <cctype>
#include <optional>
#include <stdexcept>
#include <string>

namespace tunekit::firmware::gcode_words {

/// The line upper-cased (ASCII).
inline std::string upper(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

/// The code part of a line (before ';'), trimmed.
inline std::string code(const std::string& line) {
  std::string c = line.substr(0, line.find(';'));
  const auto b = c.find_first_not_of(" \t");
  if (b == std::string::npos) return {};
  const auto e = c.find_last_not_of(" \t\r");
  return c.substr(b, e - b + 1);
}

/// Value of word `letter` in a G-code line's code ("G1 X10.5 E0.2"), if present.
inline std::optional<double> word(const std::string& code, char letter) {
  for (std::size_t i = 0; i < code.size(); ++i) {
    if (std::toupper(static_cast<unsigned char>(code[i])) != letter) continue;
    if (i > 0 && code[i - 1] != ' ' && code[i - 1] != '\t') continue;
    try {
      std::size_t used = 0;
      const double v = std::stod(code.substr(i + 1), &used);
      if (used > 0) return v;
    } catch (const std::logic_error&) {
    }
  }
  return std::nullopt;
}

/// Klipper-style KEY=value parameter.
inline std::optional<double> param(const std::string& code, const std::string& key) {
  const std::string u = upper(code);
  const auto p = u.find(" " + key + "=");
  if (p == std::string::npos) return std::nullopt;
  try {
    return std::stod(code.substr(p + key.size() + 2));
  } catch (const std::logic_error&) {
    return std::nullopt;
  }
}

/// The command word ("G1", "SET_INPUT_SHAPER"), upper-cased.
inline std::string command(const std::string& code) {
  const auto sp = code.find_first_of(" \t");
  return upper(code.substr(0, sp));
}

}  // namespace tunekit::firmware::gcode_words
