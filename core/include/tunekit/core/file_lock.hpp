#pragma once
// Serialised writers of one file: an advisory lock (flock(2), exclusive) on the file itself,
// held while a writer compares what it read with what the file holds now and replaces it
// (atomic_file.hpp). Two tunekit processes editing one configuration then take turns: the
// second finds the file changed since it read it and refuses, never overwriting the first's
// change. The replacement renames a new file over the old one, so a writer that locked the old
// file finds, once it holds the lock, that the name now names another file: it locks that one
// instead. A writer waits at most `wait` for the lock, then refuses (InputError, exit code 2).
// The lock is advisory: an editor that does not take it is not kept out (the compare still
// catches most of its changes).
//
// Temporary files left beside the file by a writer that was killed between writing and
// renaming (".NAME.tmp.XXXXXX", from mkstemp(3)) cannot belong to a live tunekit writer while
// the lock is held: stale_temporaries() lists them and remove_stale_temporaries() deletes them.

#include <chrono>
#include <string>
#include <vector>

namespace tunekit::core {

/// How long a second writer waits for the first before it refuses (s).
inline constexpr std::chrono::milliseconds kFileLockWait{10000};

class FileLock {
 public:
  /// Locks `path` (following symbolic links, as the writers do). A missing file is not locked
  /// (there is nothing to replace; the writer creates it). Throws InputError when the lock is
  /// not granted within `wait` or the file cannot be opened.
  explicit FileLock(const std::string& path, std::chrono::milliseconds wait = kFileLockWait);
  ~FileLock();
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

  /// Removes the stale temporary files of the locked file and returns their names (for a
  /// warning); a file that cannot be removed is named too.
  std::vector<std::string> remove_stale_temporaries() const;

 private:
  std::string path_;
  int fd_ = -1;
};

/// The temporary files a writer of `path` leaves if killed before its rename: ".NAME.tmp.XXXXXX"
/// in the same directory (six characters from mkstemp(3)).
std::vector<std::string> stale_temporaries(const std::string& path);

}  // namespace tunekit::core
