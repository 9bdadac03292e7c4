#pragma once
// Base64 (RFC 4648, with padding, no line breaks) as reports embed images: OpenSSL's encoder,
// from libcrypto opened on first use (calibration/results/src/libcrypto.cpp).

#include <string>
#include <string_view>

namespace tunekit::calibration {

/// The Base64 text of a byte string.
std::string base64(std::string_view bytes);

}  // namespace tunekit::calibration
