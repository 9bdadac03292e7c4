#pragma once
// Whole-file reading with a located error, shared by every layer that reads input files
// (CSV tables, images, machine profiles, results, firmware configurations): beside the error
// types it reports with. Every file is checked before a byte is read: a regular file (a FIFO
// would block forever, /dev/zero never ends, a directory has no bytes) of bounded size. Every
// file opened here is recorded in the live core::FileOpenLogs (file_open_log.hpp).

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace tunekit {

/// The largest input file read_file_bytes() reads unless told otherwise (bytes): 1 GiB, far
/// beyond any recording, image or results file tunekit reads, and within a small machine's memory.
inline constexpr std::uint64_t kMaxInputFileBytes = std::uint64_t{1} << 30;

/// Reads a whole file into memory; InputError (exit code 2, located at the file) if it cannot
/// be opened or read, is not a regular file (named: a directory, a FIFO, a device, ...), or
/// holds more than `max_bytes` bytes (checked before reading and again while reading, should it grow).
std::string read_file_bytes(const std::string& path, std::uint64_t max_bytes = kMaxInputFileBytes);

/// At most the first `max_bytes` bytes of a regular file (same checks as read_file_bytes(), but a
/// longer file is not an error): for sniffing a header.
std::string read_file_head(const std::string& path, std::uint64_t max_bytes);

/// A whole input file's bytes for the parsers, opened once. A regular file is mapped into memory
/// read-only (the page cache is parsed in place: no copy and no fresh pages to fault in, which
/// costs more than the parsing of a 20 MB file); an empty file, or one that cannot be mapped, is
/// read. The checks and errors are read_file_bytes()'s. A mapped file must not shrink while it is read.
class MappedFileBytes {
 public:
  /// InputError (exit code 2, located at the file) if it cannot be opened or read.
  explicit MappedFileBytes(const std::string& path);
  ~MappedFileBytes();
  MappedFileBytes(const MappedFileBytes&) = delete;
  MappedFileBytes& operator=(const MappedFileBytes&) = delete;
  std::string_view view() const { return map_ != nullptr ? std::string_view(map_, size_) : std::string_view(copy_); }

 private:
  const char* map_ = nullptr;
  std::size_t size_ = 0;
  std::string copy_;
};

/// Whether `a` and `b` name the same file: by filesystem identity (device and inode, so links
/// and other spellings of a path count) when both exist, else by their normalized absolute paths.
bool same_file(const std::string& a, const std::string& b);

}  // namespace tunekit
