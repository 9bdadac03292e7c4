#include "csv_rows.hpp"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <exception>
#include <latch>
#include <thread>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/core/huge_pages.hpp"

namespace tunekit::formats::detail {
namespace {

// Exact powers of ten representable in a double.
constexpr double kPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                             1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

// Clinger's fast path for plain decimals such as "-1234.567890" (what loggers write): the
// digits form an integer M < 10^15 < 2^53 and the value is M / 10^k with k <= 15; both are
// exact doubles, so one IEEE division gives the correctly rounded result. Parses from p up to
// the first character that is not part of such a number; returns that position, or nullptr
// when there were no digits or more than 15.
[[gnu::always_inline]] inline const char* plain_decimal_prefix(const char* p, const char* end, double& v) {
  const bool neg = p != end && *p == '-';
  if (neg) ++p;
  std::uint64_t m = 0;
  int digits = 0, frac_digits = 0;
  for (; p != end && static_cast<unsigned>(*p - '0') <= 9; ++p, ++digits) m = m * 10 + static_cast<unsigned>(*p - '0');
  if (p != end && *p == '.')
    for (++p; p != end && static_cast<unsigned>(*p - '0') <= 9; ++p, ++digits, ++frac_digits)
      m = m * 10 + static_cast<unsigned>(*p - '0');
  if (digits == 0 || digits > 15) return nullptr;
  v = static_cast<double>(m) / kPow10[frac_digits];
  if (neg) v = -v;
  return p;
}

// Rows below this size are parsed on one thread: starting a second costs more than it saves.
constexpr std::size_t kParallelMinBytes = std::size_t{4} << 20;

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

// The general path for one field (spaces, exponents, text): every error located.
double parse_field(const char* p, const char* q, const char* row_begin, std::size_t nf, std::size_t line_no,
                   const CsvRowLayout& layout, std::size_t& col) {
  const char* b = p;
  while (b < q && (*b == ' ' || *b == '\t')) ++b;
  const char* e = q;
  while (e > b && (e[-1] == ' ' || e[-1] == '\t')) --e;
  const std::string_view text(b, static_cast<std::size_t>(e - b));
  col = static_cast<std::size_t>(b - row_begin) + 1;
  const std::string& name = (*layout.header)[nf];
  const std::string& path = *layout.path;
  double v;
  if (text.empty())
    throw InputError(fmt::format("empty field in column '{}'", name), source_location(path, line_no, col));
  if (!parse_number(text, v))
    throw InputError(fmt::format("'{}' in column '{}' is not a number", text.substr(0, 40), name),
                     source_location(path, line_no, col));
  if (std::isnan(v)) throw InputError(fmt::format("NaN in column '{}'", name), source_location(path, line_no, col));
  if (std::isinf(v))
    throw InputError(fmt::format("infinite value in column '{}'", name), source_location(path, line_no, col));
  return v;
}

void check_time_step(double v, double prev, std::size_t k, std::size_t line_no, std::size_t col,
                     const CsvRowLayout& layout, std::size_t prev_line) {
  const std::string& name = layout.selected_names[k];
  if (v == prev)
    throw InputError(fmt::format("duplicate time stamp {} in column '{}' (also on line {})", v, name, prev_line),
                     source_location(*layout.path, line_no, col));
  if (v < prev)
    throw InputError(fmt::format("time goes backwards in column '{}': {} after {} (line {})", name, v, prev, prev_line),
                     source_location(*layout.path, line_no, col));
}

// The fast row path: fields of at most 15 digits, a sign and a point (17 bytes) and their
// delimiter; at most this many columns, so that a row's values fit on the stack.
constexpr std::size_t kMaxFastFieldBytes = 18;
constexpr std::size_t kMaxFastColumns = 32;

// One row of plain decimals starting at text[pos], ending in "\n" or "\r\n": appended to `out`
// (with the time check) and the position after it returned; anything else returns pos with
// nothing appended. At least ncols * kMaxFastFieldBytes + 2 bytes must follow pos.
std::size_t parse_plain_row(std::string_view text, std::size_t pos, std::size_t line_no, const CsvRowLayout& layout,
                            CsvRows& out) {
  double values[kMaxFastColumns];
  const char* p = text.data() + pos;
  const char* const end = text.data() + text.size();
  for (std::size_t f = 0; f < layout.ncols; ++f) {
    const char* q = plain_decimal_prefix(p, end, values[f]);
    if (q == nullptr) return pos;
    const char want = f + 1 < layout.ncols ? layout.delim : '\n';
    if (*q == '\r' && want == '\n') ++q;
    if (*q != want) return pos;
    p = q + 1;
  }
  const std::size_t t = layout.time_index;
  if (layout.check_time && t < layout.source.size() && !out.values[t].empty() &&
      !(values[layout.source[t]] > out.values[t].back()))
    return pos;  // the line reader's path names the problem
  for (std::size_t k = 0; k < layout.source.size(); ++k) out.values[k].push_back(values[layout.source[k]]);
  out.last_line = line_no;
  ++out.rows;
  return static_cast<std::size_t>(p - text.data());
}

}  // namespace

bool LineReader::next(std::string_view& line) {
  if (pos_ >= text_.size()) return false;
  ++line_no_;
  const char* begin = text_.data() + pos_;
  const void* nl = std::memchr(begin, '\n', text_.size() - pos_);
  const std::size_t len = nl ? static_cast<std::size_t>(static_cast<const char*>(nl) - begin) : text_.size() - pos_;
  if (len > max_len_)
    throw InputError(
        fmt::format("line is {} bytes long, more than the {} allowed (a file without line breaks, or not a CSV file?)",
                    len, max_len_),
        source_location(path_, line_no_));
  line = std::string_view(begin, len);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  pos_ += len + 1;
  return true;
}

bool parse_number(std::string_view s, double& v) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty()) return false;
  const char* end = s.data() + s.size();
  if (plain_decimal_prefix(s.data(), end, v) == end) return true;
  const auto [ptr, ec] = std::from_chars(s.data(), end, v);
  return ec == std::errc() && ptr == end;
}

void parse_csv_row(std::string_view row, std::size_t line_no, const CsvRowLayout& layout, CsvRows& out) {
  // Row values and the byte column of each (for the time check's message), per file column.
  thread_local std::vector<double> row_values;
  thread_local std::vector<std::size_t> row_columns;
  row_values.resize(layout.ncols);
  row_columns.resize(layout.ncols);
  const char* const row_begin = row.data();
  const char* p = row_begin;
  const char* const end = p + row.size();
  std::size_t nf = 0;
  while (true) {
    if (nf < layout.ncols && layout.wanted_field[nf]) {
      // Fast path: a plain decimal ending exactly at the delimiter or the end of the row.
      double v;
      const char* r = plain_decimal_prefix(p, end, v);
      if (r != nullptr && (r == end || *r == layout.delim)) {
        row_values[nf] = v;
        row_columns[nf] = static_cast<std::size_t>(p - row_begin) + 1;
        ++nf;
        if (r == end) break;
        p = r + 1;
        continue;
      }
    }
    const char* q = static_cast<const char*>(std::memchr(p, layout.delim, static_cast<std::size_t>(end - p)));
    if (q == nullptr) q = end;
    if (nf < layout.ncols && layout.wanted_field[nf])
      row_values[nf] = parse_field(p, q, row_begin, nf, line_no, layout, row_columns[nf]);
    ++nf;
    if (q == end) break;
    p = q + 1;
  }
  if (nf != layout.ncols)
    throw InputError(fmt::format("{} fields, but the header has {} columns", nf, layout.ncols),
                     source_location(*layout.path, line_no));
  for (std::size_t k = 0; k < layout.source.size(); ++k) {
    const double v = row_values[layout.source[k]];
    auto& vals = out.values[k];
    if (k == layout.time_index && layout.check_time && !vals.empty())
      check_time_step(v, vals.back(), k, line_no, row_columns[layout.source[k]], layout, out.last_line);
    vals.push_back(v);
  }
  out.last_line = line_no;
  ++out.rows;
}

std::size_t parse_csv_rows(std::string_view text, std::size_t first_line, const CsvRowLayout& layout, CsvRows& out) {
  const std::size_t fast_row_bytes = layout.ncols * kMaxFastFieldBytes + 2;
  const bool fast = layout.ncols <= kMaxFastColumns && layout.max_line_bytes >= fast_row_bytes;
  std::size_t pos = 0, line_no = first_line - 1;
  while (pos < text.size()) {
    // Rows of plain decimals end to end, without a separate search for each line's end; the
    // first row that is anything else (and the last rows of the text) goes through the line
    // reader below.
    if (fast && text.size() - pos >= fast_row_bytes) {
      const std::size_t next = parse_plain_row(text, pos, line_no + 1, layout, out);
      if (next != pos) {
        pos = next;
        ++line_no;
        continue;
      }
    }
    LineReader lines(text.substr(pos), *layout.path, layout.max_line_bytes, line_no + 1);
    std::string_view line;
    if (!lines.next(line)) break;
    pos += lines.pos();
    line_no = lines.line_no();
    if (!line.empty() && line.front() != ' ' && line.front() != '\t' && line.front() != '#') {
      parse_csv_row(line, line_no, layout, out);
      continue;
    }
    const std::string_view tl = trim(line);
    if (tl.empty() || tl.front() == '#') continue;
    parse_csv_row(tl, line_no, layout, out);
  }
  return line_no;
}

void parse_csv_rows_parallel(std::string_view text, std::size_t first_line, const CsvRowLayout& layout, CsvRows& out) {
  const std::size_t nl = text.size() < kParallelMinBytes ? std::string_view::npos : text.find('\n', text.size() / 2);
  if (nl == std::string_view::npos || std::thread::hardware_concurrency() < 2) {
    parse_csv_rows(text, first_line, layout, out);
    return;
  }
  const std::string_view first = text.substr(0, nl + 1), second = text.substr(nl + 1);
  CsvRows tail;
  tail.values.resize(out.values.size());
  for (auto& v : tail.values) {
    v.reserve(second.size() / std::max<std::size_t>(16, layout.ncols * 8));
    core::advise_huge_pages(v.data(), v.capacity() * sizeof(double));
  }
  // The first thread decides, once both halves are parsed, whether the second joins the first
  // (it parsed cleanly and the time column continues across the cut); if so each thread then
  // appends half of the columns, into memory the first half's columns reserved.
  bool tail_clean = false, joined = false;
  std::size_t first_end = 0;
  std::latch parsed(1), decided(1);
  const std::size_t t = layout.time_index, half = out.values.size() / 2;
  auto append = [&](std::size_t from, std::size_t to) {
    for (std::size_t k = from; k < to; ++k)
      out.values[k].insert(out.values[k].end(), tail.values[k].begin(), tail.values[k].end());
  };
  {
    // The second half's messages would carry line numbers counted from the cut: they are never
    // shown. Any problem there makes the second half be parsed again below, after the first.
    std::jthread worker([&] {
      try {
        parse_csv_rows(second, 1, layout, tail);
        tail_clean = true;
      } catch (...) {
      }
      parsed.count_down();
      decided.wait();
      if (joined) append(half, out.values.size());
    });
    try {
      first_end = parse_csv_rows(first, first_line, layout, out);
    } catch (...) {
      decided.count_down();  // joined stays false: the worker appends nothing
      throw;
    }
    parsed.wait();
    joined = tail_clean && (!layout.check_time || t >= out.values.size() || tail.rows == 0 || out.rows == 0 ||
                            tail.values[t].front() > out.values[t].back());
    decided.count_down();
    if (joined) append(0, half);
  }
  if (!joined) {
    parse_csv_rows(second, first_end + 1, layout, out);
    return;
  }
  if (tail.rows > 0) out.last_line = first_end + tail.last_line;
  out.rows += tail.rows;
}

}  // namespace tunekit::formats::detail
