#pragma once
// Crash-safe file replacement: the new content is written to a temporary file in the same
// directory, flushed to disk (fsync), then renamed over the target, and the directory is
// fsynced. A crash at any point leaves either the old file or the new one, never a mix.

#include <functional>
#include <string>
#include <string_view>

namespace tunekit::protocols {

/// Replaces `path` with `content` atomically. Keeps the target's permission bits when it
/// exists. `before_rename` (for tests) runs after the temporary file is durable and before
/// the rename; if it throws, the temporary file is removed and the target is untouched.
/// Throws tunekit::Error (exit code 2) on I/O failure.
void write_file_atomic(const std::string& path, std::string_view content,
                       const std::function<void(const std::string& temp_path)>& before_rename = {});

}  // namespace tunekit::protocols
