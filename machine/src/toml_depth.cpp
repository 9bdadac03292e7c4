#include "toml_depth.hpp"

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::machine::detail {
namespace {

bool is_bare_key_char(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
}

/// Scans the text outside strings and comments and counts the parts of each run `p.p.p`
/// (bare or quoted parts, blanks allowed around the dots, as in TOML's dotted keys).
class DepthScanner {
 public:
  DepthScanner(std::string_view text, const std::string& path) : t_(text), path_(path) {}

  void run() {
    while (i_ < t_.size()) step();
  }

 private:
  void step() {
    const char c = t_[i_];
    if (c == '#') skip_comment();
    else if (c == '"' || c == '\'') {
      skip_string(c);
      part();
    } else if (is_bare_key_char(c)) {
      skip_bare();
      part();
    } else if (c == ' ' || c == '\t') ++i_;
    else dot_or_break(c);
  }

  void dot_or_break(char c) {
    dot_ = c == '.' && after_part_;
    if (!dot_) depth_ = 0;
    after_part_ = false;
    if (c == '\n') ++line_;
    ++i_;
  }

  void part() {
    depth_ = dot_ ? depth_ + 1 : 1;
    dot_ = false;
    after_part_ = true;
    if (depth_ > kMaxDottedKeyDepth)
      throw InputError(fmt::format("a dotted key or table header nests more than {} levels deep (the most a "
                                   "machine profile accepts)",
                                   kMaxDottedKeyDepth),
                       source_location(path_, line_));
  }

  void skip_comment() {
    while (i_ < t_.size() && t_[i_] != '\n') ++i_;
  }

  void skip_bare() {
    while (i_ < t_.size() && is_bare_key_char(t_[i_])) ++i_;
  }

  void skip_string(char quote) {
    const std::string closing = at(std::string(3, quote)) ? std::string(3, quote) : std::string(1, quote);
    i_ += closing.size();
    while (i_ < t_.size() && !at(closing)) {
      if (t_[i_] == '\n' && closing.size() == 1) return;  // unterminated: the parser reports it
      if (t_[i_] == '\n') ++line_;
      i_ += t_[i_] == '\\' && quote == '"' ? 2 : 1;
    }
    i_ += closing.size();
  }

  bool at(const std::string& s) const { return t_.substr(i_, s.size()) == s; }

  std::string_view t_;
  const std::string& path_;
  std::size_t i_ = 0, line_ = 1, depth_ = 0;
  bool dot_ = false, after_part_ = false;
};

}  // namespace

void check_dotted_key_depth(std::string_view text, const std::string& path) { DepthScanner(text, path).run(); }

}  // namespace tunekit::machine::detail
