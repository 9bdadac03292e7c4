// Marlin configuration headers: active defines, conditions, value expressions (marlin_header.hpp).
#include "marlin_header.hpp"

#include <cctype>
#include <filesystem>
#include <optional>
#include <sstream>
#include <vector>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/core/text.hpp"
#include "tunekit/firmware/config_edit.hpp"

namespace tunekit::machine::detail {
namespace {

std::string header_trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

bool ident_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

/// Recursive descent over a value expression; nesting is bounded (a line of 100,000 '(' is an
/// error, not a stack overflow).
class Evaluator {
 public:
  Evaluator(const MarlinDefines& d, const Site& site, int depth) : d_(d), site_(site), depth_(depth) {}
  double eval(const std::string& text) {
    s_ = text;
    i_ = 0;
    const double v = sum();
    skip();
    if (i_ != s_.size()) fail();
    return v;
  }

 private:
  void skip() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  [[noreturn]] void fail() const {
    throw InputError(fmt::format("cannot evaluate '{}' (numbers, other defines and + - * / only)", shown(s_)),
                     site_.where());
  }
  double sum() {
    double v = product();
    for (skip(); i_ < s_.size() && (s_[i_] == '+' || s_[i_] == '-'); skip()) {
      const char op = s_[i_++];
      const double r = product();
      v = op == '+' ? v + r : v - r;
    }
    return v;
  }
  double product() {
    double v = unary();
    for (skip(); i_ < s_.size() && (s_[i_] == '*' || s_[i_] == '/'); skip()) {
      const char op = s_[i_++];
      const double r = unary();
      v = op == '*' ? v * r : v / r;
    }
    return v;
  }
  double unary();
  double parenthesized() {
    ++i_;
    const double v = sum();
    skip();
    if (i_ >= s_.size() || s_[i_] != ')') fail();
    ++i_;
    return v;
  }
  double atom();
  static constexpr int kMaxNesting = 64;
  const MarlinDefines& d_;
  const Site& site_;
  int depth_;
  int nesting_ = 0;
  std::string s_;
  std::size_t i_ = 0;
};

double Evaluator::unary() {
  skip();
  if (++nesting_ > kMaxNesting) fail();
  double v = 0;
  if (i_ < s_.size() && (s_[i_] == '-' || s_[i_] == '+')) v = s_[i_++] == '-' ? -unary() : unary();
  else if (i_ < s_.size() && s_[i_] == '(') v = parenthesized();
  else v = atom();
  --nesting_;
  return v;
}

double Evaluator::atom() {
  const std::size_t start = i_;
  while (i_ < s_.size() && (ident_char(s_[i_]) || s_[i_] == '.')) ++i_;
  std::string word = s_.substr(start, i_ - start);
  if (word.empty()) fail();
  if (std::isdigit(static_cast<unsigned char>(word[0])) || word[0] == '.') {
    while (!word.empty() && (word.back() == 'f' || word.back() == 'F' || word.back() == 'L' || word.back() == 'U'))
      word.pop_back();
    const auto v = core::parse_decimal(word);
    if (!v) fail();
    return *v;
  }
  skip();
  if ((word == "double" || word == "float" || word == "int" || word == "long") && i_ < s_.size() && s_[i_] == '(')
    return parenthesized();  // a cast: double(XYZ_BELT_PITCH)
  const auto it = d_.find(word);
  if (it == d_.end() || depth_ > 16 || it->second.value.empty()) fail();
  return Evaluator(d_, it->second.site, depth_ + 1).eval(it->second.value);
}

enum class Tri { no, yes, unknown };

Tri tri_not(Tri a) { return a == Tri::unknown ? a : a == Tri::yes ? Tri::no : Tri::yes; }
Tri tri_and(Tri a, Tri b) {
  if (a == Tri::no || b == Tri::no) return Tri::no;
  return a == Tri::yes && b == Tri::yes ? Tri::yes : Tri::unknown;
}
Tri tri_or(Tri a, Tri b) {
  if (a == Tri::yes || b == Tri::yes) return Tri::yes;
  return a == Tri::no && b == Tri::no ? Tri::no : Tri::unknown;
}

/// A preprocessor condition as far as the configuration itself decides it.
class Condition {
 public:
  Condition(const MarlinDefines& d, const std::string& text) : d_(d), s_(text) {}
  Tri eval() {
    const Tri t = any_or();
    skip();
    return i_ == s_.size() ? t : Tri::unknown;
  }

 private:
  void skip() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  bool take(const char* op) {
    skip();
    const std::string o(op);
    if (s_.compare(i_, o.size(), o) != 0) return false;
    i_ += o.size();
    return true;
  }
  Tri any_or() {
    Tri t = all_and();
    while (!bail() && take("||")) t = tri_or(t, all_and());
    return t;
  }
  Tri all_and() {
    Tri t = negation();
    while (!bail() && take("&&")) t = tri_and(t, negation());
    return t;
  }
  Tri negation() {
    if (bail()) return Tri::unknown;
    if (take("!") && !take("=")) return tri_not(negation());
    return primary();
  }
  bool bail() { return ++steps_ > 4096; }
  Tri primary();
  Tri macro(const std::string& name);
  std::vector<std::string> names();
  const MarlinDefines& d_;
  std::string s_;
  std::size_t i_ = 0;
  int steps_ = 0;
};

std::vector<std::string> Condition::names() {
  std::vector<std::string> out;
  if (!take("(")) return out;
  for (;;) {
    skip();
    const std::size_t start = i_;
    while (i_ < s_.size() && ident_char(s_[i_])) ++i_;
    out.push_back(s_.substr(start, i_ - start));
    if (take(")")) return out;
    if (!take(",")) return {};
  }
}

Tri Condition::macro(const std::string& name) {
  const auto list = names();
  if (list.empty()) return Tri::unknown;
  auto enabled = [&](const std::string& n) {
    if (d_.count(n)) return marlin_enabled(d_, n) ? Tri::yes : Tri::no;
    // Marlin's own derived names (HAS_..., IS_...) are not in the configuration.
    return n.rfind("HAS_", 0) == 0 || n.rfind("IS_", 0) == 0 ? Tri::unknown : Tri::no;
  };
  Tri all = Tri::yes, any = Tri::no;
  for (const auto& n : list) {
    const Tri e = name == "defined" ? (d_.count(n) ? Tri::yes : Tri::no) : enabled(n);
    all = tri_and(all, e);
    any = tri_or(any, e);
  }
  if (name == "ENABLED" || name == "defined" || name == "ALL" || name == "BOTH") return all;
  if (name == "DISABLED") return tri_not(all);
  if (name == "ANY" || name == "EITHER") return any;
  if (name == "NONE") return tri_not(any);
  return Tri::unknown;
}

Tri Condition::primary() {
  skip();
  if (take("(")) {
    const Tri t = any_or();
    return take(")") ? t : Tri::unknown;
  }
  const std::size_t start = i_;
  while (i_ < s_.size() && ident_char(s_[i_])) ++i_;
  const std::string word = s_.substr(start, i_ - start);
  skip();
  if (!word.empty() && i_ < s_.size() && s_[i_] == '(') return macro(word);
  if (word == "defined") {  // defined NAME, without parentheses
    const std::size_t n0 = i_;
    while (i_ < s_.size() && ident_char(s_[i_])) ++i_;
    return d_.count(s_.substr(n0, i_ - n0)) ? Tri::yes : Tri::no;
  }
  // A value, maybe compared with another: known only when both are numbers of the configuration.
  auto value = [&](const std::string& w) -> std::optional<double> {
    if (const auto v = core::parse_decimal(w)) return v;
    const auto it = d_.find(w);
    if (it == d_.end()) return std::nullopt;
    try {
      return eval_marlin_expression(d_, it->second.value, it->second.site);
    } catch (const Error&) {
      return std::nullopt;
    }
  };
  const auto a = value(word);
  for (const char* op : {"==", "!=", ">=", "<=", ">", "<"}) {
    if (!take(op)) continue;
    skip();
    const std::size_t b0 = i_;
    while (i_ < s_.size() && (ident_char(s_[i_]) || s_[i_] == '.')) ++i_;
    const auto b = value(s_.substr(b0, i_ - b0));
    if (!a || !b) return Tri::unknown;
    const std::string o(op);
    const bool r = o == "=="   ? *a == *b
                   : o == "!=" ? *a != *b
                   : o == ">=" ? *a >= *b
                   : o == "<=" ? *a <= *b
                   : o == ">"  ? *a > *b
                               : *a < *b;
    return r ? Tri::yes : Tri::no;
  }
  if (!a) return Tri::unknown;
  return *a != 0 ? Tri::yes : Tri::no;
}

/// One #if ... #endif block: whether its enclosing block is active, whether a branch was surely
/// taken, and whether the current branch is active.
struct Frame {
  bool parent = true, taken = false, active = true;
};

/// Applies a preprocessor directive (`t` without the '#'); false when it is none of the conditionals.
bool conditional(const std::string& t, const MarlinDefines& d, std::vector<Frame>& stack) {
  const auto word_end = t.find_first_of(" \t(");
  const std::string word = t.substr(0, word_end);
  const std::string rest = word_end == std::string::npos ? "" : header_trim(t.substr(word_end));
  const bool here = stack.empty() || stack.back().active;
  auto branch = [&](Frame& f, Tri c) {
    f.active = f.parent && !f.taken && c != Tri::no;
    if (c == Tri::yes && f.parent && !f.taken) f.taken = true;
  };
  if (word == "if" || word == "ifdef" || word == "ifndef") {
    Frame f{here, false, false};
    const Tri c = word == "if"      ? Condition(d, rest).eval()
                  : word == "ifdef" ? (d.count(rest) ? Tri::yes : Tri::no)
                                    : (d.count(rest) ? Tri::no : Tri::yes);
    branch(f, c);
    stack.push_back(f);
  } else if (word == "elif" && !stack.empty()) {
    branch(stack.back(), Condition(d, rest).eval());
  } else if (word == "else" && !stack.empty()) {
    stack.back().active = stack.back().parent && !stack.back().taken;
  } else if (word == "endif" && !stack.empty()) {
    stack.pop_back();
  } else {
    return false;
  }
  return true;
}

/// The line without comments; `block` carries an open /* ... */ over lines.
std::string code_of(std::string line, bool& block) {
  if (block) {
    const auto end = line.find("*/");
    if (end == std::string::npos) return {};
    line = line.substr(end + 2);
    block = false;
  }
  if (const auto open = line.find("/*"); open != std::string::npos) {
    const auto close = line.find("*/", open);
    if (close == std::string::npos) {
      line = line.substr(0, open);
      block = true;
    } else {
      line.erase(open, close + 2 - open);
    }
  }
  return header_trim(line.substr(0, line.find("//")));
}

void define_line(const std::string& t, const Site& site, MarlinDefines& out) {
  std::size_t k = 0;
  while (k < t.size() && ident_char(t[k])) ++k;
  if (k == 0 || (k < t.size() && t[k] == '(')) return;  // function-like macros are not settings
  out.try_emplace(t.substr(0, k), MarlinDefine{header_trim(t.substr(k)), site});
}

}  // namespace

bool marlin_enabled(const MarlinDefines& defines, const std::string& name) {
  const auto it = defines.find(name);
  if (it == defines.end()) return false;
  const std::string& v = it->second.value;
  return v.empty() || v == "1" || v == "true";
}

double eval_marlin_expression(const MarlinDefines& defines, const std::string& text, const Site& site) {
  return Evaluator(defines, site, 0).eval(text);
}

void read_marlin_defines(const std::string& path, MarlinDefines& out) {
  std::istringstream in(firmware::read_config_file(path));
  bool block = false;
  std::vector<Frame> stack;
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);) {
    ++n;
    std::string t = code_of(line, block);
    if (t.empty() || t[0] != '#') continue;
    t = header_trim(t.substr(1));
    if (conditional(t, out, stack) || !(stack.empty() || stack.back().active)) continue;
    const Site site{path, n, header_trim(line.substr(0, line.find("//")))};
    if (t.rfind("define", 0) == 0 && t.size() > 6 && std::isspace(static_cast<unsigned char>(t[6])))
      define_line(header_trim(t.substr(6)), site, out);
    else if (t.rfind("undef", 0) == 0 && t.size() > 5 && std::isspace(static_cast<unsigned char>(t[5])))
      out.erase(header_trim(t.substr(5)));
  }
}

}  // namespace tunekit::machine::detail
