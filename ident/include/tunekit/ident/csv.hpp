#pragma once
// Time-series CSV input. Columns are selected by name; a name may carry its unit in
// brackets or parentheses ("force (N)", "time[s]"), and matching ignores case and the unit.
// Lines starting with '#' are comments, except that a comment directly above the first
// row of numbers is taken as the header when the file has no header of its own -- this is
// how Klipper writes raw accelerometer data (`#time,accel_x,accel_y,accel_z`).
// Numbers are parsed with std::from_chars. Every problem is an InputError located as
// FILE:LINE:COLUMN (1-based), which the CLI turns into exit code 2.

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace tunekit::ident {

struct CsvColumn {
  std::string name;  ///< header name without its unit, as written
  std::string unit;  ///< unit from "name (unit)" or "name [unit]", empty if none
  std::vector<double> values;
};

struct CsvOptions {
  /// Columns to read, by name (case-insensitive, unit ignored). Empty: every column.
  std::vector<std::string> columns;
  /// If not empty, this column must be present and strictly increasing.
  std::string time_column;
  /// Lines longer than this are refused (a file without newlines, a binary file).
  std::size_t max_line_bytes = std::size_t{1} << 20;
};

struct CsvTable {
  std::string path;                       ///< as given, used in messages
  std::vector<std::string> header;        ///< every column name in the file (units stripped)
  std::vector<CsvColumn> columns;         ///< the selected columns, in the order requested
  std::size_t rows = 0;
  std::size_t header_line = 0;            ///< 1-based line number of the header
  std::vector<std::string> warnings;

  /// The selected column with this name; throws InputError naming the available columns.
  const CsvColumn& column(std::string_view name) const;
  bool has_column(std::string_view name) const;
};

/// Reads a CSV file. Throws InputError (exit code 2) for an unreadable or empty file, a
/// header without rows, ragged rows, non-numeric, NaN or infinite values, a missing column,
/// an over-long line, or a time column that does not strictly increase.
CsvTable read_csv(const std::string& path, const CsvOptions& options = {});

/// As read_csv, on text already in memory; `path` is used only in messages.
CsvTable parse_csv(std::string_view text, const std::string& path, const CsvOptions& options = {});

/// Splits "force (N)" / "force[N]" into {"force", "N"}; trims spaces.
std::pair<std::string, std::string> split_name_unit(std::string_view header_field);

/// Case-insensitive equality on ASCII.
bool iequals(std::string_view a, std::string_view b);

/// Reads a whole file into memory; InputError if it cannot be opened or read.
std::string read_file_bytes(const std::string& path);

}  // namespace tunekit::ident
