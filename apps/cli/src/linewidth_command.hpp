#pragma once
// The `tunekit linewidth` command's options and per-image result, shared by its measurement
// (cmd_linewidth.cpp) and its mapping of a profile to time (linewidth_profile_csv.cpp).

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/envelope.hpp"
#include "tunekit/vision/image_io.hpp"
#include "tunekit/vision/line_width.hpp"

namespace tunekit::cli::linewidth {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct LinewidthArgs {
  std::vector<std::string> images;
  double max_image_mp = static_cast<double>(vision::kDefaultMaxImagePixels) / 1e6;
  double px_per_mm = 0;
  std::string camera;
  std::string chessboard;
  double square_mm = 0;
  std::string charuco;  // "5x7" squares; a ChArUco board instead of a chessboard
  double marker_mm = 0;
  std::string aruco_dict = "DICT_4X4_50";
  double reference_width_mm = 0;
  bool rectify = false;
  std::string polarity = "auto";
  double step_px = 1.0;
  double min_length_px = 60.0;
  bool allow_edge = false;
  std::string overlay_dir;
  std::string save_camera;
  // Mapping to time.
  std::string profile_csv;
  int line = 1;
  double speed_mm_s = 0;
  double setpoint_width_mm = 0;
  int ring_sines = 0;
  double ring_amplitude_mm = 0;
  double ring_radius_mm = 0;
  double rod_radius_mm = 0;
  double layer_height_mm = 0;
  double ring_start_deg = 0;
  bool ring_clockwise = false;
  std::string gcode;
  double filament_diameter_mm = 0;
  double path_offset_mm = kNaN;
  bool path_reversed = false;
  OutputOptions output;
};

struct ImageRun {
  std::string path;
  cv::Mat measured;  // the (undistorted / rectified) grey image that was measured
  double ppm = 0;
  std::string scale_source;
  std::vector<cv::Point> target_outline;
  vision::LineWidthResult result;
};

inline double r6(double v) { return std::isfinite(v) ? std::round(v * 1e6) / 1e6 : v; }
inline double r4(double v) { return std::isfinite(v) ? std::round(v * 1e4) / 1e4 : v; }

/// --profile-csv: maps line `a.line` of `run` to time, writes the CSV (atomically) and returns
/// the "profile_csv" results object; warnings go to `env`.
nlohmann::json write_profile_csv(const LinewidthArgs& a, const ImageRun& run, Envelope& env);

}  // namespace tunekit::cli::linewidth
