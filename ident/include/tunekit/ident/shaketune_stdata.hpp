#pragma once
// Shake&Tune's measurement files (.stdata): what the Klipper plugin Shake&Tune (Félix
// Boisselier, Klippain Shake&Tune, version 5, 2024-2025) keeps next to its graphs in
// ShakeTune_results/ instead of Klipper's raw CSVs:
//
//   a Zstandard stream (RFC 8878) of JSON lines, one measurement per line:
//   {"name": "axis_X_20250509_131745", "samples": [[t, accel_x, accel_y, accel_z], ...]}
//
// t in s (the printer's clock), accelerations in mm/s^2: the samples Klipper's accelerometer
// client reports, the same numbers Klipper's raw_data_*.csv holds (Klipper,
// klippy/extras/adxl345.py, AccelQueryHelper.write_to_file). Input-shaper measurements are
// named axis_<X|Y|Z>_<date>; belt comparisons belt_<A|B>_<date>.

#include <string>
#include <string_view>
#include <vector>

#include "tunekit/ident/resonance.hpp"

namespace tunekit::ident {

/// True when the bytes start with a Zstandard frame (magic 28 B5 2F FD), as .stdata files do.
bool is_shaketune_stdata(std::string_view bytes);

/// The largest decompressed .stdata accepted, bytes: a 130 s sweep at 3.2 kHz is about 21 MB
/// of JSON; anything beyond this is not a measurement file.
inline constexpr std::size_t kMaxStdataBytes = std::size_t{1} << 30;

struct StdataMeasurement {
  std::string name;    ///< Shake&Tune's measurement name, e.g. axis_X_20250509_131745
  AccelRecord record;  ///< path "FILE[name]"; its line N (in messages) is sample N - 1
};

/// Decompresses and reads every measurement of a .stdata file. The axis of a measurement is
/// options.axis, else the one its name gives (axis_X_... -> 'x'), else 0. Each measurement
/// goes through the same checks as a Klipper raw CSV (load_accel_csv: sampling, gaps, clipping,
/// non-physical samples). InputError (exit 2) for a broken Zstandard stream, a line that is not
/// a measurement, or a file without measurements.
std::vector<StdataMeasurement> load_shaketune_stdata(const std::string& path, std::string_view bytes,
                                                     const AccelInputOptions& options);

}  // namespace tunekit::ident
