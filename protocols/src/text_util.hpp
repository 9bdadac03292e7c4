#pragma once
// ASCII text helpers shared by the G-code dialect and firmware-configuration parsers
// (private to the protocols library).

#include <algorithm>
#include <cctype>
#include <string>

namespace tunekit::protocols::text {

/// `s` with ASCII letters in lower case (configuration keys and G-code words are ASCII).
inline std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

/// A blank inside a configuration line: space or tab.
inline bool is_blank(char c) { return c == ' ' || c == '\t'; }

}  // namespace tunekit::protocols::text
