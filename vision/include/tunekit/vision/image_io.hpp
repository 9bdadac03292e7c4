#pragma once
// Image files without OpenCV's imgcodecs module: decoding and PNG encoding through stb_image /
// stb_image_write (Debian's libstb). OpenCV's imgcodecs pulls in ~140 shared libraries (GDAL,
// poppler, HDF5, ...) whose dynamic loading alone costs ~0.1 s at every start of `tunekit`,
// whatever the command; stb costs nothing measurable.
//
// Readable: PNG (8 and 16 bit), JPEG (baseline and progressive), BMP, PNM (PGM/PPM), TGA, PSD
// (composited), GIF (first frame), HDR is not accepted (float). TIFF is refused with a hint to
// convert it to PNG, which keeps 16-bit depth. A JPEG's EXIF orientation is applied
// (exif_orientation.hpp), so a photo is measured as it is displayed.

#include <cstdint>
#include <string>
#include <string_view>

#include <opencv2/core.hpp>

namespace tunekit::vision {

enum class ImageColor {
  keep,  ///< 1 channel for grey files, 3 channels (BGR) for colour; alpha is dropped
  gray,  ///< always 1 channel (colour converted to luminance, ITU-R BT.601 like OpenCV)
  bgr,   ///< always 3 channels (BGR)
};

/// Images are refused before decoding when their header claims more pixels than this
/// (width x height, read without decoding): 100 megapixels is four times the largest
/// photo of a common camera (24 MP) and keeps a decoded 16-bit colour image below 1 GB.
inline constexpr std::uint64_t kDefaultMaxImagePixels = 100'000'000;

/// The limit in force for this process (default kDefaultMaxImagePixels); `tunekit linewidth
/// --max-image-mp` changes it. 0 is refused (InputError).
void set_max_image_pixels(std::uint64_t pixels);
std::uint64_t max_image_pixels();

/// Reads an image file as CV_8U or CV_16U (the file's depth), 1 or 3 channels as asked.
/// Throws InputError ("cannot read image: no such file", "empty image file (0 bytes)",
/// "cannot decode image: <reason>", "TIFF images are not supported ...", "image of W x H pixels
/// exceeds the limit ...") located at `path`.
cv::Mat read_image(const std::string& path, ImageColor color = ImageColor::keep);

/// The bytes of an image file, read once for decode_image() (the same errors as read_image()'s
/// for a file that cannot be read).
std::string read_image_bytes(const std::string& path);

/// Decodes an image held in memory; `name` is the location used in error messages.
cv::Mat decode_image(std::string_view bytes, const std::string& name, ImageColor color = ImageColor::keep);

/// PNG file contents of an 8-bit image with 1, 3 (BGR) or 4 (BGRA) channels; 16-bit images are
/// scaled to 8 bit. Throws InputError for other types or an empty image.
std::string encode_png(const cv::Mat& image);

/// Writes encode_png(image) to `path` and returns those bytes. Throws InputError when the file
/// cannot be written.
std::string write_png(const std::string& path, const cv::Mat& image);

}  // namespace tunekit::vision
