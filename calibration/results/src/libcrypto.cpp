// SHA-256 of inputs and Base64 of a report's images through OpenSSL's libcrypto (Debian's
// libssl3), opened when a command first needs them (core/shared_library.hpp), not at start-up:
// libcrypto is bound at load time in full (about 3,400 symbol lookups), which a command that
// prints to the terminal only (no digest, no report) would pay for nothing.
#include <openssl/evp.h>

#include <fmt/format.h>

#include "tunekit/calibration/results/base64.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/core/shared_library.hpp"

namespace tunekit::calibration {
namespace {

// The libcrypto functions used here, resolved on first use.
struct CryptoApi {
  decltype(&::EVP_Digest) EVP_Digest;
  decltype(&::EVP_sha256) EVP_sha256;
  decltype(&::EVP_EncodeBlock) EVP_EncodeBlock;
};

const CryptoApi& crypto() {
  static const CryptoApi api = [] {
    static core::SharedLibrary lib(TUNEKIT_LIBCRYPTO_SONAME, "SHA-256 digests of inputs and reports' images",
                                   "libssl3");
    CryptoApi a;
    a.EVP_Digest = lib.function<decltype(&::EVP_Digest)>("EVP_Digest");
    a.EVP_sha256 = lib.function<decltype(&::EVP_sha256)>("EVP_sha256");
    a.EVP_EncodeBlock = lib.function<decltype(&::EVP_EncodeBlock)>("EVP_EncodeBlock");
    return a;
  }();
  return api;
}

}  // namespace

std::string sha256_hex(std::string_view bytes) {
  const CryptoApi& api = crypto();
  unsigned char md[EVP_MAX_MD_SIZE];
  unsigned int len = 0;
  api.EVP_Digest(bytes.data(), bytes.size(), md, &len, api.EVP_sha256(), nullptr);
  std::string hex;
  hex.reserve(len * 2);
  for (unsigned int i = 0; i < len; ++i) hex += fmt::format("{:02x}", md[i]);
  return hex;
}

std::string base64(std::string_view bytes) {
  std::string out(4 * ((bytes.size() + 2) / 3) + 1, '\0');
  const int n =
      crypto().EVP_EncodeBlock(reinterpret_cast<unsigned char*>(out.data()),
                               reinterpret_cast<const unsigned char*>(bytes.data()), static_cast<int>(bytes.size()));
  out.resize(static_cast<std::size_t>(n));
  return out;
}

}  // namespace tunekit::calibration
