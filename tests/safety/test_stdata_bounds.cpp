// Shake&Tune .stdata files are Zstandard streams: decompression is bounded while it streams (a
// small file that expands to gigabytes is refused at its cap, without decompressing the rest),
// and a valid stream whose output fills the decoder's buffer exactly is not called truncated.
// The frames are built by hand from RLE blocks (RFC 8878, section 3.1.1.2), so that the
// test needs no compressor.
#include <chrono>
#include <cstdint>
#include <string>

#include <catch2/catch.hpp>

#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/ident/shaketune_stdata.hpp"

namespace {

constexpr std::uint32_t kRleBlockBytes = 128 * 1024;  // Block_Maximum_Size

/// A Zstandard frame of `blocks` RLE blocks of 128 KiB of `byte` each (no content size, no
/// checksum, a 128 KiB window).
std::string rle_frame(std::size_t blocks, char byte) {
  std::string f("\x28\xb5\x2f\xfd", 4);
  f += '\x00';  // Frame_Header_Descriptor: window descriptor present, nothing else
  f += '\x38';  // Window_Descriptor: exponent 7 -> 2^(10+7) = 128 KiB
  for (std::size_t i = 0; i < blocks; ++i) {
    const std::uint32_t header = (kRleBlockBytes << 3) | (1u << 1) | (i + 1 == blocks ? 1u : 0u);  // type 1: RLE
    f += static_cast<char>(header & 0xff);
    f += static_cast<char>((header >> 8) & 0xff);
    f += static_cast<char>((header >> 16) & 0xff);
    f += byte;
  }
  return f;
}

std::string refusal(const std::string& bytes) {
  try {
    tunekit::ident::load_shaketune_stdata("bomb.stdata", bytes, {});
  } catch (const tunekit::InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

}  // namespace

TEST_CASE("a small .stdata that expands far beyond any measurement is refused at its cap while streaming",
          "[safety][stdata]") {
  // 8 KB of frame that would expand to 256 MiB of zeros: refused once the output passes 64 MiB
  // (the floor of the cap; 200 times 8 KB is less), long before the 1 GiB absolute cap.
  const std::string bomb = rle_frame(2048, '\0');
  REQUIRE(bomb.size() < 9000);
  const auto t0 = std::chrono::steady_clock::now();
  const std::string why = refusal(bomb);
  INFO(why);
  CHECK(why.find("decompresses to more than 67108864 bytes") != std::string::npos);
  CHECK(why.find("not a Shake&Tune measurement file") != std::string::npos);
  // Bounded while streaming: well under the time to expand all 256 MiB (a loose bound, for a
  // loaded machine; the decisive check is the message naming the 64 MiB cap).
  CHECK(std::chrono::steady_clock::now() - t0 < std::chrono::seconds(20));
}

TEST_CASE("a valid all-zero .stdata stream that fills the decoder's buffer exactly is not called truncated",
          "[safety][stdata]") {
  // One RLE block of 128 KiB: exactly ZSTD_DStreamOutSize() bytes of output. Decoded whole,
  // it is refused for what it holds (no measurement), not as a truncated stream.
  const std::string why = refusal(rle_frame(1, '\0'));
  INFO(why);
  CHECK(why.find("truncated") == std::string::npos);
  CHECK(why != "(accepted)");
  // A frame cut in the middle still is.
  const std::string cut = rle_frame(3, '\0').substr(0, 6 + 4 + 2);
  CHECK(refusal(cut).find("truncated") != std::string::npos);
}
