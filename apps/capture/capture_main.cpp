// tunekit-capture: one averaged still from a camera, for `tunekit calibrate --liquefier camera
// --camera-device`. It is the only program linked with OpenCV's videoio module (which loads the
// camera back-ends: V4L2, GStreamer, FFmpeg), so `tunekit` itself starts without them.
//
//   tunekit-capture DEVICE OUT.png [FRAMES] [SETTLE_S]
//
// Opens DEVICE (a path such as /dev/video0, or an index), lets auto-focus and auto-exposure
// settle for SETTLE_S seconds (frames are read and dropped meanwhile), averages FRAMES frames
// (less sensor noise) and writes an 8-bit PNG. Exit 0 on success; 3 with one line on stderr
// when the camera cannot be opened or gives no frame; 2 for bad arguments.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "tunekit/core/error.hpp"
#include "tunekit/vision/image_io.hpp"

int main(int argc, char** argv) {
  if (argc < 3 || argc > 5) {
    std::fprintf(stderr, "usage: tunekit-capture DEVICE OUT.png [FRAMES] [SETTLE_S]\n");
    return 2;
  }
  const std::string device = argv[1], out = argv[2];
  const int frames = argc > 3 ? std::atoi(argv[3]) : 8;
  const double settle_s = argc > 4 ? std::atof(argv[4]) : 2.0;
  if (frames < 1 || frames > 1000 || !(settle_s >= 0 && settle_s < 60)) {
    std::fprintf(stderr, "tunekit-capture: error: FRAMES must be 1..1000 and SETTLE_S 0..60\n");
    return 2;
  }
  // OpenCV's back-ends log their own warnings (GStreamer: "no source element"); the one error line is ours.
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_ERROR);
  cv::VideoCapture cap;
  const bool numeric = !device.empty() && device.find_first_not_of("0123456789") == std::string::npos;
  const bool opened = numeric ? cap.open(std::atoi(device.c_str())) : cap.open(device);
  if (!opened || !cap.isOpened()) {
    std::fprintf(stderr, "tunekit: error: %s: the camera cannot be opened\n", device.c_str());
    return 3;
  }
  cv::Mat frame;
  const auto settle_until = std::chrono::steady_clock::now() + std::chrono::duration<double>(settle_s);
  while (std::chrono::steady_clock::now() < settle_until)
    if (!cap.read(frame)) break;
  cv::Mat sum;
  int got = 0;
  for (int k = 0; k < frames * 3 && got < frames; ++k) {
    if (!cap.read(frame) || frame.empty()) continue;
    cv::Mat f;
    frame.convertTo(f, CV_32F);
    if (sum.empty()) sum = cv::Mat::zeros(f.size(), f.type());
    if (f.size() != sum.size() || f.type() != sum.type()) continue;
    sum += f;
    ++got;
  }
  if (got == 0) {
    std::fprintf(stderr, "tunekit: error: %s: the camera opened but gave no frame\n", device.c_str());
    return 3;
  }
  cv::Mat avg;
  sum.convertTo(avg, CV_8U, 1.0 / got);
  try {
    tunekit::vision::write_png(out, avg);
  } catch (const tunekit::Error& e) {
    std::fprintf(stderr, "tunekit: error: %s\n", e.formatted().c_str());
    return 2;
  }
  return 0;
}
