#pragma once
// Whole-file reading with a located error, shared by every layer that reads input files
// (CSV tables, images, machine profiles, results, firmware configurations): beside the error
// types it reports with. Every file is checked before a byte is read: a regular file (a FIFO
// would block forever, /dev/zero never ends, a directory has no bytes) of bounded size.

#include <cstdint>
#include <string>

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

/// Whether `a` and `b` name the same file: by filesystem identity (device and inode, so links
/// and other spellings of a path count) when both exist, else by their normalized absolute paths.
bool same_file(const std::string& a, const std::string& b);

}  // namespace tunekit
