#pragma once
// An input file as a command's JSON envelope records it: path, SHA-256 of the bytes read, size.

#include <cstddef>
#include <string>
#include <string_view>

#include "tunekit/calibration/results/envelope.hpp"

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

}  // namespace tunekit::calibration
