#pragma once
// Shared by `tunekit linewidth`'s measurement (linewidth_command.cpp) and its mapping of a profile to
// time (linewidth_profile_csv.cpp): one measured image and the rounding of reported values.

#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "tunekit/calibration/results/input_digest.hpp"
#include "tunekit/calibration/analyses/linewidth_command.hpp"
#include "tunekit/vision/line_width.hpp"
#include "tunekit/vision/photo_widths.hpp"

namespace tunekit::calibration::linewidth {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct ImageRun {
  std::string path;
  cv::Mat measured;  // the (undistorted / rectified) grey image that was measured
  double ppm = 0;
  vision::ScaleChoice scale;
  std::vector<cv::Point> target_outline;
  vision::LineWidthResult result;
  std::vector<vision::CalibratedLine> lines;  // result's lines in mm
  std::optional<vision::RingResult> ring;
  std::vector<std::string> warnings;
};

inline double r6(double v) { return std::isfinite(v) ? std::round(v * 1e6) / 1e6 : v; }
inline double r4(double v) { return std::isfinite(v) ? std::round(v * 1e4) / 1e4 : v; }

/// The ring test described by the ring options (--ring-sines and its modulation).
vision::RingTest ring_test(const LinewidthOptions& a);

/// --profile-csv: maps line `a.line` of `run` to time, writes the CSV (atomically) and returns
/// the "profile_csv" results object; appends its warnings and the G-code it read.
nlohmann::json write_profile_csv(const LinewidthOptions& a, const ImageRun& run, std::vector<std::string>& warnings,
                                 std::vector<InputDigest>& inputs);

}  // namespace tunekit::calibration::linewidth
