// Klipper printer.cfg reading with includes and the SAVE_CONFIG block, as klippy/configfile.py
// loads it (see klipper_config_reader.hpp).
#include "klipper_config_reader.hpp"

#include <glob.h>

#include <algorithm>
#include <filesystem>
#include <set>
#include <vector>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/core/text.hpp"
#include "tunekit/firmware/config_edit.hpp"

namespace tunekit::machine::detail {
namespace {

// klippy/configfile.py AUTOSAVE_HEADER, line by line.
constexpr const char* kAutosaveHeader1 = "#*# <---------------------- SAVE_CONFIG ---------------------->";
constexpr const char* kAutosaveHeader2 = "#*# DO NOT EDIT THIS BLOCK OR BELOW. The contents are auto-generated.";
constexpr const char* kAutosaveHeader3 = "#*#";
constexpr std::size_t kMaxKlipperIncludeDepth = 64;
constexpr std::size_t kMaxKlipperFiles = 1000;

bool cfg_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

std::string cfg_trim(const std::string& s) {
  std::size_t b = 0, e = s.size();
  while (b < e && cfg_blank(s[b])) ++b;
  while (e > b && cfg_blank(s[e - 1])) --e;
  return s.substr(b, e - b);
}

std::vector<std::string> cfg_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::size_t start = 0;
  while (start <= text.size()) {
    auto end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string line = text.substr(start, end - start);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back(std::move(line));
    start = end + 1;
  }
  return lines;
}

/// configparser's inline comment: ';' after a cfg_blank.
std::string strip_inline_semicolon(const std::string& v) {
  for (std::size_t k = 1; k < v.size(); ++k)
    if (v[k] == ';' && cfg_blank(v[k - 1])) return cfg_trim(v.substr(0, k));
  return v;
}

struct IncludeState {
  std::set<std::string> stack;  // canonical paths of the files being read (include loop check)
  std::size_t depth = 0;
  std::size_t files = 0;
};

class KlipperParser {
 public:
  KlipperParser(KlipperConfig& cfg, IncludeState& state) : cfg_(cfg), state_(state) {}
  /// Parses lines [first, last) of one file; `prefix` bytes are dropped from each (the block's "#*# ").
  void parse(const std::vector<std::string>& lines, std::size_t first, std::size_t last, std::size_t prefix,
             const std::string& file, bool includes_allowed);

 private:
  void line(const std::string& raw, const Site& site, bool includes_allowed);
  void include(const std::string& spec, const Site& site);
  KlipperConfig& cfg_;
  IncludeState& state_;
  KlipperSection* section_ = nullptr;
  KlipperOption* option_ = nullptr;
};

void KlipperParser::parse(const std::vector<std::string>& lines, std::size_t first, std::size_t last,
                          std::size_t prefix, const std::string& file, bool includes_allowed) {
  for (std::size_t i = first; i < last; ++i) {
    const std::string& full = lines[i];
    const std::string raw = full.size() > prefix ? full.substr(prefix) : std::string();
    line(raw, Site{file, i + 1, cfg_trim(raw.substr(0, raw.find('#')))}, includes_allowed);
  }
}

void KlipperParser::line(const std::string& raw, const Site& site, bool includes_allowed) {
  const std::string text = raw.substr(0, raw.find('#'));  // klippy/configfile.py: from the first '#'
  const std::string t = cfg_trim(text);
  if (t.empty() || t[0] == ';') return;
  if (cfg_blank(text[0]) && option_ != nullptr) {  // continuation of a multi-line value
    option_->value += "\n" + t;
    return;
  }
  if (t[0] == '[' && t.rfind(']') != std::string::npos && t.rfind(']') > 1) {
    const std::string header = t.substr(1, t.rfind(']') - 1);
    option_ = nullptr;
    if (header.rfind("include ", 0) == 0) {
      if (!includes_allowed) throw InputError("[include] inside the SAVE_CONFIG block", site.where());
      section_ = nullptr;
      include(cfg_trim(header.substr(8)), site);
      return;
    }
    auto [it, added] = cfg_.sections.try_emplace(header);
    if (added) it->second.site = site;
    section_ = &it->second;
    return;
  }
  const auto sep = t.find_first_of(":=");
  if (sep == std::string::npos || sep == 0)
    throw InputError(fmt::format("'{}' is neither a [section] nor an option (key: value)", shown(t)), site.where());
  if (section_ == nullptr)
    throw InputError(fmt::format("the option '{}' comes before any [section] header", cfg_trim(t.substr(0, sep))),
                     site.where());
  const std::string key = core::lower(cfg_trim(t.substr(0, sep)));
  option_ = &section_->options[key];
  *option_ = KlipperOption{strip_inline_semicolon(cfg_trim(t.substr(sep + 1))), site};
}

std::vector<std::string> glob_sorted(const std::string& pattern) {
  std::vector<std::string> files;
  glob_t g{};
  if (::glob(pattern.c_str(), 0, nullptr, &g) == 0)
    for (std::size_t i = 0; i < g.gl_pathc; ++i) files.emplace_back(g.gl_pathv[i]);
  ::globfree(&g);
  std::sort(files.begin(), files.end());
  return files;
}

void read_klipper_file(KlipperConfig& cfg, IncludeState& state, const std::string& file, const Site& from);

void KlipperParser::include(const std::string& spec, const Site& site) {
  if (spec.empty()) throw InputError("[include] names no file", site.where());
  const std::string dir = std::filesystem::path(site.file).parent_path().string();
  const std::string pattern = dir.empty() ? spec : (std::filesystem::path(dir) / spec).string();
  const auto files = glob_sorted(pattern);
  const bool magic = spec.find_first_of("*?[") != std::string::npos;
  if (files.empty() && !magic)
    throw InputError(fmt::format("[include {}]: the file {} does not exist (Klipper refuses to start: \"Include "
                                 "file '...' does not exist\")",
                                 spec, pattern),
                     site.where());
  for (const auto& f : files) read_klipper_file(cfg_, state_, f, site);
}

void read_klipper_file(KlipperConfig& cfg, IncludeState& state, const std::string& file, const Site& from) {
  std::error_code ec;
  const std::string canon = std::filesystem::weakly_canonical(file, ec).string();
  if (state.stack.count(canon))
    throw InputError(fmt::format("[include] of {} loops: that file is already being read (Klipper: \"Recursive "
                                 "include of config file\")",
                                 file),
                     from.where());
  if (++state.files > kMaxKlipperFiles || state.depth + 1 > kMaxKlipperIncludeDepth)
    throw InputError(fmt::format("more than {} nested includes or {} files", kMaxKlipperIncludeDepth, kMaxKlipperFiles),
                     from.where());
  const auto lines = cfg_lines(firmware::read_config_file(file));
  state.stack.insert(canon);
  ++state.depth;
  KlipperParser(cfg, state).parse(lines, 0, lines.size(), 0, file, true);
  --state.depth;
  state.stack.erase(canon);
}

/// klippy/configfile.py _find_autosave_data: the index of the header's first line when the block
/// is one Klipper reads (the exact three header lines, no "#*# " line before them, every later
/// line "#*#"-prefixed); lines.size() otherwise (then Klipper reads the whole file as regular).
std::size_t find_klipper_autosave(const std::vector<std::string>& lines) {
  for (std::size_t i = 0; i + 2 < lines.size(); ++i) {
    if (lines[i] != kAutosaveHeader1 || lines[i + 1] != kAutosaveHeader2 || lines[i + 2] != kAutosaveHeader3) continue;
    for (std::size_t j = 0; j < i; ++j)
      if (lines[j].rfind("#*# ", 0) == 0) return lines.size();
    std::size_t last = lines.size();
    while (last > i + 3 && cfg_trim(lines[last - 1]).empty()) --last;
    for (std::size_t j = i + 3; j < last; ++j)
      if (lines[j].rfind("#*#", 0) != 0 || (lines[j].size() >= 4 && lines[j][3] != ' ')) return lines.size();
    return i;
  }
  return lines.size();
}

/// The block's options that the regular part does not set (ConfigAutoSave._strip_duplicates).
void merge_autosave(KlipperConfig& cfg, const KlipperConfig& block) {
  for (const auto& [name, sec] : block.sections) {
    auto [it, added] = cfg.sections.try_emplace(name);
    if (added) it->second.site = sec.site;
    for (const auto& [key, opt] : sec.options) it->second.options.try_emplace(key, opt);
  }
}

}  // namespace

const KlipperOption* KlipperSection::find(const std::string& key) const {
  const auto it = options.find(key);
  return it == options.end() ? nullptr : &it->second;
}

const KlipperSection* KlipperConfig::find(const std::string& name) const {
  const auto it = sections.find(name);
  return it == sections.end() ? nullptr : &it->second;
}

KlipperConfig read_klipper_config(const std::string& path) {
  KlipperConfig cfg;
  cfg.main_file = path;
  IncludeState state;
  std::error_code ec;
  const std::string canon = std::filesystem::weakly_canonical(path, ec).string();
  const auto lines = cfg_lines(firmware::read_config_file(path));
  const std::size_t block = find_klipper_autosave(lines);
  state.stack.insert(canon);
  state.files = 1;
  state.depth = 1;
  KlipperParser(cfg, state).parse(lines, 0, block, 0, path, true);
  if (block < lines.size()) {
    KlipperConfig saved;
    IncludeState none;
    KlipperParser(saved, none).parse(lines, block + 3, lines.size(), 4, path, false);
    merge_autosave(cfg, saved);
  }
  return cfg;
}

}  // namespace tunekit::machine::detail
