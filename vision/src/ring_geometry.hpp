#pragma once
// The geometry of a ring in a photo, for the ring print's width profile (photo_tests.cpp):
// its circle and the angle of a point around it. Inside the vision library, so that
// width_to_dynamics.hpp, which the protocols include, needs no OpenCV.

#include <vector>

#include <opencv2/core.hpp>

namespace tunekit::vision {

/// Circle through points (algebraic least squares). Returns centre and radius (same units).
cv::Vec3d fit_circle(const std::vector<cv::Point2d>& pts);

/// Polar angle of p around c as seen in the image (counterclockwise, 0 = +x), in [0, 2 pi).
double view_angle(cv::Point2d p, cv::Point2d c);

}  // namespace tunekit::vision
