#pragma once
// tunekit inspect as a function: read a time-series CSV with the same reader every analysis
// uses and summarize its columns, units, row count, time span and sampling: the quickest way
// to check that a log is readable before fitting it. The shape of a command is described in
// docs/cpp-api.md.

#include <cstddef>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/results/input_digest.hpp"

namespace tunekit::calibration {

struct InspectOptions {
  std::string file;                  ///< CSV file
  std::string time_column;           ///< must strictly increase (s); empty: no time column checked
  std::vector<std::string> columns;  ///< columns to read; empty: all
};

/// One column read, in its own unit.
struct InspectColumn {
  std::string name, unit;  ///< unit as in the header ("" when none)
  double min = 0, max = 0, mean = 0;
};

/// The sampling of the time column.
struct InspectTiming {
  double span_s = 0;                  ///< last minus first time (s)
  double sample_rate_hz = 0;          ///< 1 / mean interval (Hz)
  double min_dt_s = 0, max_dt_s = 0;  ///< shortest and longest interval (s)
};

struct InspectOutcome {
  InspectOptions options;
  InputDigest input;
  std::size_t rows = 0;
  std::vector<std::string> header;      ///< every column name of the file, in order
  std::vector<InspectColumn> columns;   ///< the columns read
  std::optional<InspectTiming> timing;  ///< with a time column and at least 2 rows
  std::vector<std::string> warnings;    ///< irregular sampling, then the reader's
};

/// Reads and summarizes the CSV; InputError (exit 2) with FILE:LINE when it is not readable.
InspectOutcome compute_inspect(const InspectOptions& options);

Envelope to_envelope(const InspectOutcome& outcome);
void print_text(const InspectOutcome& outcome, std::ostream& os);

}  // namespace tunekit::calibration
