#pragma once
// Time-series CSV input. Columns are selected by name; a name may carry its unit in
// brackets or parentheses ("force (N)", "time[s]", "shear rate [1/s]") or as a snake_case
// suffix as pandas and most loggers write it ("time_s", "flow_mm3_s", "force_N",
// "shear_rate_1_s"); matching ignores case, and a column is found by its name as written or
// by its name without the unit ("flow" finds "flow_mm3_s").
// Lines starting with '#' are comments, except that a comment directly above the first
// row of numbers is taken as the header when the file has no header of its own -- this is
// how Klipper writes raw accelerometer data (`#time,accel_x,accel_y,accel_z`).
// Numbers are parsed with std::from_chars. Every problem is an InputError located as
// FILE:LINE:COLUMN (1-based), which the CLI turns into exit code 2.

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "tunekit/core/file_bytes.hpp"
#include "tunekit/core/text.hpp"

namespace tunekit::formats {

struct CsvColumn {
  std::string name;  ///< header name as written, without a bracketed unit ("flow_mm3_s", "force")
  std::string base;  ///< the name without a unit suffix as well ("flow", "force")
  std::string unit;  ///< from "name (unit)", "name [unit]" or a suffix ("mm^3/s"), empty if none
  std::vector<double> values;
};

struct CsvOptions {
  /// Columns to read, by name (case-insensitive, unit ignored). Empty: every column.
  std::vector<std::string> columns;
  /// If not empty, this column must be present and strictly increasing.
  std::string time_column;
  /// With time_column empty: find the time column by name (kTimeColumnNames, with or without a
  /// unit), refuse the file when there is none. A time column in ms or us is converted to s.
  bool find_time_column = false;
  /// The time column must strictly increase (false: records whose time restarts, e.g. per group).
  bool time_must_increase = true;
  /// Lines longer than this are refused (a file without newlines, a binary file).
  std::size_t max_line_bytes = std::size_t{1} << 20;
};

struct CsvTable {
  std::string path;                 ///< as given, used in messages
  std::vector<std::string> header;  ///< every column name in the file (units stripped)
  std::vector<CsvColumn> columns;   ///< the selected columns, in the order requested
  std::size_t rows = 0;
  std::size_t header_line = 0;  ///< 1-based line number of the header
  std::string time_column;      ///< the time column's name (given or found), empty if none
  std::vector<std::string> warnings;

  /// The selected column with this name; throws InputError naming the available columns.
  const CsvColumn& column(std::string_view name) const;
  bool has_column(std::string_view name) const;
};

/// A whole input file's bytes for the parsers, mapped when it can be (core's MappedFileBytes).
using InputFileBytes = MappedFileBytes;

/// Reads a CSV file. Throws InputError (exit code 2) for an unreadable or empty file, a
/// header without rows, ragged rows, non-numeric, NaN or infinite values, a missing column,
/// an over-long line, or a time column that does not strictly increase.
CsvTable read_csv(const std::string& path, const CsvOptions& options = {});

/// As read_csv, on text already in memory; `path` is used only in messages.
CsvTable parse_csv(std::string_view text, const std::string& path, const CsvOptions& options = {});

/// Splits "force (N)" / "force[N]" into {"force", "N"}; trims spaces.
std::pair<std::string, std::string> split_name_unit(std::string_view header_field);

/// Splits a unit written as a snake_case suffix: "flow_mm3_s" -> {"flow", "mm^3/s"},
/// "shear_rate_1_s" -> {"shear_rate", "1/s"}, "temperature_C" -> {"temperature", "degC"}.
/// Recognised (case-insensitive, longest first): _1_s, _pa_s, _mpa_s, _mm3_s, _mm_s2, _mm_s,
/// _mm, _hz, _ms, _us, _s, _n, _c, _degc, _k, _pa, _kpa, _bar. A name without one: {name, ""}.
std::pair<std::string, std::string> split_unit_suffix(std::string_view name);

/// True when `unit` is a volumetric flow in mm^3/s ("mm3/s", "mm^3/s", "mm\u00b3/s", "mm3 s-1").
bool is_volumetric_flow_unit(std::string_view unit);

/// Names a time column is found by when none is given (then also "time_s", "t (s)", ...).
inline constexpr const char* kTimeColumnNames[] = {"time", "t", "#time", "timestamp"};

/// Case-insensitive equality on ASCII (core's, used by the column matching above).
using core::iequals;

}  // namespace tunekit::formats
