#pragma once
// Whole-file reading with a located error, shared by every layer that reads input files
// (CSV tables, images, machine profiles, results): beside the error types it reports with.

#include <string>

namespace tunekit {

/// Reads a whole file into memory; InputError (exit code 2, located at the file) if it cannot
/// be opened or read.
std::string read_file_bytes(const std::string& path);

}  // namespace tunekit
