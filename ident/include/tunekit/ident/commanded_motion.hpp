#pragma once
// The commanded motion of an axis test, piece by piece, as the machine ran it.
//
// A motion planner runs each move as pieces of constant jerk (constant acceleration for
// Klipper's trapezoids, whose motion_report/dump_trapq rows are such pieces). Beside an
// accelerometer record they give the input of the axis' resonance exactly, which an output-error
// fit needs (axis_response_fit.hpp). tunekit writes them as commanded_motion_<axis>_<tag>.csv
// beside raw_data_<axis>_<tag>.csv: columns time (s, the piece's start on the accelerometer's
// clock), duration (s), accel_x and accel_y (mm/s^2 at the start), jerk_x and jerk_y (mm/s^3).

#include <string>
#include <string_view>
#include <vector>

namespace tunekit::ident {

/// One piece along one axis: from t0_s for duration_s, the acceleration accel + jerk (t - t0).
struct AccelPiece {
  double t0_s = 0;
  double duration_s = 0;
  double accel_mm_s2 = 0;
  double jerk_mm_s3 = 0;
};

/// The pieces of `axis` ('x' or 'y') from a commanded-motion CSV in memory, in time order.
/// InputError (exit 2) for a missing column, a value that is not finite, a negative duration or
/// pieces out of time order.
std::vector<AccelPiece> load_commanded_motion_csv(const std::string& path, std::string_view bytes, char axis);

/// The commanded-motion file that belongs to a raw accelerometer record: raw_data_<rest>.csv ->
/// commanded_motion_<rest>.csv in the same folder. Empty when the name does not follow that
/// pattern or the file does not exist.
std::string commanded_motion_beside(const std::string& raw_path);

}  // namespace tunekit::ident
