// The image readers (PNG, JPEG, BMP, PNM, TGA, PSD, GIF through stb) on arbitrary bytes, with
// the pixel limit checked before decoding (kept small here so that a fuzzed header cannot ask
// for gigabytes).
#include "fuzz_common.hpp"
#include "tunekit/ident/image_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool limited = (tunekit::ident::set_max_image_pixels(4'000'000), true);
  (void)limited;
  const std::string bytes(tunekit::fuzz::as_text(data, size));
  tunekit::fuzz::expect_result_or_error([&] { tunekit::ident::decode_image(bytes, "fuzz.img"); });
  tunekit::fuzz::expect_result_or_error([&] { tunekit::ident::decode_image(bytes, "fuzz.img", tunekit::ident::ImageColor::gray); });
  return 0;
}
