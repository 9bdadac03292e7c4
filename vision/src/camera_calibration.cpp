#include "tunekit/vision/camera_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <regex>
#include <sstream>

#include <fmt/format.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "tunekit/core/json_error_text.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/file_bytes.hpp"

namespace tunekit::vision {
namespace {

cv::Mat to_u8(const cv::Mat& gray) {
  if (gray.type() == CV_8U) return gray;
  double lo = 0, hi = 0;
  cv::minMaxLoc(gray, &lo, &hi);
  cv::Mat out;
  if (gray.depth() == CV_8U) return gray;
  // Stretch to 8 bit (16-bit and float images).
  const double scale = hi > lo ? 255.0 / (hi - lo) : 1.0;
  gray.convertTo(out, CV_8U, scale, -lo * scale);
  return out;
}

cv::Point2d apply(const cv::Matx33d& H, cv::Point2d p) {
  const cv::Vec3d q = H * cv::Vec3d(p.x, p.y, 1.0);
  return {q[0] / q[2], q[1] / q[2]};
}

nlohmann::json mat_json(const cv::Matx33d& m) {
  nlohmann::json j = nlohmann::json::array();
  for (int r = 0; r < 3; ++r) j.push_back({m(r, 0), m(r, 1), m(r, 2)});
  return j;
}

cv::Matx33d json_mat(const nlohmann::json& j, const std::string& what, const std::string& origin) {
  if (!j.is_array() || j.size() != 3) throw InputError(fmt::format("'{}' must be a 3x3 array", what), origin);
  cv::Matx33d m;
  for (int r = 0; r < 3; ++r) {
    const auto& row = j[static_cast<std::size_t>(r)];
    if (!row.is_array() || row.size() != 3) throw InputError(fmt::format("'{}' must be a 3x3 array", what), origin);
    for (int c = 0; c < 3; ++c) m(r, c) = row[static_cast<std::size_t>(c)].get<double>();
  }
  return m;
}

}  // namespace

ChessboardSpec parse_chessboard_spec(const std::string& text, double square_mm) {
  static const std::regex re(R"(^\s*(\d+)\s*[xX]\s*(\d+)\s*$)");
  std::smatch m;
  if (!std::regex_match(text, m, re))
    throw InputError(fmt::format("chessboard '{}' is not COLSxROWS (inner corners, e.g. 9x6)", text));
  ChessboardSpec s;
  s.cols = std::stoi(m[1]);
  s.rows = std::stoi(m[2]);
  s.square_mm = square_mm;
  if (s.cols < 2 || s.rows < 2 || s.cols > 200 || s.rows > 200)
    throw InputError(fmt::format("chessboard '{}': inner corners must be 2..200 each way", text));
  if (!(square_mm > 0)) throw InputError("chessboard square size must be > 0 mm (--square-mm)");
  return s;
}

double local_px_per_mm(const cv::Matx33d& img_to_mm, cv::Point2d p) {
  const double h = 0.5;
  const cv::Point2d a = apply(img_to_mm, {p.x - h, p.y}), b = apply(img_to_mm, {p.x + h, p.y});
  const cv::Point2d c = apply(img_to_mm, {p.x, p.y - h}), d = apply(img_to_mm, {p.x, p.y + h});
  const double j11 = (b.x - a.x) / (2 * h), j21 = (b.y - a.y) / (2 * h);
  const double j12 = (d.x - c.x) / (2 * h), j22 = (d.y - c.y) / (2 * h);
  const double mm2_per_px2 = std::abs(j11 * j22 - j12 * j21);
  return 1.0 / std::sqrt(mm2_per_px2);
}

ChessboardDetection detect_chessboard(const cv::Mat& gray, const ChessboardSpec& spec) {
  ChessboardDetection det;
  const cv::Mat u8 = to_u8(gray);
  const cv::Size pattern(spec.cols, spec.rows);
  std::vector<cv::Point2f> corners;
  bool found = false;
  try {
    found = cv::findChessboardCornersSB(u8, pattern, corners,
                                        cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_EXHAUSTIVE | cv::CALIB_CB_ACCURACY);
  } catch (const cv::Exception&) {
    found = false;
  }
  if (!found) {
    found =
        cv::findChessboardCorners(u8, pattern, corners, cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
    if (found)
      cv::cornerSubPix(u8, corners, cv::Size(5, 5), cv::Size(-1, -1),
                       cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-3));
  }
  if (!found || corners.size() != static_cast<std::size_t>(spec.cols * spec.rows)) return det;
  std::vector<cv::Point2f> board;
  for (int r = 0; r < spec.rows; ++r)
    for (int c = 0; c < spec.cols; ++c)
      board.emplace_back(static_cast<float>(c * spec.square_mm), static_cast<float>(r * spec.square_mm));
  const cv::Mat H = cv::findHomography(corners, board, 0);
  if (H.empty()) return det;
  det.found = true;
  det.corners = corners;
  det.img_to_mm = cv::Matx33d(H);
  double ss = 0;
  const cv::Matx33d inv = det.img_to_mm.inv();
  cv::Point2d centre(0, 0);
  for (std::size_t i = 0; i < corners.size(); ++i) {
    const cv::Point2d p = apply(inv, board[i]);
    ss += (p.x - corners[i].x) * (p.x - corners[i].x) + (p.y - corners[i].y) * (p.y - corners[i].y);
    centre += cv::Point2d(corners[i]);
  }
  det.fit_rms_px = std::sqrt(ss / static_cast<double>(corners.size()));
  centre *= 1.0 / static_cast<double>(corners.size());
  det.px_per_mm = local_px_per_mm(det.img_to_mm, centre);
  const double s = spec.square_mm;
  const double xe = (spec.cols - 1) * s, ye = (spec.rows - 1) * s;
  for (const cv::Point2d q : {cv::Point2d(-1.6 * s, -1.6 * s), cv::Point2d(xe + 1.6 * s, -1.6 * s),
                              cv::Point2d(xe + 1.6 * s, ye + 1.6 * s), cv::Point2d(-1.6 * s, ye + 1.6 * s)}) {
    const cv::Point2d p = apply(inv, q);
    det.outline.emplace_back(static_cast<int>(std::lround(p.x)), static_cast<int>(std::lround(p.y)));
  }
  return det;
}

nlohmann::json CameraProfile::to_json() const {
  nlohmann::json j;
  j["format"] = "tunekit camera profile";
  j["version"] = 1;
  j["image_size_px"] = {image_size.width, image_size.height};
  j["camera_matrix"] = mat_json(camera_matrix);
  j["dist_coeffs"] = dist_coeffs;
  j["rms_reprojection_px"] = rms_reprojection_px;
  j["images_used"] = images_used;
  j["target"] = {
      {"type", "chessboard"}, {"inner_corners", {target.cols, target.rows}}, {"square_mm", target.square_mm}};
  if (has_bed_plane) {
    j["bed_plane"] = {{"img_to_mm", mat_json(bed_img_to_mm)}, {"px_per_mm", px_per_mm}};
  }
  return j;
}

CameraProfile CameraProfile::from_json(const nlohmann::json& j, const std::string& origin) {
  CameraProfile p;
  try {
    if (j.value("format", std::string()) != "tunekit camera profile")
      throw InputError("not a tunekit camera profile (missing \"format\": \"tunekit camera profile\")", origin);
    const auto& sz = j.at("image_size_px");
    p.image_size = cv::Size(sz.at(0).get<int>(), sz.at(1).get<int>());
    p.camera_matrix = json_mat(j.at("camera_matrix"), "camera_matrix", origin);
    p.dist_coeffs = j.at("dist_coeffs").get<std::vector<double>>();
    p.rms_reprojection_px = j.value("rms_reprojection_px", 0.0);
    p.images_used = j.value("images_used", 0);
    if (j.contains("target")) {
      const auto& t = j["target"];
      p.target.cols = t.at("inner_corners").at(0).get<int>();
      p.target.rows = t.at("inner_corners").at(1).get<int>();
      p.target.square_mm = t.at("square_mm").get<double>();
    }
    if (j.contains("bed_plane")) {
      p.has_bed_plane = true;
      p.bed_img_to_mm = json_mat(j["bed_plane"].at("img_to_mm"), "bed_plane.img_to_mm", origin);
      p.px_per_mm = j["bed_plane"].at("px_per_mm").get<double>();
      if (!(p.px_per_mm > 0)) throw InputError("bed_plane.px_per_mm must be > 0", origin);
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("malformed camera profile: {}", core::plain_json_error(e.what())), origin);
  }
  return p;
}

CameraProfile calibrate_camera(const std::vector<cv::Mat>& grays, const ChessboardSpec& spec,
                               std::vector<int>* skipped) {
  std::vector<std::vector<cv::Point3f>> obj;
  std::vector<std::vector<cv::Point2f>> img;
  CameraProfile p;
  p.target = spec;
  int first = -1;
  for (std::size_t i = 0; i < grays.size(); ++i) {
    if (i == 0) p.image_size = grays[i].size();
    if (grays[i].size() != p.image_size)
      throw InputError(fmt::format("calibration image {} is {}x{} px, the first is {}x{} px", i + 1, grays[i].cols,
                                   grays[i].rows, p.image_size.width, p.image_size.height));
    const auto det = detect_chessboard(grays[i], spec);
    if (!det.found) {
      if (skipped) skipped->push_back(static_cast<int>(i));
      continue;
    }
    if (first < 0) first = static_cast<int>(i);
    std::vector<cv::Point3f> o;
    for (int r = 0; r < spec.rows; ++r)
      for (int c = 0; c < spec.cols; ++c)
        o.emplace_back(static_cast<float>(c * spec.square_mm), static_cast<float>(r * spec.square_mm), 0.f);
    obj.push_back(std::move(o));
    img.push_back(det.corners);
  }
  if (img.size() < 3)
    throw InputError(fmt::format("camera calibration needs the {}x{} chessboard in at least 3 images; found it in {}",
                                 spec.cols, spec.rows, img.size()));
  cv::Mat K, D;
  std::vector<cv::Mat> rvecs, tvecs;
  double rms = 0;
  try {
    rms = cv::calibrateCamera(obj, img, p.image_size, K, D, rvecs, tvecs, 0,
                              cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-12));
  } catch (const cv::Exception& e) {
    throw FitError(fmt::format("camera calibration failed: {}", e.what()));
  }
  if (!std::isfinite(rms)) throw FitError("camera calibration did not converge");
  p.camera_matrix = cv::Matx33d(K);
  p.dist_coeffs.assign(D.begin<double>(), D.end<double>());
  p.rms_reprojection_px = rms;
  p.images_used = static_cast<int>(img.size());
  // Bed plane from the first board, on the undistorted image.
  std::vector<cv::Point2f> und;
  cv::undistortPoints(img.front(), und, K, D, cv::noArray(), K);
  std::vector<cv::Point2f> board;
  for (const auto& q : obj.front()) board.emplace_back(q.x, q.y);
  const cv::Mat H = cv::findHomography(und, board, 0);
  if (!H.empty()) {
    p.has_bed_plane = true;
    p.bed_img_to_mm = cv::Matx33d(H);
    cv::Point2d c(0, 0);
    for (const auto& q : und) c += cv::Point2d(q);
    c *= 1.0 / static_cast<double>(und.size());
    p.px_per_mm = local_px_per_mm(p.bed_img_to_mm, c);
  }
  return p;
}

CameraProfile load_camera_profile(const std::string& path) { return parse_camera_profile(read_file_bytes(path), path); }

CameraProfile parse_camera_profile(std::string_view text, const std::string& path) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("camera profile is not valid JSON: {}", core::plain_json_error(e.what())), path);
  }
  return CameraProfile::from_json(j, path);
}

cv::Mat undistort_image(const cv::Mat& gray, const CameraProfile& p, const std::string& origin) {
  if (gray.size() != p.image_size)
    throw InputError(fmt::format("image is {}x{} px but the camera profile was calibrated at {}x{} px", gray.cols,
                                 gray.rows, p.image_size.width, p.image_size.height),
                     origin);
  if (p.dist_coeffs.empty() || std::all_of(p.dist_coeffs.begin(), p.dist_coeffs.end(), [](double d) { return d == 0; }))
    return gray;
  cv::Mat out;
  cv::undistort(gray, out, cv::Mat(p.camera_matrix), p.dist_coeffs);
  return out;
}

Rectified rectify_to_plane(const cv::Mat& gray, const cv::Matx33d& img_to_mm, double px_per_mm, double max_pixels) {
  Rectified r;
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (const cv::Point2d c : {cv::Point2d(0, 0), cv::Point2d(gray.cols - 1.0, 0), cv::Point2d(0, gray.rows - 1.0),
                              cv::Point2d(gray.cols - 1.0, gray.rows - 1.0)}) {
    const cv::Vec3d q = img_to_mm * cv::Vec3d(c.x, c.y, 1.0);
    if (!(q[2] > 0) && !(q[2] < 0)) throw InputError("the bed plane is seen edge-on: cannot rectify");
    const double x = q[0] / q[2], y = q[1] / q[2];
    x0 = std::min(x0, x);
    y0 = std::min(y0, y);
    x1 = std::max(x1, x);
    y1 = std::max(y1, y);
  }
  double ppm = px_per_mm;
  const double area = (x1 - x0) * (y1 - y0) * ppm * ppm;
  if (!(area > 0) || !std::isfinite(area)) throw InputError("the bed plane's footprint in the image is degenerate");
  if (area > max_pixels) ppm *= std::sqrt(max_pixels / area);
  const cv::Matx33d S(ppm, 0, -x0 * ppm, 0, ppm, -y0 * ppm, 0, 0, 1);
  r.img_to_rect = S * img_to_mm;
  r.px_per_mm = ppm;
  const cv::Size size(static_cast<int>(std::ceil((x1 - x0) * ppm)) + 1,
                      static_cast<int>(std::ceil((y1 - y0) * ppm)) + 1);
  cv::warpPerspective(gray, r.image, cv::Mat(r.img_to_rect), size, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  return r;
}

}  // namespace tunekit::vision
