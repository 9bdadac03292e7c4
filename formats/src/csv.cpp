#include "tunekit/formats/csv.hpp"

#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <tuple>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/core/file_bytes.hpp"
#include "tunekit/core/huge_pages.hpp"

#include "csv_rows.hpp"

namespace tunekit::formats {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

char detect_delimiter(std::string_view header) {
  if (header.find(',') != std::string_view::npos) return ',';
  if (header.find('\t') != std::string_view::npos) return '\t';
  if (header.find(';') != std::string_view::npos) return ';';
  return ',';
}

struct Field {
  std::string_view text;  // trimmed
  std::size_t column;     // 1-based byte column of the field's first character
};

// Splits a line into fields; `out` is reused between calls.
void split(std::string_view line, char delim, std::vector<Field>& out) {
  out.clear();
  std::size_t start = 0;
  while (true) {
    const std::size_t end = line.find(delim, start);
    const std::string_view raw =
        line.substr(start, end == std::string_view::npos ? std::string_view::npos : end - start);
    std::size_t lead = 0;
    while (lead < raw.size() && (raw[lead] == ' ' || raw[lead] == '\t')) ++lead;
    out.push_back({trim(raw), start + lead + 1});
    if (end == std::string_view::npos) break;
    start = end + 1;
  }
}

using detail::LineReader;
using detail::parse_number;

bool all_numeric(const std::vector<Field>& fields) {
  double v;
  for (const auto& f : fields)
    if (!parse_number(f.text, v)) return false;
  return !fields.empty();
}

std::string join_names(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) {
    if (!s.empty()) s += ", ";
    s += n;
  }
  return s;
}

/// UTF-16 text with a byte-order mark (FF FE little-endian, FE FF big-endian) as UTF-8;
/// InputError for an odd length or an unpaired surrogate.
std::string csv_utf16_to_utf8(std::string_view bytes, const std::string& path) {
  const bool little = bytes[0] == '\xFF';
  if (bytes.size() % 2 != 0)
    throw InputError("the file starts with a UTF-16 byte-order mark but has an odd number of bytes", path);
  auto unit = [&](std::size_t i) {
    const auto a = static_cast<unsigned char>(bytes[i]), b = static_cast<unsigned char>(bytes[i + 1]);
    return little ? static_cast<unsigned>(a | (b << 8)) : static_cast<unsigned>((a << 8) | b);
  };
  std::string out;
  out.reserve(bytes.size() / 2);
  std::size_t line = 1;
  for (std::size_t i = 2; i + 1 < bytes.size(); i += 2) {
    unsigned cp = unit(i);
    if (cp >= 0xD800 && cp <= 0xDBFF && i + 3 < bytes.size() && unit(i + 2) >= 0xDC00 && unit(i + 2) <= 0xDFFF) {
      cp = 0x10000 + ((cp - 0xD800) << 10) + (unit(i + 2) - 0xDC00);
      i += 2;
    } else if (cp >= 0xD800 && cp <= 0xDFFF) {
      throw InputError("invalid UTF-16 text (an unpaired surrogate)", source_location(path, line));
    }
    if (cp == '\n') ++line;
    if (cp < 0x80) {
      out.push_back(static_cast<char>(cp));
    } else if (cp < 0x800) {
      out.push_back(static_cast<char>(0xC0 | (cp >> 6)));
      out.push_back(static_cast<char>(0x80 | (cp & 0x3F)));
    } else if (cp < 0x10000) {
      out.push_back(static_cast<char>(0xE0 | (cp >> 12)));
      out.push_back(static_cast<char>(0x80 | ((cp >> 6) & 0x3F)));
      out.push_back(static_cast<char>(0x80 | (cp & 0x3F)));
    } else {
      out.push_back(static_cast<char>(0xF0 | (cp >> 18)));
      out.push_back(static_cast<char>(0x80 | ((cp >> 12) & 0x3F)));
      out.push_back(static_cast<char>(0x80 | ((cp >> 6) & 0x3F)));
      out.push_back(static_cast<char>(0x80 | (cp & 0x3F)));
    }
  }
  return out;
}

}  // namespace

std::pair<std::string, std::string> split_name_unit(std::string_view f) {
  f = trim(f);
  if (!f.empty() && (f.back() == ')' || f.back() == ']')) {
    const char open = f.back() == ')' ? '(' : '[';
    const std::size_t p = f.rfind(open);
    if (p != std::string_view::npos && p > 0)
      return {std::string(trim(f.substr(0, p))), std::string(trim(f.substr(p + 1, f.size() - p - 2)))};
  }
  return {std::string(f), {}};
}

namespace {

struct UnitSuffix {
  std::string_view suffix;  // lower case, with the leading '_'
  std::string_view unit;    // canonical spelling
};

// Longest first, so "_pa_s" wins over "_s" and "_mm3_s" over "_s".
constexpr UnitSuffix kUnitSuffixes[] = {
    {"_mm3_s", "mm^3/s"}, {"_mpa_s", "mPa.s"}, {"_mm_s2", "mm/s^2"}, {"_pa_s", "Pa.s"}, {"_mm_s", "mm/s"},
    {"_degc", "degC"},    {"_1_s", "1/s"},     {"_kpa", "kPa"},      {"_bar", "bar"},   {"_mm", "mm"},
    {"_hz", "Hz"},        {"_ms", "ms"},       {"_us", "us"},        {"_pa", "Pa"},     {"_s", "s"},
    {"_n", "N"},          {"_c", "degC"},      {"_k", "K"},
};

bool iends_with(std::string_view s, std::string_view suffix) {
  return s.size() >= suffix.size() && iequals(s.substr(s.size() - suffix.size()), suffix);
}

// A header column matches a requested name by its name as written, else by its base name.
// Returns the index, or `names.size()` when none matches.
// A requested name with a unit suffix ("force_N") also finds the same name with that unit in
// brackets ("force [N]").
template <class Label, class Base, class Unit>
std::size_t match_column(std::size_t n, Label label, Base base, Unit unit, std::string_view wanted) {
  const std::string wname = split_name_unit(wanted).first;
  for (std::size_t i = 0; i < n; ++i)
    if (iequals(label(i), wname)) return i;
  for (std::size_t i = 0; i < n; ++i)
    if (iequals(base(i), wname)) return i;
  const auto [wbase, wunit] = split_unit_suffix(wname);
  if (!wunit.empty())
    for (std::size_t i = 0; i < n; ++i)
      if (iequals(base(i), wbase) && iequals(unit(i), wunit)) return i;
  return n;
}

}  // namespace

std::pair<std::string, std::string> split_unit_suffix(std::string_view name) {
  name = trim(name);
  for (const auto& s : kUnitSuffixes) {
    if (!iends_with(name, s.suffix) || name.size() == s.suffix.size()) continue;
    const std::string_view base = name.substr(0, name.size() - s.suffix.size());
    if (base.back() == '_') continue;
    return {std::string(base), std::string(s.unit)};
  }
  return {std::string(name), {}};
}

bool is_volumetric_flow_unit(std::string_view unit) {
  std::string u;
  for (char c : unit)
    if (c != ' ' && c != '^') u.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
  return u == "mm3/s" || u == "mm\xc2\xb3/s" || u == "mm3s-1" || u == "mm3*s-1" || u == "mm3.s-1";
}

const CsvColumn& CsvTable::column(std::string_view name) const {
  const std::size_t i = match_column(
      columns.size(), [&](std::size_t k) -> const std::string& { return columns[k].name; },
      [&](std::size_t k) -> const std::string& { return columns[k].base; },
      [&](std::size_t k) -> const std::string& { return columns[k].unit; }, name);
  if (i < columns.size()) return columns[i];
  throw InputError(fmt::format("no column '{}'; the file has: {}", name, join_names(header)),
                   source_location(path, header_line));
}

bool CsvTable::has_column(std::string_view name) const {
  return match_column(
             columns.size(), [&](std::size_t k) -> const std::string& { return columns[k].name; },
             [&](std::size_t k) -> const std::string& { return columns[k].base; },
             [&](std::size_t k) -> const std::string& { return columns[k].unit; }, name) < columns.size();
}

CsvTable read_csv(const std::string& path, const CsvOptions& options) {
  const InputFileBytes data(path);
  return parse_csv(data.view(), path, options);
}

namespace {

// The header row: its fields, the delimiter, and the first data row when the header was the
// comment right above the data (Klipper style; empty otherwise) with its line number.
struct HeaderRow {
  std::vector<Field> fields;
  char delim = ',';
  std::string_view pending_first_row;
  std::size_t pending_line = 0;
};

// Reads up to the header row (blank lines and comments before it skipped); its line number
// into t.header_line. InputError when there is none or the first row holds numbers without a
// comment above it.
HeaderRow read_header_row(LineReader& lines, const std::string& path, CsvTable& t) {
  HeaderRow h;
  std::string_view line;
  std::string_view last_comment;
  std::size_t last_comment_line = 0;
  while (lines.next(line)) {
    const std::string_view tl = trim(line);
    if (tl.empty()) continue;
    if (tl.front() == '#') {
      last_comment = tl.substr(1);
      last_comment_line = lines.line_no();
      continue;
    }
    h.delim = detect_delimiter(tl);
    split(tl, h.delim, h.fields);
    if (all_numeric(h.fields)) {
      if (last_comment_line == 0)
        throw InputError("the first row holds numbers, not column names; add a header row (e.g. 'time (s),force (N)')",
                         source_location(path, lines.line_no()));
      // Klipper style: the header is the comment right above the data.
      h.delim = detect_delimiter(last_comment);
      split(trim(last_comment), h.delim, h.fields);
      t.header_line = last_comment_line;
      h.pending_first_row = tl;
      h.pending_line = lines.line_no();
    } else {
      t.header_line = lines.line_no();
    }
    return h;
  }
  throw InputError("no header row and no data (only comments or blank lines)", path);
}

// A header column's name as written, its name without the unit, and the unit.
struct HeaderName {
  std::string label, base, unit;
};

std::vector<HeaderName> header_names(const std::vector<Field>& fields) {
  std::vector<HeaderName> header;
  for (const auto& f : fields) {
    auto [label, unit] = split_name_unit(f.text);
    std::string base = label;
    if (unit.empty()) std::tie(base, unit) = split_unit_suffix(label);
    header.push_back({label, base, unit});
  }
  return header;
}

// The index of the header column `name` matches (match_column), or header.size().
std::size_t find_in_header(const std::vector<HeaderName>& header, std::string_view name) {
  return match_column(
      header.size(), [&](std::size_t i) -> const std::string& { return header[i].label; },
      [&](std::size_t i) -> const std::string& { return header[i].base; },
      [&](std::size_t i) -> const std::string& { return header[i].unit; }, name);
}

// The time column's index: given, or found by its usual names (header.size() when not looked
// for). InputError when the given one or, looked for, none is found.
std::size_t find_time_column(const std::vector<HeaderName>& header, const CsvOptions& options, const CsvTable& t) {
  const std::size_t ncols = header.size();
  std::size_t time_source = ncols;
  if (!options.time_column.empty()) {
    time_source = find_in_header(header, options.time_column);
    if (time_source == ncols)
      throw InputError(fmt::format("no column '{}'; the file has: {}", split_name_unit(options.time_column).first,
                                   join_names(t.header)),
                       source_location(t.path, t.header_line));
  } else if (options.find_time_column) {
    for (const char* candidate : kTimeColumnNames) {
      time_source = find_in_header(header, candidate);
      if (time_source != ncols) break;
    }
    if (time_source == ncols)
      throw InputError(fmt::format("no time column (looked for time, t, timestamp, with or without a unit such as "
                                   "time_s); name it with --time; the file has: {}",
                                   join_names(t.header)),
                       source_location(t.path, t.header_line));
  }
  return time_source;
}

// Which file column feeds each requested column (the time column first when it was not
// requested) into `source`, the columns into t.columns. Returns the time column's index among
// them (t.columns.size() when there is none).
std::size_t select_columns(const std::vector<HeaderName>& header, const CsvOptions& options, std::size_t time_source,
                           CsvTable& t, std::vector<std::size_t>& source) {
  const std::size_t ncols = header.size();
  std::vector<std::string> wanted = options.columns;
  if (wanted.empty()) wanted = t.header;
  std::size_t time_index = ncols;
  for (const auto& w : wanted) {
    const std::size_t found = find_in_header(header, w);
    if (found == ncols)
      throw InputError(fmt::format("no column '{}'; the file has: {}", split_name_unit(w).first, join_names(t.header)),
                       source_location(t.path, t.header_line));
    if (found == time_source) time_index = source.size();
    source.push_back(found);
    t.columns.push_back({header[found].label, header[found].base, header[found].unit, {}});
  }
  if (time_source != ncols && time_index == ncols) {
    time_index = 0;
    source.insert(source.begin(), time_source);
    t.columns.insert(t.columns.begin(),
                     {header[time_source].label, header[time_source].base, header[time_source].unit, {}});
  }
  if (time_index == ncols) time_index = t.columns.size();
  return time_index;
}

detail::CsvRowLayout row_layout(const CsvTable& t, std::size_t ncols, const std::vector<std::size_t>& source,
                                std::size_t time_index, const CsvOptions& options, char delim) {
  detail::CsvRowLayout layout;
  layout.path = &t.path;
  layout.header = &t.header;
  for (const auto& c : t.columns) layout.selected_names.push_back(c.name);
  layout.ncols = ncols;
  layout.source = source;
  layout.wanted_field.assign(ncols, 0);
  for (std::size_t src : source) layout.wanted_field[src] = 1;
  layout.time_index = time_index;
  layout.check_time = options.time_must_increase;
  layout.delim = delim;
  layout.max_line_bytes = options.max_line_bytes;
  return layout;
}

// Time is in seconds everywhere else: a time column logged in ms or us is converted.
void time_in_seconds(CsvTable& t, std::size_t time_index) {
  if (time_index >= t.columns.size()) return;
  auto& tc = t.columns[time_index];
  const double scale = iequals(tc.unit, "ms") ? 1e-3 : (iequals(tc.unit, "us") ? 1e-6 : 1.0);
  if (scale != 1.0) {
    for (double& v : tc.values) v *= scale;
    tc.unit = "s";
  }
}

}  // namespace

CsvTable parse_csv(std::string_view text, const std::string& path, const CsvOptions& options) {
  CsvTable t;
  t.path = path;
  // Byte-order marks: UTF-16 text is decoded to UTF-8 first; any number of UTF-8 marks
  // (editors that add one to a file that had one already) are dropped.
  if (text.size() >= 2 && ((text[0] == '\xFF' && text[1] == '\xFE') || (text[0] == '\xFE' && text[1] == '\xFF'))) {
    if (text.size() >= 4 && text[0] == '\xFF' && text[2] == '\0' && text[3] == '\0')
      throw InputError("the file is UTF-32 text (byte-order mark FF FE 00 00); save it as UTF-8",
                       source_location(path, 1));
    return parse_csv(csv_utf16_to_utf8(text, path), path, options);
  }
  while (text.size() >= 3 && std::memcmp(text.data(), "\xEF\xBB\xBF", 3) == 0) text.remove_prefix(3);
  if (trim(text).empty() || text.find_first_not_of(" \t\r\n") == std::string_view::npos)
    throw InputError("empty file: no header and no data", path);

  LineReader lines(text, path, options.max_line_bytes);
  const HeaderRow h = read_header_row(lines, path, t);
  const std::vector<HeaderName> header = header_names(h.fields);
  for (const auto& name : header) t.header.push_back(name.label);
  const std::size_t ncols = header.size();
  const std::size_t time_source = find_time_column(header, options, t);
  if (time_source != ncols) t.time_column = header[time_source].label;
  std::vector<std::size_t> source;
  const std::size_t time_index = select_columns(header, options, time_source, t, source);
  const detail::CsvRowLayout layout = row_layout(t, ncols, source, time_index, options, h.delim);

  detail::CsvRows rows;
  rows.values.resize(t.columns.size());
  const std::size_t estimate = text.size() / std::max<std::size_t>(16, ncols * 8);
  for (auto& v : rows.values) {
    v.reserve(estimate);
    core::advise_huge_pages(v.data(), v.capacity() * sizeof(double));
  }
  if (!h.pending_first_row.empty()) detail::parse_csv_row(h.pending_first_row, h.pending_line, layout, rows);
  detail::parse_csv_rows_parallel(text.substr(lines.pos()), lines.line_no() + 1, layout, rows);
  for (std::size_t k = 0; k < t.columns.size(); ++k) t.columns[k].values = std::move(rows.values[k]);
  t.rows = rows.rows;
  if (t.rows == 0) throw InputError("a header but no data rows", source_location(path, t.header_line));
  time_in_seconds(t, time_index);
  return t;
}

}  // namespace tunekit::formats
