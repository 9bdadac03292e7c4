#pragma once
// RepRapFirmware's accelerometer files: what `M956 P<board> S<samples> A<mode>` writes to
// 0:/sys/accelerometer/*.csv (Duet3D, RepRapFirmware, src/Accelerometers/Accelerometers.cpp,
// and the Duet3D documentation "Connecting an accelerometer", 2021-2024):
//
//   Sample,X,Y,Z                 header: "Sample" and the recorded axes (M956 A... / the axes asked for)
//   0,0.012,-0.031,1.002         sample number, then acceleration in g (2 to 4 decimals by resolution)
//   ...
//   Rate 1344, overflows 0       trailer: the measured sample rate (Hz) and FIFO overflows
//
// A run that failed ends with "Failed to collect data from accelerometer", "Failed to start
// accelerometer", "Received bad data" or "Received mismatched data" instead of the trailer.
// There is no time column: sample k is at k / rate seconds.

#include <string>
#include <string_view>

#include "tunekit/ident/resonance.hpp"

namespace tunekit::ident {

/// Standard gravity in mm/s^2 (RRF writes g).
constexpr double kStandardGravityMmS2 = 9806.65;

/// True when the text starts with RRF's "Sample,X..." header.
bool is_rrf_accelerometer_csv(std::string_view bytes);

/// Reads an M956 file into an accelerometer record (mm/s^2, time from the rate). InputError
/// (FILE:LINE) for a failed run, a missing or bad "Rate" trailer, or a bad row; FIFO overflows
/// are a warning. The accel_columns / time_column options do not apply (the layout is fixed);
/// the axis comes from `options.axis` or the file name.
AccelRecord load_rrf_accelerometer_csv(const std::string& path, std::string_view bytes,
                                       const AccelInputOptions& options);

}  // namespace tunekit::ident
