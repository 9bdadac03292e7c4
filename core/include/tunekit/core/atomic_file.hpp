#pragma once
// Crash-safe file replacement: the new content is written to a temporary file in the same
// directory, flushed to disk (fsync), then renamed over the target, and the directory is
// fsynced. A crash at any point leaves either the old file or the new one, never a mix.
// FileBatch does the same for several files that must change together (all or nothing).
// A replaced file keeps its permission bits, owner and group; a file with several hard links is
// refused (InputError, nothing written), since the rename would split the links and writing in
// place is not crash-safe.
//
// Symbolic links: a writer never follows one out of the directory it writes in (a report, a
// plot, a run directory's files, an -o output): a link at the target's name whose target lies
// in another directory is refused (InputError, nothing written), one within the same directory
// is followed. A configuration file is the exception (Klipper's printer.cfg is often a link into
// another tree): its writers say so (Links::follow) and the link's target is replaced, the link
// staying a link.

#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace tunekit::core {

/// Whether a writer follows a symbolic link at the target's name out of its directory.
enum class Links {
  within_directory,  ///< the default: a link whose target is in another directory is refused
  follow,            ///< a configuration file: the link's target is replaced wherever it is
};

/// Throws InputError when `path` is a symbolic link (or a chain of them) whose target lies outside
/// the directory of `path` (for writers that do not go through write_file_atomic, e.g. a plot
/// library writing its own file).
void require_link_within_directory(const std::string& path);

/// The longest file name the writers create (bytes; NAME_MAX of Linux file systems).
inline constexpr std::size_t kMaxFileNameBytes = 255;

/// `name` cut to at most `max_bytes` bytes, not inside a UTF-8 character: for names built from a
/// user's file name (backups, temporary files) that must stay within kMaxFileNameBytes.
std::string shorten_file_name(std::string_view name, std::size_t max_bytes);

/// The name prefix of the temporary files written beside `path` (".NAME.tmp.", NAME shortened so
/// that the six characters of mkstemp(3) still fit within kMaxFileNameBytes).
std::string temporary_name_prefix(const std::string& path);

/// Replaces `path` with `content` atomically. Keeps the target's permission bits when it
/// exists; a new file gets 0666 less the umask (0644 under umask 022), as from any other tool. `before_rename` (for
/// tests) runs after the temporary file is durable and before the rename; if it throws, the temporary file is removed
/// and the target is untouched. Throws tunekit::Error (exit code 2) on I/O failure.
void write_file_atomic(const std::string& path, std::string_view content,
                       const std::function<void(const std::string& temp_path)>& before_rename = {},
                       Links links = Links::within_directory);

/// write_file_atomic() giving `path` the permission bits of the file `mode_of` (when it
/// exists): a backup keeps its original's mode.
void write_file_atomic_as(const std::string& path, std::string_view content, const std::string& mode_of,
                          const std::function<void(const std::string& temp_path)>& before_rename = {});

/// Several files written together, all or nothing. commit() first writes every new content
/// to a durable temporary file beside its target (any failure: every temporary file is
/// removed and no target has changed), then renames them over their targets in the order
/// they were added; should a rename fail, the targets already replaced get their previous
/// bytes back (or are removed when they did not exist). Throws InputError (exit code 2)
/// naming the file that could not be written.
class FileBatch {
 public:
  /// Adds a file; a later add of the same path replaces the earlier content. The file gets
  /// the permission bits of `mode_of` when that exists (default: `path` itself, kept when
  /// replaced), else those of a new file under the umask.
  void add(std::string path, std::string content, std::string mode_of = {}, Links links = Links::within_directory);
  bool empty() const { return files_.empty(); }
  /// `before_rename` (for tests) runs before each rename with the target's path; if it
  /// throws, the batch is rolled back as for a failed rename.
  void commit(const std::function<void(const std::string& target_path)>& before_rename = {});

 private:
  struct File {
    std::string path, content, mode_of;
    Links links = Links::within_directory;
  };
  std::vector<File> files_;
};

}  // namespace tunekit::core
