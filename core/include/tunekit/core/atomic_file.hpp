#pragma once
// Crash-safe file replacement: the new content is written to a temporary file in the same
// directory, flushed to disk (fsync), then renamed over the target, and the directory is
// fsynced. A crash at any point leaves either the old file or the new one, never a mix.
// FileBatch does the same for several files that must change together (all or nothing).
// A replaced file keeps its permission bits, owner and group; a symbolic link is followed and
// its target replaced (the link stays a link); a file with several hard links is refused
// (InputError, nothing written), since the rename would split the links and writing in place
// is not crash-safe.

#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace tunekit::core {

/// Replaces `path` with `content` atomically. Keeps the target's permission bits when it
/// exists; a new file gets 0666 less the umask (0644 under umask 022), as from any other tool. `before_rename` (for
/// tests) runs after the temporary file is durable and before the rename; if it throws, the temporary file is removed
/// and the target is untouched. Throws tunekit::Error (exit code 2) on I/O failure.
void write_file_atomic(const std::string& path, std::string_view content,
                       const std::function<void(const std::string& temp_path)>& before_rename = {});

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
  void add(std::string path, std::string content, std::string mode_of = {});
  bool empty() const { return files_.empty(); }
  /// `before_rename` (for tests) runs before each rename with the target's path; if it
  /// throws, the batch is rolled back as for a failed rename.
  void commit(const std::function<void(const std::string& target_path)>& before_rename = {});

 private:
  struct File {
    std::string path, content, mode_of;
  };
  std::vector<File> files_;
};

}  // namespace tunekit::core
