// JPEG EXIF orientation: read from the APP1 segment and applied on decoding, checked on the
// public EXIF orientation example photos (datasets/images/PROVENANCE.md): every orientation
// decodes to the picture that orientation 1 shows.
#include <catch2/catch.hpp>

#include <string>

#include <opencv2/imgproc.hpp>

#include "test_support.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/vision/exif_orientation.hpp"
#include "tunekit/vision/image_io.hpp"
#include "tunekit/core/file_bytes.hpp"

using tunekit::test::dataset;

namespace {

cv::Mat small_gray(const cv::Mat& m) {
  cv::Mat g, s;
  cv::cvtColor(m, g, cv::COLOR_BGR2GRAY);
  cv::resize(g, s, cv::Size(90, 60), 0, 0, cv::INTER_AREA);
  return s;
}

double mean_abs_diff(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat d;
  cv::absdiff(a, b, d);
  return cv::mean(d)[0];
}

}  // namespace

TEST_CASE("the EXIF orientation tag is read from a JPEG's APP1 segment") {
  for (int n : {1, 3, 6, 8}) {
    INFO(n);
    const auto bytes = tunekit::read_file_bytes(dataset("images/Landscape_" + std::to_string(n) + ".jpg"));
    CHECK(tunekit::vision::jpeg_exif_orientation(bytes) == n);
  }
  // Not a JPEG, a damaged segment length, a truncated Exif block: 1, without reading past the end.
  CHECK(tunekit::vision::jpeg_exif_orientation("") == 1);
  CHECK(tunekit::vision::jpeg_exif_orientation("\x89PNG\r\n") == 1);
  CHECK(tunekit::vision::jpeg_exif_orientation(std::string("\xFF\xD8\xFF\xE1\xFF\xFF"
                                                           "Exif",
                                                           10)) == 1);
  const auto six = tunekit::read_file_bytes(dataset("images/Landscape_6.jpg"));
  for (std::size_t cut : {std::size_t{30}, std::size_t{40}, std::size_t{60}, std::size_t{100}})
    CHECK(tunekit::vision::jpeg_exif_orientation(six.substr(0, cut)) == 1);
}

TEST_CASE("photos with EXIF orientations 3, 6 and 8 decode to the picture orientation 1 shows") {
  const cv::Mat ref = tunekit::vision::read_image(dataset("images/Landscape_1.jpg"));
  REQUIRE(ref.cols > ref.rows);  // a landscape picture
  const cv::Mat ref_small = small_gray(ref);
  for (int n : {3, 6, 8}) {
    INFO(n);
    const cv::Mat m = tunekit::vision::read_image(dataset("images/Landscape_" + std::to_string(n) + ".jpg"));
    CHECK(m.cols == ref.cols);
    CHECK(m.rows == ref.rows);
    CHECK(mean_abs_diff(small_gray(m), ref_small) < 6.0);
    // The stored pixels (the decoded image turned back) are another picture: portrait for 6
    // and 8, upside down for 3.
    const cv::Mat stored = tunekit::vision::apply_exif_orientation(m, n == 6 ? 8 : (n == 8 ? 6 : 3));
    if (n == 3) CHECK(mean_abs_diff(small_gray(stored), ref_small) > 20.0);
    else CHECK(stored.rows > stored.cols);
  }
}
