#pragma once
// ASCII text helpers shared by the layers that read names out of files and command lines:
// CSV column names, window and model names, firmware configuration keys, G-code words. All of
// them are ASCII by their formats' definitions, so case folding is byte-wise and ignores the
// locale; bytes outside ASCII pass through unchanged.

#include <cctype>
#include <cstddef>
#include <string>
#include <string_view>

namespace tunekit::core {

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

}  // namespace tunekit::core
