// The CSV reader on arbitrary bytes: every column, and with a time column that must increase.
#include "fuzz_common.hpp"
#include "tunekit/formats/csv.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto text = tunekit::fuzz::as_text(data, size);
  tunekit::fuzz::expect_result_or_error([&] { tunekit::formats::parse_csv(text, "fuzz.csv"); });
  tunekit::fuzz::expect_result_or_error([&] {
    tunekit::formats::CsvOptions o;
    o.time_column = "time";
    o.columns = {"time", "accel_x", "accel_y", "accel_z"};
    o.max_line_bytes = 4096;
    tunekit::formats::parse_csv(text, "fuzz.csv", o);
  });
  return 0;
}
