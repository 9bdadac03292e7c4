// The time-series CSV reader: every malformed input gives exit code 2 and one line naming
// file, line (and column where there is one) and the problem.
#include <catch2/catch.hpp>

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

#include <fmt/format.h>

#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/formats/csv.hpp"

using tunekit::test::run_cli;
using tunekit::test::write_scratch;

namespace {

// Runs `tunekit inspect FILE --time time` and checks code and the single error line.
void expect_rejected(const std::string& name, const std::string& content, const std::string& location_suffix,
                     const std::string& problem) {
  const std::string path = write_scratch(name, content);
  const auto r = run_cli({"inspect", path, "--time", "time"});
  INFO("stderr: " << r.err);
  CHECK(r.code == 2);
  CHECK(r.err == "tunekit: error: " + path + location_suffix + ": " + problem + "\n");
}

}  // namespace

TEST_CASE("a well-formed CSV with units in names is read by column name") {
  const auto t = tunekit::formats::parse_csv("# a log\ntime (s),force [N], speed\n0,1.5,2\n0.1,+2.5,3e-1\n", "mem.csv",
                                             {{"Force", "time"}, "time"});
  REQUIRE(t.rows == 2);
  REQUIRE(t.columns.size() == 2);
  CHECK(t.column("force").unit == "N");
  CHECK(t.column("time").unit == "s");
  CHECK(t.column("force").values[1] == 2.5);
  CHECK(t.header == std::vector<std::string>{"time", "force", "speed"});
  CHECK(t.header_line == 2);
}

TEST_CASE("Klipper raw accelerometer files take their header from the comment line") {
  const auto t = tunekit::formats::parse_csv("#time,accel_x,accel_y,accel_z\n100.0,1,2,3\n100.0003125,4,5,6\n",
                                             "raw.csv", {{"accel_x", "accel_z"}, "time"});
  CHECK(t.rows == 2);
  CHECK(t.column("accel_z").values == std::vector<double>{3, 6});
  CHECK(t.column("time").values[1] == Approx(100.0003125));
}

TEST_CASE("CRLF line endings and a UTF-8 byte-order mark are accepted") {
  const auto path = write_scratch("crlf_bom.csv", "\xEF\xBB\xBFtime,y\r\n0,1\r\n1,2\r\n");
  const auto r = run_cli({"inspect", path, "--time", "time", "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.out.find("\"rows\": 2") != std::string::npos);
  CHECK(r.out.find("\"header\": [\n      \"time\",\n      \"y\"") != std::string::npos);
}

TEST_CASE("a one-column file is read, and a missing second column is named") {
  const auto path = write_scratch("one_col.csv", "time\n0\n1\n2\n");
  CHECK(run_cli({"inspect", path, "--time", "time"}).code == 0);
  const auto r = run_cli({"inspect", path, "--time", "time", "--columns", "force"});
  CHECK(r.code == 2);
  CHECK(r.err == "tunekit: error: " + path + ":1: no column 'force'; the file has: time\n");
}

TEST_CASE("malformed CSV inputs are refused with file, line, column and reason") {
  expect_rejected("empty.csv", "", "", "empty file: no header and no data");
  expect_rejected("blank.csv", "\n\n  \n", "", "empty file: no header and no data");
  expect_rejected("header_only.csv", "time,y\n", ":1", "a header but no data rows");
  expect_rejected("ragged.csv", "time,y\n0,1\n1,2,3\n", ":3", "3 fields, but the header has 2 columns");
  expect_rejected("text.csv", "time,y\n0,1\n1,abc\n", ":3:3", "'abc' in column 'y' is not a number");
  expect_rejected("nan.csv", "time,y\n0,1\n1,NaN\n", ":3:3", "NaN in column 'y'");
  expect_rejected("inf.csv", "time,y\n0,1\n1,-inf\n", ":3:3", "infinite value in column 'y'");
  expect_rejected("backwards.csv", "time,y\n0,1\n2,2\n1,3\n", ":4:1",
                  "time goes backwards in column 'time': 1 after 2 (line 3)");
  expect_rejected("duplicate.csv", "time,y\n0,1\n1,2\n1,3\n", ":4:1",
                  "duplicate time stamp 1 in column 'time' (also on line 3)");
  expect_rejected("empty_field.csv", "time,y\n0,\n", ":2:3", "empty field in column 'y'");
  expect_rejected("numbers_first.csv", "0,1\n1,2\n", ":1",
                  "the first row holds numbers, not column names; add a header row (e.g. 'time (s),force (N)')");
}

TEST_CASE("a field or a column name with control bytes or broken UTF-8 is quoted escaped, UTF-8 kept") {
  // An escape sequence in a file must not drive the terminal the error is printed on, and a
  // byte that is not UTF-8 must not reach a JSON document; a degree sign stays a degree sign.
  expect_rejected("control.csv", "time,y\n0,1\n1,\x1b[31mred\x01\n", ":3:3",
                  "'\\x1b[31mred\\x01' in column 'y' is not a number");
  expect_rejected("latin1.csv",
                  "time,y\n0,1\n1,5\xb0"
                  "C\xe2\x82\n",
                  ":3:3", "'5\\xb0C\\xe2\\x82' in column 'y' is not a number");
  expect_rejected("utf8.csv",
                  "time,y\n0,1\n1,5\xc2\xb0"
                  "C\n",
                  ":3:3",
                  "'5\xc2\xb0"
                  "C' in column 'y' is not a number");
  const auto path = write_scratch("name_bytes.csv", "time,y\xff\n0,1\n");
  const auto r = run_cli({"inspect", path, "--time", "time", "--columns", "y"});
  CHECK(r.code == 2);
  CHECK(r.err == "tunekit: error: " + path + ":1: no column 'y'; the file has: time, y\\xff\n");
}

TEST_CASE("an error's text is printable: control bytes, overlong forms and surrogates become \\xNN") {
  using tunekit::printable_message;
  CHECK(printable_message("line one\n\tline two") == "line one\n\tline two");
  CHECK(printable_message("a\rb\x7f") == "a\\x0db\\x7f");
  CHECK(printable_message("\xc0\xaf") == "\\xc0\\xaf");                    // an overlong '/'
  CHECK(printable_message("\xed\xa0\x80") == "\\xed\\xa0\\x80");           // a UTF-16 surrogate
  CHECK(printable_message("\xf4\x90\x80\x80") == "\\xf4\\x90\\x80\\x80");  // above U+10FFFF
  CHECK(printable_message("\xf0\x9f\x94\xa5 \xe2\x82\xac \xc3\xa9") == "\xf0\x9f\x94\xa5 \xe2\x82\xac \xc3\xa9");
  const tunekit::InputError e("bad \x1b", "f\x07.csv:1");
  CHECK(e.formatted() == "tunekit: error: f\\x07.csv:1: bad \\x1b");
  CHECK(std::string(e.what()) == "f\\x07.csv:1: bad \\x1b");
}

TEST_CASE("a 10 MB line without a newline is refused without reading it as data") {
  const std::string huge(10u << 20, '7');
  expect_rejected(
      "huge_line.csv", huge, ":1",
      "line is 10485760 bytes long, more than the 1048576 allowed (a file without line breaks, or not a CSV file?)");
}

TEST_CASE("a file that does not exist is an input error") {
  const auto r = run_cli({"inspect", "/nonexistent/dir/log.csv"});
  CHECK(r.code == 2);
  CHECK(r.err.find("tunekit: error: /nonexistent/dir/log.csv") == 0);
}

TEST_CASE("the reader throws InputError with the location for library users") {
  try {
    tunekit::formats::parse_csv("t,y\n0,1\n1,x\n", "lib.csv", {{"y"}, "t"});
    FAIL("no exception");
  } catch (const tunekit::InputError& e) {
    CHECK(e.code() == tunekit::ExitCode::bad_input);
    CHECK(e.location() == "lib.csv:3:3");
  }
}

TEST_CASE("unit suffixes in snake_case names are read as units, and the column is found with or without them") {
  using tunekit::formats::split_unit_suffix;
  CHECK(split_unit_suffix("flow_mm3_s") == std::pair<std::string, std::string>{"flow", "mm^3/s"});
  CHECK(split_unit_suffix("shear_rate_1_s") == std::pair<std::string, std::string>{"shear_rate", "1/s"});
  CHECK(split_unit_suffix("viscosity_Pa_s") == std::pair<std::string, std::string>{"viscosity", "Pa.s"});
  CHECK(split_unit_suffix("temperature_C") == std::pair<std::string, std::string>{"temperature", "degC"});
  CHECK(split_unit_suffix("force_N") == std::pair<std::string, std::string>{"force", "N"});
  CHECK(split_unit_suffix("speed_mm_s") == std::pair<std::string, std::string>{"speed", "mm/s"});
  CHECK(split_unit_suffix("T_K") == std::pair<std::string, std::string>{"T", "K"});
  CHECK(split_unit_suffix("f_hz") == std::pair<std::string, std::string>{"f", "Hz"});
  CHECK(split_unit_suffix("accel_x") == std::pair<std::string, std::string>{"accel_x", ""});
  CHECK(split_unit_suffix("_s") == std::pair<std::string, std::string>{"_s", ""});
  CHECK(split_unit_suffix("flow") == std::pair<std::string, std::string>{"flow", ""});
  CHECK(tunekit::formats::is_volumetric_flow_unit("mm3/s"));
  CHECK(tunekit::formats::is_volumetric_flow_unit("mm^3/s"));
  CHECK(tunekit::formats::is_volumetric_flow_unit("mm\xc2\xb3/s"));
  CHECK_FALSE(tunekit::formats::is_volumetric_flow_unit("mm/s"));

  const auto t = tunekit::formats::parse_csv("time_ms,flow_mm3_s,force [N],shear_rate_1_s\n0,1,2,3\n10,4,5,6\n",
                                             "mem.csv", {{"flow", "force_N", "shear_rate_1_s"}, "", true});
  CHECK(t.time_column == "time_ms");
  CHECK(t.header == std::vector<std::string>{"time_ms", "flow_mm3_s", "force", "shear_rate_1_s"});
  CHECK(t.column("flow").unit == "mm^3/s");
  CHECK(t.column("flow_mm3_s").values == std::vector<double>{1, 4});
  CHECK(t.column("force").unit == "N");
  CHECK(t.column("shear_rate").unit == "1/s");
  // The time column, found by name, is converted from ms to s.
  CHECK(t.column("time").unit == "s");
  CHECK(t.column("time").values == std::vector<double>{0, 0.01});
}

TEST_CASE("the time column is found by its usual names, and its absence is one clear error") {
  for (const char* h : {"t,y", "timestamp,y", "Time (s),y", "time_s,y"}) {
    INFO(h);
    const auto t = tunekit::formats::parse_csv(std::string(h) + "\n0,1\n1,2\n", "mem.csv", {{}, "", true});
    REQUIRE_FALSE(t.time_column.empty());
    CHECK(t.columns.front().name == t.time_column);
  }
  CHECK(tunekit::formats::parse_csv("#time,accel_x\n0,1\n1,2\n", "mem.csv", {{"accel_x"}, "", true}).time_column ==
        "time");
  CHECK_THROWS_WITH(tunekit::formats::parse_csv("when,y\n0,1\n", "mem.csv", {{}, "", true}),
                    Catch::Contains("no time column") && Catch::Contains("the file has: when, y"));
}

TEST_CASE("plain decimals and the general number forms read the same values, mapped or in memory") {
  // The reader's one-pass path takes "-12.5" at a delimiter; spaces, a '+', an exponent or more
  // than 15 digits take the general path. Both must give the same doubles, and reading the file
  // (mapped) must equal parsing its bytes.
  const std::string text =
      "time,a,b\n"
      "0.5,-12.5,3\n"
      "1.5, -12.5 ,+3\n"
      "2.5,-1.25e1,3.000000000000000\n"
      "3.5,-12.50000000000000000001,0.3e1\n";
  const std::string path = write_scratch("csv_fast_general_" + std::to_string(getpid()) + ".csv", text);
  const auto mapped = tunekit::formats::read_csv(path, {{"a", "b"}, "time"});
  const auto parsed = tunekit::formats::parse_csv(text, path, {{"a", "b"}, "time"});
  REQUIRE(mapped.rows == 4);
  for (const auto* t : {&mapped, &parsed}) {
    for (std::size_t r = 0; r < 4; ++r) {
      CHECK(t->column("a").values[r] == -12.5);
      CHECK(t->column("b").values[r] == 3.0);
      CHECK(t->column("time").values[r] == 0.5 + static_cast<double>(r));
    }
  }
  // A value the one-pass path cannot take is located exactly as before.
  const std::string bad =
      write_scratch("csv_fast_bad_" + std::to_string(getpid()) + ".csv", "time,a\n0.5,1.5\n1.5,-\n");
  const auto r = run_cli({"inspect", bad, "--time", "time"});
  CHECK(r.code == 2);
  CHECK(r.err == "tunekit: error: " + bad + ":3:5: '-' in column 'a' is not a number\n");
}

TEST_CASE("plain decimals of every length read exactly the double that from_chars reads") {
  // The one-pass path reads plain decimals of up to 15 digits by Clinger's fast path, longer ones
  // by std::from_chars; every split of 0-9 integer and 0-9 fraction digits, with and without a
  // sign and a point, in a middle and in the last column, must give the correctly rounded value.
  std::mt19937_64 rng(20261129);
  std::string text = "time,a,b\n";
  std::vector<std::string> fields;
  double time = 0;
  for (int int_digits = 0; int_digits <= 9; ++int_digits)
    for (int frac_digits = 0; frac_digits <= 9; ++frac_digits)
      for (int k = 0; k < 20; ++k) {
        std::string f = (k % 2) != 0 ? "-" : "";
        for (int i = 0; i < int_digits; ++i) f += static_cast<char>('0' + rng() % 10);
        if (frac_digits > 0 || k % 5 == 0) f += '.';
        for (int i = 0; i < frac_digits; ++i) f += static_cast<char>('0' + rng() % 10);
        if (int_digits + frac_digits == 0) f += '0';
        fields.push_back(f);
        text += fmt::format("{},{},{}\n", time += 1, f, f);
      }
  const auto t = tunekit::formats::parse_csv(text, "digits.csv", {{"a", "b"}, "time"});
  REQUIRE(t.rows == fields.size());
  for (std::size_t r = 0; r < fields.size(); ++r) {
    INFO(fields[r]);
    const std::string& f = fields[r];
    double want = 0;
    const char* begin = f.data() + (f.front() == '-' ? 1 : 0);
    REQUIRE(std::from_chars(begin, f.data() + f.size(), want).ec == std::errc());
    if (f.front() == '-') want = -want;
    CHECK(t.column("a").values[r] == want);
    CHECK(t.column("b").values[r] == want);
  }
}

namespace {

// A Klipper-style raw accelerometer file of `rows` rows, every row the same length (so the
// middle of the data, where a large file is cut for the second thread, is a known row).
std::string large_raw_csv(std::size_t rows) {
  std::string s = "#time,accel_x,accel_y,accel_z\n";
  char line[96];
  for (std::size_t i = 0; i < rows; ++i) {
    const int n = std::snprintf(line, sizeof line, "%011.6f,%+011.4f,%+011.4f,%+011.4f\n", 1000.0 + 3.125e-4 * i,
                                static_cast<double>(i % 977) - 488.5, static_cast<double>(i % 89) * 0.25,
                                9800.0 + static_cast<double>(i % 7));
    s.append(line, static_cast<std::size_t>(n));
  }
  return s;
}

std::string error_of(const std::string& text) {
  try {
    (void)tunekit::formats::parse_csv(text, "big.csv", {{}, "time"});
  } catch (const tunekit::InputError& e) {
    return e.location() + ": " + e.message();
  }
  return "";
}

}  // namespace

TEST_CASE("a large file parsed on two threads gives every row once, in order, with the values written") {
  const std::size_t rows = 200'000;  // 9 MB: above the size at which the rows are split
  const std::string text = large_raw_csv(rows);
  REQUIRE(text.size() > (std::size_t{8} << 20));
  const auto t = tunekit::formats::parse_csv(text, "big.csv", {{}, "time"});
  REQUIRE(t.rows == rows);
  const auto& time = t.column("time").values;
  const auto& x = t.column("accel_x").values;
  REQUIRE(time.size() == rows);
  REQUIRE(x.size() == rows);
  for (const std::size_t i : {std::size_t{0}, rows / 2 - 1, rows / 2, rows / 2 + 1, rows - 1}) {
    CHECK(x[i] == static_cast<double>(i % 977) - 488.5);
    CHECK(time[i] == Approx(1000.0 + 3.125e-4 * static_cast<double>(i)).margin(6e-7));  // written with 6 decimals
  }
  CHECK(std::is_sorted(time.begin(), time.end()));
  CHECK(std::adjacent_find(time.begin(), time.end()) == time.end());
}

TEST_CASE("a large file's errors name the line a single pass names, on either side of the cut") {
  const std::size_t rows = 200'000, header_lines = 1;
  const std::string good = large_raw_csv(rows);
  const std::size_t row_bytes = (good.size() - good.find('\n') - 1) / rows;
  // Rows around the middle of the data (the cut) and far into the second half.
  for (const std::size_t row : {rows / 2 - 1, rows / 2, rows / 2 + 1, rows - 3}) {
    const std::size_t line = header_lines + row + 1;  // 1-based line of data row `row`
    const std::size_t at = good.find('\n') + 1 + row * row_bytes;
    SECTION("a field that is not a number, data row " + std::to_string(row)) {
      std::string bad = good;
      bad.replace(at + 12, 11, "   garbage ");  // the field starts at byte 13, its text at 16
      CHECK(error_of(bad) == "big.csv:" + std::to_string(line) + ":16: 'garbage' in column 'accel_x' is not a number");
    }
    SECTION("a time stamp repeated from the row above, data row " + std::to_string(row)) {
      std::string bad = good;
      bad.replace(at, 11, good.substr(at - row_bytes, 11));
      const double repeated = std::stod(good.substr(at - row_bytes, 11));
      CHECK(error_of(bad) == fmt::format("big.csv:{}:1: duplicate time stamp {} in column 'time' (also on line {})",
                                         line, repeated, line - 1));
    }
  }
}

TEST_CASE(
    "a file that is only a header without a line break is refused as having no rows, not with an internal error") {
  for (const std::string text : {",", "time,x", "time,x\r", "# comment\ntime,x"}) {
    INFO(text);
    try {
      (void)tunekit::formats::parse_csv(text, "short.csv", {});
      FAIL("accepted");
    } catch (const tunekit::InputError& e) {
      CHECK(e.message() == "a header but no data rows");
    }
  }
}
