#pragma once
// Which files the file layer (file_bytes.hpp: read_file_bytes, read_file_head, MappedFileBytes)
// opens, for tests that check a command reads each of its inputs once. Costs one relaxed atomic
// load per opened file while no log is alive.

#include <cstddef>
#include <mutex>
#include <string>
#include <vector>

namespace tunekit::core {

/// Records every path the file layer opens, on any thread, while the object is alive (several
/// may be alive at once; each records what is opened during its own lifetime).
class FileOpenLog {
 public:
  FileOpenLog();
  ~FileOpenLog();
  FileOpenLog(const FileOpenLog&) = delete;
  FileOpenLog& operator=(const FileOpenLog&) = delete;

  /// The paths opened so far, as the callers spelled them, in the order they were opened.
  std::vector<std::string> paths() const;
  /// How many times the file `path` names was opened: paths are compared as normalized absolute
  /// paths, so "a/../b.csv" and "./b.csv" name the same file.
  std::size_t opens(const std::string& path) const;

  /// Called by the file layer for each file it opens: adds `path` to every live log.
  static void record(const std::string& path);

 private:
  mutable std::mutex mutex_;
  std::vector<std::string> paths_;
};

}  // namespace tunekit::core
