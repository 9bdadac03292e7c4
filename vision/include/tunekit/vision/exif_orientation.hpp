#pragma once
// EXIF orientation of JPEG photos. Cameras and phones store the sensor's pixels as read out
// and record how to turn them for display in the EXIF Orientation tag (0x0112, values 1-8;
// JEITA CP-3451, "Exchangeable image file format for digital still cameras: Exif", section
// 4.6.4). stb_image does not apply it, so a portrait photo would be measured lying on its side.

#include <string_view>

#include <opencv2/core.hpp>

namespace tunekit::vision {

/// The Orientation tag of a JPEG's APP1 Exif segment (IFD0), 1 ("top-left", nothing to do)
/// when the bytes are not a JPEG, carry no Exif segment or tag, or the tag is out of range.
/// Bounds-checked: a damaged segment gives 1, never a read past the data.
int jpeg_exif_orientation(std::string_view bytes);

/// The image turned as the orientation says it is displayed (2 mirror, 3 rotate 180,
/// 4 flip vertically, 5 transpose, 6 rotate 90 clockwise, 7 transverse, 8 rotate 90
/// counter-clockwise; 1 and anything else: unchanged).
cv::Mat apply_exif_orientation(const cv::Mat& image, int orientation);

}  // namespace tunekit::vision
