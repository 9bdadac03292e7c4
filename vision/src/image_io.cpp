#include "tunekit/vision/image_io.hpp"

#include <algorithm>
#include <atomic>
#include "tunekit/vision/exif_orientation.hpp"

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>
#include <stb_image.h>
#include <stb_image_write.h>

#include "tunekit/core/error.hpp"
#include "tunekit/core/file_bytes.hpp"

namespace tunekit::vision {
namespace {

bool starts_with(std::string_view s, const char* magic, std::size_t n) {
  return s.size() >= n && std::memcmp(s.data(), magic, n) == 0;
}

struct StbFree {
  void operator()(void* p) const { stbi_image_free(p); }
};

cv::Mat convert_color(const cv::Mat& m, ImageColor color) {
  const int ch = m.channels();
  cv::Mat out;
  switch (color) {
    case ImageColor::keep: return m;
    case ImageColor::gray:
      if (ch == 1) return m;
      cv::cvtColor(m, out, cv::COLOR_BGR2GRAY);
      return out;
    case ImageColor::bgr:
      if (ch == 3) return m;
      cv::cvtColor(m, out, cv::COLOR_GRAY2BGR);
      return out;
  }
  return m;
}

}  // namespace

namespace {
std::atomic<std::uint64_t> g_max_image_pixels{kDefaultMaxImagePixels};
}  // namespace

void set_max_image_pixels(std::uint64_t pixels) {
  if (pixels == 0) throw InputError("the image size limit must be at least one pixel");
  g_max_image_pixels = pixels;
}

std::uint64_t max_image_pixels() { return g_max_image_pixels; }

cv::Mat decode_image(std::string_view bytes, const std::string& name, ImageColor color) {
  if (bytes.empty()) throw InputError("empty image file (0 bytes)", name);
  if (starts_with(bytes, "II*\0", 4) || starts_with(bytes, "MM\0*", 4))
    throw InputError("TIFF images are not supported: convert the photo to PNG (16-bit PNG keeps the depth)", name);
  if (bytes.size() > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw InputError("image file too large (over 2 GiB)", name);
  const auto* data = reinterpret_cast<const stbi_uc*>(bytes.data());
  const int len = static_cast<int>(bytes.size());
  int w = 0, h = 0, n = 0;
  if (!stbi_info_from_memory(data, len, &w, &h, &n)) {
    const char* why = stbi_failure_reason();
    throw InputError(fmt::format("cannot decode image (not an image, truncated, or an unsupported format: {})",
                                 why ? why : "unknown"),
                     name);
  }
  // The header's dimensions, before any pixel is decoded: a tiny file may claim a huge image.
  // Magnitudes: a top-down BMP stores a negative height, which stb's info call passes on as
  // it is, while its decoder allocates for the magnitude (a libFuzzer finding: a 29-byte BMP
  // claiming 14852 x -45747 pixels passed a check that clamped negatives to zero).
  const std::uint64_t w_claimed = static_cast<std::uint64_t>(std::llabs(static_cast<long long>(w)));
  const std::uint64_t h_claimed = static_cast<std::uint64_t>(std::llabs(static_cast<long long>(h)));
  const std::uint64_t pixels_claimed = w_claimed * h_claimed;
  if (pixels_claimed > max_image_pixels())
    throw InputError(fmt::format("image of {} x {} pixels ({:.1f} MP) exceeds the limit of {:.1f} MP (raise it with "
                                 "--max-image-mp); nothing was decoded",
                                 w_claimed, h_claimed, static_cast<double>(pixels_claimed) / 1e6,
                                 static_cast<double>(max_image_pixels()) / 1e6),
                     name);
  if (stbi_is_hdr_from_memory(data, len))
    throw InputError("cannot decode image: HDR (float) images are not supported", name);
  const bool sixteen = stbi_is_16_bit_from_memory(data, len) != 0;
  void* pixels = sixteen ? static_cast<void*>(stbi_load_16_from_memory(data, len, &w, &h, &n, 0))
                         : static_cast<void*>(stbi_load_from_memory(data, len, &w, &h, &n, 0));
  if (!pixels) {
    const char* why = stbi_failure_reason();
    throw InputError(fmt::format("cannot decode image (truncated or corrupt: {})", why ? why : "unknown"), name);
  }
  std::unique_ptr<void, StbFree> hold(pixels);
  if (w <= 0 || h <= 0 || n < 1 || n > 4) throw InputError("cannot decode image: no pixels", name);
  const int depth = sixteen ? CV_16U : CV_8U;
  const cv::Mat raw(h, w, CV_MAKETYPE(depth, n), pixels);
  cv::Mat m;
  switch (n) {
    case 1: m = raw.clone(); break;
    case 2: cv::extractChannel(raw, m, 0); break;  // grey + alpha
    case 3: cv::cvtColor(raw, m, cv::COLOR_RGB2BGR); break;
    case 4: cv::cvtColor(raw, m, cv::COLOR_RGBA2BGR); break;
    default: break;
  }
  // JPEG photos turned as their EXIF orientation says they are displayed.
  m = apply_exif_orientation(m, jpeg_exif_orientation(bytes));
  return convert_color(m, color);
}

std::string read_image_bytes(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError("cannot read image: no such file", path);
  return read_file_bytes(path);
}

cv::Mat read_image(const std::string& path, ImageColor color) {
  return decode_image(read_image_bytes(path), path, color);
}

std::string encode_png(const cv::Mat& image) {
  if (image.empty()) throw InputError("cannot encode an empty image as PNG");
  cv::Mat m8;
  if (image.depth() == CV_8U) m8 = image;
  else if (image.depth() == CV_16U) image.convertTo(m8, CV_8U, 1.0 / 257.0);
  else
    throw InputError(fmt::format("cannot encode an image of OpenCV type {} as PNG (8 or 16 bit only)", image.type()));
  cv::Mat rgb;
  switch (m8.channels()) {
    case 1: rgb = m8; break;
    case 3: cv::cvtColor(m8, rgb, cv::COLOR_BGR2RGB); break;
    case 4: cv::cvtColor(m8, rgb, cv::COLOR_BGRA2RGBA); break;
    default: throw InputError(fmt::format("cannot encode an image with {} channels as PNG", m8.channels()));
  }
  if (!rgb.isContinuous()) rgb = rgb.clone();
  std::string out;
  auto sink = [](void* ctx, void* data, int size) {
    static_cast<std::string*>(ctx)->append(static_cast<const char*>(data), static_cast<std::size_t>(size));
  };
  const int ok =
      stbi_write_png_to_func(sink, &out, rgb.cols, rgb.rows, rgb.channels(), rgb.data, static_cast<int>(rgb.step[0]));
  if (!ok || out.empty()) throw InputError("PNG encoding failed");
  return out;
}

std::string write_png(const std::string& path, const cv::Mat& image) {
  const std::string png = encode_png(image);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw InputError("cannot write image: cannot create the file", path);
  out.write(png.data(), static_cast<std::streamsize>(png.size()));
  out.close();
  if (!out) throw InputError("cannot write image: write error", path);
  return png;
}

}  // namespace tunekit::vision
