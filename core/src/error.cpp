#include "tunekit/core/error.hpp"

namespace tunekit {

namespace {

// What a lead byte of well-formed UTF-8 starts (RFC 3629, section 4): the sequence's length and
// the range of its second byte, which rules out overlong forms, surrogates and code points above
// U+10FFFF; a length of 0 for a byte that starts no sequence.
struct Utf8Lead {
  std::size_t length;
  unsigned char second_min, second_max;
};

Utf8Lead utf8_lead(unsigned char b) {
  if (b >= 0xc2 && b <= 0xdf) return {2, 0x80, 0xbf};
  if (b == 0xe0) return {3, 0xa0, 0xbf};
  if (b == 0xed) return {3, 0x80, 0x9f};
  if (b >= 0xe1 && b <= 0xef) return {3, 0x80, 0xbf};
  if (b == 0xf0) return {4, 0x90, 0xbf};
  if (b >= 0xf1 && b <= 0xf3) return {4, 0x80, 0xbf};
  if (b == 0xf4) return {4, 0x80, 0x8f};
  return {0, 0, 0};
}

// The length of the well-formed UTF-8 sequence at text[i], or 0 if there is none.
std::size_t utf8_sequence_length(std::string_view text, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const Utf8Lead lead = utf8_lead(byte(i));
  if (lead.length == 0 || i + lead.length > text.size()) return 0;
  if (byte(i + 1) < lead.second_min || byte(i + 1) > lead.second_max) return 0;
  for (std::size_t k = 2; k < lead.length; ++k)
    if (byte(i + k) < 0x80 || byte(i + k) > 0xbf) return 0;
  return lead.length;
}

bool is_printable_ascii(unsigned char c) { return (c >= 0x20 && c < 0x7f) || c == '\n' || c == '\t'; }

}  // namespace

std::string printable_message(std::string_view text) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size();) {
    const auto c = static_cast<unsigned char>(text[i]);
    const std::size_t n = c < 0x80 ? (is_printable_ascii(c) ? 1 : 0) : utf8_sequence_length(text, i);
    if (n > 0) {
      out.append(text.substr(i, n));
      i += n;
      continue;
    }
    out += {'\\', 'x', kHex[c >> 4], kHex[c & 0xf]};
    ++i;
  }
  return out;
}

Error::Error(ExitCode code, std::string message, std::string location)
    : std::runtime_error(printable_message(location.empty() ? message : location + ": " + message)),
      code_(code),
      message_(printable_message(message)),
      location_(printable_message(location)) {}

std::string Error::formatted() const {
  std::string s = "tunekit: error: ";
  if (!location_.empty()) s += location_ + ": ";
  s += message_;
  return s;
}

std::string source_location(const std::string& file, std::size_t line, std::size_t column) {
  std::string s = file + ":" + std::to_string(line);
  if (column > 0) s += ":" + std::to_string(column);
  return s;
}

}  // namespace tunekit
