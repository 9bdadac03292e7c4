#pragma once
// Shared by the libFuzzer harnesses: every harness feeds bytes to one reader or parser and
// accepts exactly two outcomes, a result or tunekit's own located error (tunekit::Error).
// Anything else -- a crash, a sanitizer report, another exception, a hang -- is a finding.

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "tunekit/core/error.hpp"

namespace tunekit::fuzz {

inline std::string_view as_text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

/// Runs `f`; tunekit's own errors are expected answers to bad input, everything else escapes
/// (libFuzzer reports an uncaught exception as a crash).
template <class F>
void expect_result_or_error(F&& f) {
  try {
    f();
  } catch (const tunekit::Error&) {
  }
}

}  // namespace tunekit::fuzz
