#pragma once
// One reading of each input while a step that reads it from several places runs: a machine
// profile's importer sniffs the file's format, then its reader and the firmware's own parser read
// the same file again by path. While an InputReadScope is alive on a thread, read_file_bytes()
// and read_file_head() (file_bytes.hpp) of a path read before in it return the bytes read the
// first time, without opening the file again: every part of the step sees the same bytes, and the
// file is opened once (core::FileOpenLog counts it so). A MappedFileBytes of such a path takes
// those bytes too (it keeps nothing itself).

#include <map>
#include <optional>
#include <string>

namespace tunekit::core {

/// Keeps the bytes of every file read on this thread while it is alive. A scope opened while
/// another is alive on the same thread adds nothing: the outer one keeps the bytes.
class InputReadScope {
 public:
  InputReadScope();
  ~InputReadScope();
  InputReadScope(const InputReadScope&) = delete;
  InputReadScope& operator=(const InputReadScope&) = delete;

  /// Whether a scope is alive on this thread.
  static bool active();
  /// The bytes of `path` read earlier in the live scope of this thread; nullopt when there is
  /// no live scope or `path` was not read in it (paths as the callers spell them).
  static std::optional<std::string> cached(const std::string& path);
  /// Keeps `bytes` as `path`'s in the live scope of this thread (nothing when there is none).
  static void keep(const std::string& path, const std::string& bytes);

 private:
  bool outermost_ = false;
  std::map<std::string, std::string> bytes_;
};

}  // namespace tunekit::core
