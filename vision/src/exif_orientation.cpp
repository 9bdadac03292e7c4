#include "tunekit/vision/exif_orientation.hpp"

#include <cstdint>
#include <cstring>

namespace tunekit::vision {
namespace {

std::uint16_t exif_u16(const unsigned char* p, bool little) {
  return little ? static_cast<std::uint16_t>(p[0] | (p[1] << 8)) : static_cast<std::uint16_t>((p[0] << 8) | p[1]);
}

std::uint32_t exif_u32(const unsigned char* p, bool little) {
  return little ? (std::uint32_t{p[0]} | (std::uint32_t{p[1]} << 8) | (std::uint32_t{p[2]} << 16) |
                   (std::uint32_t{p[3]} << 24))
                : ((std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
                   std::uint32_t{p[3]});
}

// Orientation from a TIFF header + IFD0 (the APP1 payload after "Exif\0\0"), 1 if absent.
int exif_tiff_orientation(const unsigned char* t, std::size_t n) {
  if (n < 8) return 1;
  bool little;
  if (t[0] == 'I' && t[1] == 'I') little = true;
  else if (t[0] == 'M' && t[1] == 'M') little = false;
  else return 1;
  if (exif_u16(t + 2, little) != 42) return 1;
  const std::uint32_t ifd = exif_u32(t + 4, little);
  if (ifd > n - 2 || ifd < 8) return 1;
  const std::size_t count = exif_u16(t + ifd, little);
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t e = ifd + 2 + 12 * i;
    if (e + 12 > n) return 1;
    if (exif_u16(t + e, little) != 0x0112) continue;
    const std::uint16_t type = exif_u16(t + e + 2, little);
    if (type != 3 || exif_u32(t + e + 4, little) != 1) return 1;  // SHORT, one value
    const int v = exif_u16(t + e + 8, little);
    return v >= 1 && v <= 8 ? v : 1;
  }
  return 1;
}

}  // namespace

int jpeg_exif_orientation(std::string_view bytes) {
  const auto* b = reinterpret_cast<const unsigned char*>(bytes.data());
  const std::size_t n = bytes.size();
  if (n < 4 || b[0] != 0xFF || b[1] != 0xD8) return 1;
  std::size_t pos = 2;
  while (pos + 4 <= n) {
    if (b[pos] != 0xFF) return 1;  // not at a marker: damaged
    const unsigned char marker = b[pos + 1];
    if (marker == 0xFF) {  // fill byte
      ++pos;
      continue;
    }
    if (marker == 0xD8 || marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) {  // no length
      pos += 2;
      continue;
    }
    if (marker == 0xDA || marker == 0xD9) return 1;  // image data: the header segments are over
    const std::size_t len = (std::size_t{b[pos + 2]} << 8) | b[pos + 3];
    if (len < 2 || pos + 2 + len > n) return 1;
    const unsigned char* seg = b + pos + 4;
    const std::size_t seg_len = len - 2;
    if (marker == 0xE1 && seg_len >= 6 && std::memcmp(seg, "Exif\0\0", 6) == 0)
      return exif_tiff_orientation(seg + 6, seg_len - 6);
    pos += 2 + len;
  }
  return 1;
}

cv::Mat apply_exif_orientation(const cv::Mat& m, int orientation) {
  cv::Mat out;
  switch (orientation) {
    case 2: cv::flip(m, out, 1); break;
    case 3: cv::rotate(m, out, cv::ROTATE_180); break;
    case 4: cv::flip(m, out, 0); break;
    case 5: cv::transpose(m, out); break;
    case 6: cv::rotate(m, out, cv::ROTATE_90_CLOCKWISE); break;
    case 7:
      cv::transpose(m, out);
      cv::flip(out, out, -1);
      break;
    case 8: cv::rotate(m, out, cv::ROTATE_90_COUNTERCLOCKWISE); break;
    default: return m;
  }
  return out;
}

}  // namespace tunekit::vision
