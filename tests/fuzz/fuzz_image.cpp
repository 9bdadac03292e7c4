// The image readers (PNG, JPEG, BMP, PNM, TGA, PSD, GIF through stb) on arbitrary bytes, with
// the pixel limit checked before decoding (kept small here so that a fuzzed header cannot ask
// for gigabytes).
#include "fuzz_common.hpp"
#include "tunekit/vision/image_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool limited = (tunekit::vision::set_max_image_pixels(4'000'000), true);
  (void)limited;
  const std::string bytes(tunekit::fuzz::as_text(data, size));
  tunekit::fuzz::expect_result_or_error([&] { tunekit::vision::decode_image(bytes, "fuzz.img"); });
  tunekit::fuzz::expect_result_or_error(
      [&] { tunekit::vision::decode_image(bytes, "fuzz.img", tunekit::vision::ImageColor::gray); });
  return 0;
}
