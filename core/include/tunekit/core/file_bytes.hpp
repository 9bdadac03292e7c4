#pragma once
// Whole-file reading with a located error, shared by every layer that reads input files
// (CSV tables, images, machine profiles, results): beside the error types it reports with.

#include <string>

namespace tunekit {

/// Reads a whole file into memory; InputError (exit code 2, located at the file) if it cannot
/// be opened or read.
std::string read_file_bytes(const std::string& path);

/// Whether `a` and `b` name the same file: by filesystem identity (device and inode, so links
/// and other spellings of a path count) when both exist, else by their normalized absolute paths.
bool same_file(const std::string& a, const std::string& b);

}  // namespace tunekit
