#pragma once
// The data rows of a CSV file, after its header: one pass per row, only the selected fields
// parsed, no allocation per row. Internal to csv.cpp (parse_csv); the header, the column
// selection and every message's wording live there.

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace tunekit::formats::detail {

/// What every chunk of rows shares: the layout found from the header.
struct CsvRowLayout {
  const std::string* path = nullptr;                 ///< for messages
  const std::vector<std::string>* header = nullptr;  ///< every column's name, for messages
  std::vector<std::string> selected_names;           ///< the selected columns' names, for messages
  std::size_t ncols = 0;                             ///< fields each row must have
  std::vector<std::size_t> source;                   ///< the file column of each selected column
  std::vector<char> wanted_field;                    ///< per file column: parsed or skipped
  std::size_t time_index = 0;                        ///< the selected time column (>= source.size(): none)
  bool check_time = false;                           ///< time must strictly increase
  char delim = ',';
  std::size_t max_line_bytes = 0;
};

/// Rows parsed from one stretch of the file: the selected columns' values, in order.
struct CsvRows {
  std::vector<std::vector<double>> values;  ///< per selected column
  std::size_t rows = 0;
  std::size_t last_line = 0;  ///< line number of the last row (for a following chunk's messages)
};

/// Iterates over the lines of a text (a final line without '\n' included), without the '\r' of a
/// CRLF ending; a line longer than max_len is an InputError at its line number.
class LineReader {
 public:
  LineReader(std::string_view text, const std::string& path, std::size_t max_len, std::size_t first_line = 1)
      : text_(text), path_(path), max_len_(max_len), line_no_(first_line - 1) {}
  bool next(std::string_view& line);
  std::size_t line_no() const { return line_no_; }
  /// Where the next line starts (the text's size after its last line).
  std::size_t pos() const { return pos_ < text_.size() ? pos_ : text_.size(); }

 private:
  std::string_view text_;
  const std::string& path_;
  std::size_t max_len_;
  std::size_t line_no_;
  std::size_t pos_ = 0;
};

/// A number as a CSV field holds it: a plain decimal by Clinger's fast path, else
/// std::from_chars; a leading '+' allowed. False when the whole field is not one number.
bool parse_number(std::string_view s, double& v);

/// One data row (already trimmed) appended to `out`; InputError located at line_no.
void parse_csv_row(std::string_view row, std::size_t line_no, const CsvRowLayout& layout, CsvRows& out);

/// Parses every row of `text` (whole lines; blank lines and '#' comments skipped) into `out`,
/// continuing it: the time check compares with out's last time. `first_line` is the line number
/// of text's first line. Throws InputError located at FILE:LINE:COLUMN for the first bad row.
/// Returns the line number of text's last line.
std::size_t parse_csv_rows(std::string_view text, std::size_t first_line, const CsvRowLayout& layout, CsvRows& out);

/// parse_csv_rows for a large text, on two threads: the second half is parsed on its own and
/// appended when both halves are clean and the time column continues across the cut; otherwise
/// the second half is parsed again after the first, so every message is the one a single pass
/// gives (the first bad row in the file, with its line number).
void parse_csv_rows_parallel(std::string_view text, std::size_t first_line, const CsvRowLayout& layout, CsvRows& out);

}  // namespace tunekit::formats::detail
