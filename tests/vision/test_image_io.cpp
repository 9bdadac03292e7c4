// Image files through stb (ident/image_io): round trips, colour handling and the errors a user
// sees for files that are not usable photos.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <functional>
#include <string>

#include <opencv2/core.hpp>

#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/vision/image_io.hpp"
#include "tunekit/vision/line_width.hpp"

using namespace tunekit;

namespace {

std::string error_of(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const InputError& e) {
    return e.formatted();
  }
  return "no InputError";
}

}  // namespace

TEST_CASE("image_io: PNG round trip keeps grey and BGR pixels and converts colour") {
  const auto dir = test::scratch_dir("image_io");
  cv::Mat grey(37, 53, CV_8U);
  cv::randu(grey, 0, 256);
  const auto gp = dir + "/grey.png";
  vision::write_png(gp, grey);
  const cv::Mat g2 = vision::read_image(gp);
  REQUIRE(g2.type() == CV_8UC1);
  CHECK(cv::norm(grey, g2, cv::NORM_INF) == 0);

  cv::Mat bgr(21, 34, CV_8UC3);
  cv::randu(bgr, 0, 256);
  bgr.at<cv::Vec3b>(0, 0) = cv::Vec3b(255, 0, 0);  // pure blue stays blue (no R/B swap)
  const auto cp = dir + "/colour.png";
  vision::write_png(cp, bgr);
  const cv::Mat c2 = vision::read_image(cp);
  REQUIRE(c2.type() == CV_8UC3);
  CHECK(cv::norm(bgr, c2, cv::NORM_INF) == 0);
  CHECK(c2.at<cv::Vec3b>(0, 0) == cv::Vec3b(255, 0, 0));
  const cv::Mat cg = vision::read_image(cp, vision::ImageColor::gray);
  CHECK(cg.type() == CV_8UC1);
  CHECK(std::abs(cg.at<uchar>(0, 0) - 29) <= 1);  // 0.114 * 255 (BT.601 luminance of blue)
  CHECK(vision::read_image(gp, vision::ImageColor::bgr).type() == CV_8UC3);
  // In-memory encode/decode agrees with the file.
  CHECK(cv::norm(vision::decode_image(vision::encode_png(bgr), "mem"), bgr, cv::NORM_INF) == 0);
}

TEST_CASE("image_io: unusable files are InputErrors with the reason and the file") {
  const auto dir = test::scratch_dir("image_io_err");
  CHECK(error_of([&] { vision::read_image(dir + "/missing.png"); }).find("no such file") != std::string::npos);
  const auto empty = test::write_scratch("image_io_empty.png", "");
  CHECK(error_of([&] { vision::read_image(empty); }).find("empty image file") != std::string::npos);
  const auto tiff = test::write_scratch("image_io_photo.tif", std::string("II*\0\x08\0\0\0", 8) + "rest");
  const auto te = error_of([&] { vision::read_image(tiff); });
  CHECK(te.find("TIFF images are not supported") != std::string::npos);
  CHECK(te.find("image_io_photo.tif") != std::string::npos);
  cv::Mat img(40, 40, CV_8U, cv::Scalar(99));
  const std::string png = vision::encode_png(img);
  const auto cut = test::write_scratch("image_io_cut.png", png.substr(0, png.size() / 2));
  CHECK(error_of([&] { vision::read_image(cut); }).find("cannot decode") != std::string::npos);
  CHECK(error_of([&] { vision::encode_png(cv::Mat(4, 4, CV_32F, cv::Scalar(1))); }).find("8 or 16 bit") !=
        std::string::npos);
  // The line-width loader refuses tiny images.
  const auto small = dir + "/small.png";
  vision::write_png(small, cv::Mat(8, 8, CV_8U, cv::Scalar(3)));
  CHECK(error_of([&] { vision::load_gray_image(small); }).find("image too small") != std::string::npos);
}
