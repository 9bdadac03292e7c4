#pragma once
// An input file as a command's JSON envelope records it (path, SHA-256 of the bytes read, size),
// and an input file read once with its digest carried along (InputFile): a command opens each
// of its files once and records the digest of the very bytes it analysed.

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/core/file_bytes.hpp"

namespace tunekit::calibration {

struct InputDigest {
  std::string path;
  std::string sha256;          ///< lower-case hex SHA-256 of the bytes
  std::size_t size_bytes = 0;  ///< bytes
};

inline InputDigest input_digest(const std::string& path, std::string_view bytes) {
  return {path, sha256_hex(bytes), bytes.size()};
}

inline void add_input(Envelope& env, const InputDigest& d) { env.add_input_digest(d.path, d.sha256, d.size_bytes); }

/// An input file's bytes, read once (mapped when they can be), and their digest, computed once
/// from those bytes. Copies share the bytes.
class InputFile {
 public:
  /// Opens and reads `path` once (core's MappedFileBytes) and hashes it; InputError (exit 2,
  /// located at the file) if it cannot be read.
  static InputFile read(const std::string& path);
  /// Bytes already in memory under the name `path` (a file a run has just written, which it
  /// need not read back).
  static InputFile from_bytes(std::string path, std::string bytes);

  const std::string& path() const { return digest_.path; }
  std::string_view bytes() const { return bytes_; }
  /// Path, SHA-256 and size of the bytes.
  const InputDigest& digest() const { return digest_; }

 private:
  std::shared_ptr<const void> owner_;  ///< keeps the bytes alive (a mapping or a string)
  std::string_view bytes_;
  InputDigest digest_;
};

inline InputFile InputFile::read(const std::string& path) {
  auto data = std::make_shared<const MappedFileBytes>(path);
  InputFile f;
  f.bytes_ = data->view();
  f.owner_ = std::move(data);
  f.digest_ = input_digest(path, f.bytes_);
  return f;
}

inline InputFile InputFile::from_bytes(std::string path, std::string bytes) {
  auto data = std::make_shared<const std::string>(std::move(bytes));
  InputFile f;
  f.bytes_ = *data;
  f.owner_ = std::move(data);
  f.digest_ = input_digest(path, f.bytes_);
  return f;
}

}  // namespace tunekit::calibration
