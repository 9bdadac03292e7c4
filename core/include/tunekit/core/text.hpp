#pragma once
// ASCII text helpers shared by the layers that read names out of files and command lines:
// CSV column names, window and model names, firmware configuration keys, G-code words. All of
// them are ASCII by their formats' definitions, so case folding is byte-wise and ignores the
// locale; bytes outside ASCII pass through unchanged.

#include <cctype>
#include <charconv>
#include <cstddef>
#include <cstdlib>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>

namespace tunekit::core {

/// `text` (a profile's name, a machine id, a file name) made safe to put in a G-code or
/// configuration comment: every control character (a line break would start a live line after
/// the comment) becomes '?'; the rest is kept as it is.
inline std::string comment_safe(std::string_view text) {
  std::string out(text);
  for (char& c : out)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
  return out;
}

/// `s` with the ASCII letters A-Z in lower case.
inline std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

/// Case-insensitive equality on ASCII letters (other bytes compare exactly).
inline bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const auto ca = static_cast<unsigned char>(a[i]), cb = static_cast<unsigned char>(b[i]);
    if (std::tolower(ca) != std::tolower(cb)) return false;
  }
  return true;
}

/// Whether `s` is a plain decimal number as people type one: an optional sign, digits with an
/// optional decimal point, and an optional exponent ("12", "-0.5", ".5", "1e-3"). Hexadecimal
/// ("0x10", which strtod reads as 16), "inf", "nan", white space and trailing text are not.
inline bool is_decimal_number(std::string_view s) {
  std::size_t i = 0, digits = 0;
  auto is_digit = [&](std::size_t k) { return k < s.size() && s[k] >= '0' && s[k] <= '9'; };
  if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
  while (is_digit(i)) ++i, ++digits;
  if (i < s.size() && s[i] == '.') {
    ++i;
    while (is_digit(i)) ++i, ++digits;
  }
  if (digits == 0) return false;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
    if (!is_digit(i)) return false;
    while (is_digit(i)) ++i;
  }
  return i == s.size();
}

/// The value of a plain decimal number (is_decimal_number()); nullopt for anything else. A
/// number beyond a double's range reads as +-inf or, below the smallest, as 0 or a denormal:
/// callers range-check the value.
inline std::optional<double> parse_decimal(std::string_view s) {
  if (!is_decimal_number(s)) return std::nullopt;
  const std::string text(s);
  return std::strtod(text.c_str(), nullptr);
}

/// Appends `v` with `decimals` digits after the point, as printf's "%.*f" writes it (correctly
/// rounded, "-0.00" for a small negative). For the sensor streams, hundreds of thousands of
/// numbers per run: std::to_chars needs no format string and no allocation. `decimals` <= 60
/// (the buffer holds the largest double's 309 integer digits with them).
inline void append_fixed(std::string& out, double v, int decimals) {
  char buf[400];
  const auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed, decimals);
  out.append(buf, r.ec == std::errc() ? r.ptr : buf);
}

/// A value and the decimals it is written with (the resolution of its column or field).
struct FixedField {
  double value;
  int decimals;
};

/// Appends the fields with append_fixed(), `separator` between them (a CSV row, a sensor line).
inline void append_fixed_fields(std::string& out, char separator, std::initializer_list<FixedField> fields) {
  bool first = true;
  for (const auto& f : fields) {
    if (!first) out.push_back(separator);
    first = false;
    append_fixed(out, f.value, f.decimals);
  }
}

}  // namespace tunekit::core
