#pragma once
// Byte-exact, line-based editing of firmware configuration files. A file is split into lines
// that keep their own line ending ("\n", "\r\n" or none for a last line without one); edits
// replace or insert whole lines, and everything not edited is reproduced byte for byte.
// The edit list also gives a unified diff for the preview, and the write path makes a
// timestamped backup and replaces the file atomically (atomic_file.hpp).

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace tunekit::firmware {

class LineEditor {
 public:
  explicit LineEditor(std::string_view text);

  std::size_t size() const { return lines_.size(); }
  /// Line i (original numbering, 0-based) without its line ending.
  const std::string& line(std::size_t i) const { return lines_.at(i).text; }
  /// The line ending new lines get: that of the first line that has one, else "\n".
  const std::string& eol() const { return eol_; }

  /// Replaces original line i (keeps its line ending). A replacement equal to the original
  /// is not an edit. Replacing the same line twice keeps the last text.
  void replace(std::size_t i, std::string text);
  /// Inserts lines before original line i; i == size() appends at the end of the file.
  /// Several insertions at the same place keep their order.
  void insert_before(std::size_t i, const std::vector<std::string>& lines);

  bool changed() const { return !replaced_.empty() || !inserted_.empty(); }
  std::string render() const;
  /// Unified diff (original -> edited) with `context` lines of context; empty if unchanged. The
  /// header names `label` as a/LABEL and b/LABEL, or as it is when it is an absolute path.
  std::string unified_diff(const std::string& label, int context = 3) const;

 private:
  struct Line {
    std::string text;
    std::string eol;
  };
  std::vector<Line> lines_;
  std::string eol_ = "\n";
  std::map<std::size_t, std::string> replaced_;
  std::map<std::size_t, std::vector<std::string>> inserted_;
};

/// The edited line with its trailing comment replaced by `marker + " " + note` when the edit
/// changed the line's code and kept the original's trailing comment (a comment that described
/// the old value, e.g. "pressure_advance: 0.05   ; tuned by hand" -> "pressure_advance: 0.041
/// ; <note>"). A trailing comment starts at the first marker (e.g. "#", ";", "//") that
/// follows code and white space. A line whose only change is being uncommented (Marlin's
/// "//#define X" -> "#define X") keeps its comment, as does a line without one.
std::string replace_trailing_comment(const std::string& original, const std::string& edited,
                                     const std::vector<std::string>& markers, const std::string& note);

/// While an instance lives, LineEditor::replace on the same thread passes every replacement
/// through replace_trailing_comment with these markers and this note (the firmware writers
/// need not know about it). An empty note disables it.
class ScopedCommentNote {
 public:
  ScopedCommentNote(std::vector<std::string> markers, std::string note);
  ~ScopedCommentNote();
  ScopedCommentNote(const ScopedCommentNote&) = delete;
  ScopedCommentNote& operator=(const ScopedCommentNote&) = delete;

 private:
  const void* previous_;
};

/// Formats a number with at most `decimals` decimals, trailing zeros removed ("0.04", "45.2",
/// "3"). Negative zero prints as "0".
std::string format_number(double v, int decimals);

/// Whether `text` is a number equal to `v` rounded to `decimals` decimals (so an existing
/// "0.040" counts as already set to 0.04 and is left alone: idempotence).
bool same_number(std::string_view text, double v, int decimals);

/// The largest configuration file tunekit reads (bytes): 16 MiB, some hundred times a large
/// Klipper printer.cfg or Marlin Configuration.h.
inline constexpr std::uint64_t kMaxConfigFileBytes = std::uint64_t{16} << 20;

/// Reads a firmware configuration file (a regular file of at most kMaxConfigFileBytes,
/// read_file_bytes()) and refuses, with InputError (exit code 2), text that is not
/// ASCII-compatible: UTF-16 or UTF-32 (byte-order mark or NUL bytes) would be "edited" by
/// appending ASCII lines the firmware cannot read. ASCII and UTF-8 (with or without its
/// byte-order mark) are accepted.
std::string read_config_file(const std::string& path);

/// "<path>.<YYYYmmdd-HHMMSS>.bak" for the current UTC time (with -1, -2, ... appended when
/// that name already exists).
std::string backup_path_for(const std::string& path);

/// Writes `new_content` over `path`: first a backup copy of the current bytes (returned),
/// then atomic replacement (temporary file, fsync, rename). `before_rename` is passed to
/// write_file_atomic for the replacement of the target (tests use it to simulate a crash).
std::string write_with_backup(const std::string& path, std::string_view new_content,
                              const std::function<void(const std::string&)>& before_rename = {});

}  // namespace tunekit::firmware
