#include "tunekit/firmware/orca_profile.hpp"

#include <algorithm>
#include <cmath>
#include <set>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "tunekit/core/json_error_text.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/firmware/config_edit.hpp"
#include "tunekit/firmware/firmware_limits.hpp"

namespace tunekit::firmware {
namespace {

/// One top-level member's byte spans.
struct OrcaMember {
  std::string key;
  std::size_t begin = 0;  // opening quote of the key
  std::size_t value_begin = 0;
  std::size_t value_end = 0;  // one past the value
};

class OrcaScanner {
 public:
  OrcaScanner(const std::string& t, const std::string& path) : t_(t), path_(path) {}

  std::vector<OrcaMember> members() {
    std::vector<OrcaMember> out;
    ws();
    expect('{');
    ws();
    if (peek() == '}') return out;
    for (;;) {
      ws();
      OrcaMember m;
      m.begin = i_;
      m.key = string_value();
      ws();
      expect(':');
      ws();
      m.value_begin = i_;
      skip_value();
      m.value_end = i_;
      out.push_back(m);
      ws();
      if (peek() == ',') {
        ++i_;
        continue;
      }
      expect('}');
      break;
    }
    return out;
  }

  /// Spans of the string elements of the array starting at `at` (which must be '[').
  std::vector<std::pair<std::size_t, std::size_t>> array_strings(std::size_t at) {
    i_ = at;
    std::vector<std::pair<std::size_t, std::size_t>> out;
    expect('[');
    ws();
    if (peek() == ']') return out;
    for (;;) {
      ws();
      const std::size_t b = i_;
      if (peek() == '"') {
        string_value();
        out.emplace_back(b, i_);
      } else {
        skip_value();
      }
      ws();
      if (peek() == ',') {
        ++i_;
        continue;
      }
      expect(']');
      break;
    }
    return out;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(fmt::format("not an OrcaSlicer profile (JSON object): {} at byte {}", what, i_), path_);
  }
  char peek() const {
    if (i_ >= t_.size()) fail("unexpected end");
    return t_[i_];
  }
  void ws() {
    while (i_ < t_.size() && (t_[i_] == ' ' || t_[i_] == '\t' || t_[i_] == '\n' || t_[i_] == '\r')) ++i_;
  }
  void expect(char c) {
    if (peek() != c) fail(fmt::format("expected '{}'", c));
    ++i_;
  }
  std::string string_value() {
    expect('"');
    const std::size_t b = i_;
    while (peek() != '"') i_ += t_[i_] == '\\' ? 2 : 1;
    ++i_;
    return t_.substr(b, i_ - b - 1);
  }
  void skip_value() {
    const char c = peek();
    if (c == '"') {
      string_value();
      return;
    }
    if (c == '{' || c == '[') {
      int depth = 0;
      do {
        const char d = peek();
        if (d == '"') {
          string_value();
          continue;
        }
        if (d == '{' || d == '[') ++depth;
        if (d == '}' || d == ']') --depth;
        ++i_;
      } while (depth > 0);
      return;
    }
    while (i_ < t_.size() && t_[i_] != ',' && t_[i_] != '}' && t_[i_] != ']' && t_[i_] != ' ' && t_[i_] != '\n' &&
           t_[i_] != '\r' && t_[i_] != '\t')
      ++i_;
  }

  const std::string& t_;
  std::string path_;
  std::size_t i_ = 0;
};

std::string orca_json_string(const std::string& s) { return nlohmann::json(s).dump(); }

/// Whitespace before position `pos` back to the line start (the member's indentation).
std::string orca_indent_before(const std::string& t, std::size_t pos) {
  std::size_t b = pos;
  while (b > 0 && (t[b - 1] == ' ' || t[b - 1] == '\t')) --b;
  return t.substr(b, pos - b);
}

}  // namespace

std::string orca_model_text(const std::vector<design::OrcaPoint>& table) {
  namespace L = limits;
  if (table.size() < 2) throw InputError("OrcaSlicer's adaptive pressure advance needs at least two lines");
  std::vector<design::OrcaPoint> t = table;
  for (const auto& p : t) {
    if (!(std::isfinite(p.k_s) && p.k_s >= 0 && p.k_s <= L::kOrcaAdvanceMax_s))
      throw InputError(
          fmt::format("refusing to write OrcaSlicer's adaptive pressure advance: advance {} s is outside "
                      "0..{} s",
                      p.k_s, L::kOrcaAdvanceMax_s));
    if (!(std::isfinite(p.flow_mm3_s) && p.flow_mm3_s > 0))
      throw InputError(
          fmt::format("refusing to write OrcaSlicer's adaptive pressure advance: flow {} mm^3/s is not "
                      "positive",
                      p.flow_mm3_s));
    if (!(std::isfinite(p.accel_mm_s2) && p.accel_mm_s2 >= 0))
      throw InputError(
          fmt::format("refusing to write OrcaSlicer's adaptive pressure advance: acceleration {} mm/s^2 "
                      "is negative or not a number",
                      p.accel_mm_s2));
  }
  std::stable_sort(t.begin(), t.end(), [](const auto& a, const auto& b) {
    return a.flow_mm3_s != b.flow_mm3_s ? a.flow_mm3_s < b.flow_mm3_s : a.accel_mm_s2 < b.accel_mm_s2;
  });
  std::set<std::pair<std::string, std::string>> seen;
  std::string out;
  for (const auto& p : t) {
    const std::string flow = format_number(p.flow_mm3_s, 2), acc = format_number(std::round(p.accel_mm_s2), 0);
    if (!seen.insert({flow, acc}).second)
      throw InputError(
          fmt::format("two OrcaSlicer advance lines at flow {} mm^3/s and acceleration {} mm/s^2 (OrcaSlicer "
                      "interpolates over distinct flows)",
                      flow, acc));
    if (!out.empty()) out += "\n";
    out += format_number(p.k_s, L::kOrcaAdvanceDecimals) + "," + flow + "," + acc;
  }
  return out;
}

std::vector<std::pair<std::string, std::string>> json_top_level_members(const std::string& text,
                                                                        const std::string& path) {
  OrcaScanner sc(text, path);
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& m : sc.members()) out.emplace_back(m.key, text.substr(m.begin, m.value_end - m.begin));
  return out;
}

namespace {

// InputError unless the text is a JSON object and, where it says its type, a filament profile.
void check_filament_profile(const std::string& text, const std::string& path) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("not valid JSON: {}", core::plain_json_error(e.what())), path);
  }
  if (!j.is_object()) throw InputError("an OrcaSlicer profile is a JSON object", path);
  if (j.contains("type") && j["type"].is_string() && j["type"] != "filament")
    throw InputError(
        fmt::format("this is an OrcaSlicer '{}' profile, not a filament profile", j["type"].get<std::string>()), path);
}

// InputError for a fallback advance outside OrcaSlicer's range.
void check_fallback_advance(const OrcaAdvanceProfile& p) {
  if (!(std::isfinite(p.fallback_k_s) && p.fallback_k_s >= 0 && p.fallback_k_s <= limits::kOrcaAdvanceMax_s))
    throw InputError(fmt::format("refusing to write OrcaSlicer's pressure_advance {} s (0..{} s)", p.fallback_k_s,
                                 limits::kOrcaAdvanceMax_s));
}

// A replacement of text[begin, end).
struct TextEdit {
  std::size_t begin, end;
  std::string text;
};

// The members the profile lacks, appended after its last member in the style of the file's
// arrays (one line or one element per line, its indent and line ends); their keys into `added`.
std::string appended_members(const std::string& text, const std::vector<OrcaMember>& members,
                             const std::vector<std::pair<std::string, std::string>>& missing,
                             std::vector<std::string>& added) {
  const OrcaMember& last = members.back();
  const std::string ind = orca_indent_before(text, last.begin);
  std::string elem_ind;
  bool multiline = false;
  for (const auto& m : members) {
    if (text[m.value_begin] != '[') continue;
    const auto nl = text.find('\n', m.value_begin);
    if (nl != std::string::npos && nl < m.value_end) {
      const auto first = text.find_first_not_of(" \t", nl + 1);
      if (first != std::string::npos && first < m.value_end && text[first] != ']') {
        elem_ind = text.substr(nl + 1, first - nl - 1);
        multiline = true;
        break;
      }
    }
  }
  const std::string eol = text.find("\r\n") != std::string::npos ? "\r\n" : "\n";
  const bool one_line_object = text.find('\n') == std::string::npos;
  std::string add;
  for (const auto& [key, value] : missing) {
    add += ",";
    add += one_line_object ? " " : eol + ind;
    add += orca_json_string(key) + ": ";
    add += multiline ? "[" + eol + elem_ind + orca_json_string(value) + eol + ind + "]"
                     : "[" + orca_json_string(value) + "]";
    added.push_back(key);
  }
  return add;
}

}  // namespace

OrcaMergeResult merge_orca_filament_profile(const std::string& text, const OrcaAdvanceProfile& p,
                                            const std::string& path) {
  check_filament_profile(text, path);
  check_fallback_advance(p);
  const std::vector<std::pair<std::string, std::string>> want = {
      {"adaptive_pressure_advance", "1"},
      {"adaptive_pressure_advance_model", orca_model_text(p.table)},
      {"enable_pressure_advance", "1"},
      {"pressure_advance", format_number(p.fallback_k_s, limits::kOrcaAdvanceDecimals)},
  };
  OrcaScanner sc(text, path);
  const auto members = sc.members();
  if (members.empty()) throw InputError("an empty JSON object is not an OrcaSlicer filament profile", path);

  std::vector<TextEdit> edits;
  OrcaMergeResult r;
  std::vector<std::pair<std::string, std::string>> missing;
  for (const auto& wanted : want) {
    // Plain references, not a structured binding: the lambda captures the key (clang 14, which
    // builds the fuzz harnesses, refuses to capture a structured binding).
    const std::string& key = wanted.first;
    const std::string& value = wanted.second;
    const auto it = std::find_if(members.begin(), members.end(), [&](const OrcaMember& m) { return m.key == key; });
    if (it == members.end()) {
      missing.emplace_back(key, value);
      continue;
    }
    const std::string enc = orca_json_string(value);
    if (text[it->value_begin] == '[') {
      const auto elems = sc.array_strings(it->value_begin);
      if (elems.empty()) {
        edits.push_back({it->value_begin, it->value_end, "[" + enc + "]"});
      } else {
        // One entry per extruder variant: each gets the same value.
        for (const auto& [b, e] : elems)
          if (text.compare(b, e - b, enc) != 0) edits.push_back({b, e, enc});
      }
    } else {
      edits.push_back({it->value_begin, it->value_end, "[" + enc + "]"});
    }
    if (!edits.empty() && edits.back().begin >= it->value_begin && edits.back().end <= it->value_end)
      r.changed_keys.push_back(key);
  }
  if (!missing.empty())
    edits.push_back(
        {members.back().value_end, members.back().value_end, appended_members(text, members, missing, r.added_keys)});
  std::sort(edits.begin(), edits.end(), [](const TextEdit& a, const TextEdit& b) { return a.begin > b.begin; });
  r.text = text;
  for (const auto& e : edits) r.text.replace(e.begin, e.end - e.begin, e.text);
  try {
    if (!nlohmann::json::parse(r.text).is_object())
      throw InputError("internal error: the merged profile is not an object", path);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(
        fmt::format("internal error: the merged profile is not valid JSON ({})", core::plain_json_error(e.what())),
        path);
  }
  return r;
}

std::string new_orca_filament_profile(const OrcaAdvanceProfile& p, const std::string& name,
                                      const std::string& inherits) {
  check_fallback_advance(p);
  nlohmann::ordered_json j;
  j["type"] = "filament";
  j["name"] = name;
  if (!inherits.empty()) j["inherits"] = inherits;
  j["from"] = "User";
  j["instantiation"] = "true";
  j["filament_settings_id"] = nlohmann::json::array({name});
  j["adaptive_pressure_advance"] = nlohmann::json::array({"1"});
  j["adaptive_pressure_advance_model"] = nlohmann::json::array({orca_model_text(p.table)});
  j["enable_pressure_advance"] = nlohmann::json::array({"1"});
  j["pressure_advance"] = nlohmann::json::array({format_number(p.fallback_k_s, limits::kOrcaAdvanceDecimals)});
  return j.dump(4) + "\n";
}

}  // namespace tunekit::firmware
