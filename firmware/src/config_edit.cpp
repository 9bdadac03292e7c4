#include "tunekit/firmware/config_edit.hpp"

#include <charconv>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/core/file_bytes.hpp"

namespace tunekit::firmware {

namespace {

struct CommentNotePolicy {
  std::vector<std::string> markers;
  std::string note;
};
thread_local const CommentNotePolicy* g_comment_note = nullptr;

// Start of the trailing comment of a line (npos if none): the first marker after code.
std::size_t trailing_comment_at(const std::string& line, const std::vector<std::string>& markers, std::string* marker) {
  const std::size_t first = line.find_first_not_of(" \t");
  if (first == std::string::npos) return std::string::npos;
  // A line that is commented out as a whole ("//#define X 1 // note") has its code after the
  // leading marker.
  std::size_t code = first;
  for (const auto& m : markers)
    if (line.compare(first, m.size(), m) == 0) {
      code = first + m.size();
      break;
    }
  std::size_t best = std::string::npos;
  for (const auto& m : markers) {
    for (std::size_t p = line.find(m, code + 1); p != std::string::npos; p = line.find(m, p + 1)) {
      if (line[p - 1] != ' ' && line[p - 1] != '\t') continue;
      if (p < best) {
        best = p;
        if (marker) *marker = m;
      }
      break;
    }
  }
  return best;
}

std::string code_part(const std::string& line, std::size_t comment_at, const std::vector<std::string>& markers) {
  std::string c = line.substr(0, comment_at == std::string::npos ? line.size() : comment_at);
  const std::size_t b = c.find_first_not_of(" \t");
  if (b == std::string::npos) return {};
  c.erase(0, b);
  for (const auto& m : markers)
    if (c.compare(0, m.size(), m) == 0) {
      c.erase(0, m.size());
      break;
    }
  while (!c.empty() && (c.back() == ' ' || c.back() == '\t')) c.pop_back();
  return c;
}

}  // namespace

std::string replace_trailing_comment(const std::string& original, const std::string& edited,
                                     const std::vector<std::string>& markers, const std::string& note) {
  if (note.empty() || original == edited) return edited;
  std::string marker;
  const std::size_t at = trailing_comment_at(original, markers, &marker);
  if (at == std::string::npos) return edited;
  const std::string comment = original.substr(at);
  if (edited.size() < comment.size() || edited.compare(edited.size() - comment.size(), comment.size(), comment) != 0)
    return edited;  // the writer already rewrote the comment
  const std::size_t edited_at = edited.size() - comment.size();
  if (code_part(original, at, markers) == code_part(edited, edited_at, markers)) return edited;  // only uncommented
  return edited.substr(0, edited_at) + marker + " " + note;
}

ScopedCommentNote::ScopedCommentNote(std::vector<std::string> markers, std::string note) : previous_(g_comment_note) {
  g_comment_note = note.empty() ? nullptr : new CommentNotePolicy{std::move(markers), std::move(note)};
}

ScopedCommentNote::~ScopedCommentNote() {
  delete g_comment_note;
  g_comment_note = static_cast<const CommentNotePolicy*>(previous_);
}

LineEditor::LineEditor(std::string_view text) {
  std::size_t pos = 0;
  while (pos < text.size()) {
    const std::size_t nl = text.find('\n', pos);
    Line l;
    if (nl == std::string_view::npos) {
      l.text = std::string(text.substr(pos));
      pos = text.size();
    } else {
      std::size_t end = nl;
      if (end > pos && text[end - 1] == '\r') --end;
      l.text = std::string(text.substr(pos, end - pos));
      l.eol = std::string(text.substr(end, nl + 1 - end));
      pos = nl + 1;
    }
    lines_.push_back(std::move(l));
  }
  for (const auto& l : lines_)
    if (!l.eol.empty()) {
      eol_ = l.eol;
      break;
    }
}

void LineEditor::replace(std::size_t i, std::string text) {
  if (i >= lines_.size()) throw std::out_of_range("LineEditor::replace: no such line");
  if (g_comment_note)
    text = replace_trailing_comment(lines_[i].text, text, g_comment_note->markers, g_comment_note->note);
  if (text == lines_[i].text) replaced_.erase(i);
  else replaced_[i] = std::move(text);
}

void LineEditor::insert_before(std::size_t i, const std::vector<std::string>& lines) {
  if (i > lines_.size()) throw std::out_of_range("LineEditor::insert_before: no such line");
  if (lines.empty()) return;
  auto& v = inserted_[i];
  v.insert(v.end(), lines.begin(), lines.end());
}

std::string LineEditor::render() const {
  std::string out;
  const std::size_t n = lines_.size();
  const bool append = inserted_.count(n) != 0;
  for (std::size_t i = 0; i <= n; ++i) {
    if (auto it = inserted_.find(i); it != inserted_.end())
      for (const auto& s : it->second) out += s + eol_;
    if (i == n) break;
    auto r = replaced_.find(i);
    out += r != replaced_.end() ? r->second : lines_[i].text;
    // A last line without a line ending gets one when lines are appended after it.
    out += (lines_[i].eol.empty() && i + 1 == n && append) ? eol_ : lines_[i].eol;
  }
  return out;
}

std::string LineEditor::unified_diff(const std::string& label, int context) const {
  if (!changed()) return {};
  struct Op {
    char kind;  // ' ', '-', '+'
    std::string text;
    bool no_eol = false;
  };
  std::vector<Op> ops;
  const std::size_t n = lines_.size();
  const bool append = inserted_.count(n) != 0;
  for (std::size_t i = 0; i <= n; ++i) {
    if (auto it = inserted_.find(i); it != inserted_.end())
      for (const auto& s : it->second) ops.push_back({'+', s});
    if (i == n) break;
    const bool last_no_eol = lines_[i].eol.empty() && i + 1 == n;
    auto r = replaced_.find(i);
    if (r != replaced_.end()) {
      ops.push_back({'-', lines_[i].text, last_no_eol});
      ops.push_back({'+', r->second, last_no_eol && !append});
    } else if (last_no_eol && append) {
      ops.push_back({'-', lines_[i].text, true});
      ops.push_back({'+', lines_[i].text, false});
    } else {
      ops.push_back({' ', lines_[i].text, last_no_eol});
    }
  }
  // Positions (in old and new numbering) before each op.
  std::vector<std::size_t> old_before(ops.size() + 1), new_before(ops.size() + 1);
  for (std::size_t k = 0; k < ops.size(); ++k) {
    old_before[k + 1] = old_before[k] + (ops[k].kind != '+');
    new_before[k + 1] = new_before[k] + (ops[k].kind != '-');
  }
  std::vector<std::size_t> changes;
  for (std::size_t k = 0; k < ops.size(); ++k)
    if (ops[k].kind != ' ') changes.push_back(k);

  const std::size_t ctx = static_cast<std::size_t>(std::max(context, 0));
  // git's a/ and b/ prefixes for a relative path (patch -p1); an absolute path as it is (patch -p0).
  const bool absolute = !label.empty() && label.front() == '/';
  std::string out =
      absolute ? fmt::format("--- {}\n+++ {}\n", label, label) : fmt::format("--- a/{}\n+++ b/{}\n", label, label);
  std::size_t c = 0;
  while (c < changes.size()) {
    const std::size_t begin = changes[c] >= ctx ? changes[c] - ctx : 0;
    std::size_t last = changes[c];
    while (c + 1 < changes.size() && changes[c + 1] <= last + 2 * ctx + 1) last = changes[++c];
    ++c;
    const std::size_t end = std::min(ops.size(), last + ctx + 1);
    const std::size_t old_count = old_before[end] - old_before[begin];
    const std::size_t new_count = new_before[end] - new_before[begin];
    const std::size_t old_start = old_count ? old_before[begin] + 1 : old_before[begin];
    const std::size_t new_start = new_count ? new_before[begin] + 1 : new_before[begin];
    out += fmt::format("@@ -{},{} +{},{} @@\n", old_start, old_count, new_start, new_count);
    for (std::size_t k = begin; k < end; ++k) {
      out += ops[k].kind;
      out += ops[k].text;
      out += '\n';
      if (ops[k].no_eol) out += "\\ No newline at end of file\n";
    }
  }
  return out;
}

std::string format_number(double v, int decimals) {
  std::string s = fmt::format("{:.{}f}", v, decimals);
  if (s.find('.') != std::string::npos) {
    while (!s.empty() && s.back() == '0') s.pop_back();
    if (!s.empty() && s.back() == '.') s.pop_back();
  }
  if (s == "-0") s = "0";
  return s;
}

bool same_number(std::string_view text, double v, int decimals) {
  double parsed = 0;
  const char* b = text.data();
  const char* e = text.data() + text.size();
  if (b != e && *b == '+') ++b;
  const auto [ptr, ec] = std::from_chars(b, e, parsed);
  if (ec != std::errc() || ptr != e) return false;
  return format_number(parsed, decimals) == format_number(v, decimals);
}

std::string backup_path_for(const std::string& path) {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  ::gmtime_r(&now, &tm);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%d-%H%M%S", &tm);
  // NAME.STAMP[.N].bak, NAME shortened so that the backup's name stays within the file system's
  // limit (a configuration named near 255 bytes still gets its backup).
  const std::filesystem::path p(path);
  const std::string dir = p.has_parent_path() ? p.parent_path().string() + "/" : std::string();
  const std::string name = core::shorten_file_name(p.filename().string(), core::kMaxFileNameBytes - 32);
  std::string candidate = fmt::format("{}{}.{}.bak", dir, name, stamp);
  std::error_code ec;
  for (int i = 1; std::filesystem::exists(candidate, ec); ++i)
    candidate = fmt::format("{}{}.{}.{}.bak", dir, name, stamp, i);
  return candidate;
}

std::string read_config_file(const std::string& path) {
  std::string text = read_file_bytes(path, kMaxConfigFileBytes);
  const auto starts = [&](std::string_view bom) { return std::string_view(text).substr(0, bom.size()) == bom; };
  const char* encoding = starts(std::string_view("\x00\x00\xFE\xFF", 4))   ? "UTF-32 (big-endian byte-order mark)"
                         : starts(std::string_view("\xFF\xFE\x00\x00", 4)) ? "UTF-32 (little-endian byte-order mark)"
                         : starts("\xFE\xFF")                              ? "UTF-16 (big-endian byte-order mark)"
                         : starts("\xFF\xFE")                              ? "UTF-16 (little-endian byte-order mark)"
                                                                           : nullptr;
  const auto nul = text.find('\0');
  if (encoding || nul != std::string::npos)
    throw InputError(
        fmt::format("the configuration file is {}, not ASCII-compatible text: tunekit edits ASCII or UTF-8 "
                    "configuration files only (convert it, e.g. iconv -f UTF-16 -t UTF-8, and run again; nothing "
                    "was changed)",
                    encoding ? encoding : fmt::format("binary or UTF-16/UTF-32 text (a NUL byte at offset {})", nul)),
        path);
  return text;
}

std::string write_with_backup(const std::string& path, std::string_view new_content,
                              const std::function<void(const std::string&)>& before_rename) {
  const std::string old = read_config_file(path);
  const std::string backup = backup_path_for(path);
  core::write_file_atomic_as(backup, old, path);  // the backup keeps the original's mode
  core::write_file_atomic(path, new_content, before_rename, core::Links::follow);  // a configuration: links followed
  return backup;
}

}  // namespace tunekit::firmware
