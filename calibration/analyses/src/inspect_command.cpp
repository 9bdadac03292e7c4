// tunekit inspect: read a time-series CSV with the same reader every analysis uses, and
// report its columns, units, row count, time span and sampling. The quickest way to check
// that a log is readable before fitting it.
#include <algorithm>
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/analyses/inspect_command.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/core/file_bytes.hpp"

namespace tunekit::calibration {

InspectOutcome compute_inspect(const InspectOptions& a) {
  formats::CsvOptions opt;
  opt.columns = a.columns;
  opt.time_column = a.time_column;
  const std::string bytes = read_file_bytes(a.file);
  const auto table = formats::parse_csv(bytes, a.file, opt);

  InspectOutcome outcome;
  outcome.options = a;
  outcome.input = input_digest(a.file, bytes);
  outcome.rows = table.rows;
  outcome.header = table.header;
  for (const auto& c : table.columns) {
    const auto [lo, hi] = std::minmax_element(c.values.begin(), c.values.end());
    double mean = 0;
    for (double v : c.values) mean += v;
    mean /= static_cast<double>(c.values.size());
    outcome.columns.push_back({c.name, c.unit, *lo, *hi, mean});
  }
  if (!a.time_column.empty() && table.rows >= 2) {
    const auto& t = table.column(a.time_column).values;
    const double span = t.back() - t.front();
    double max_dt = 0, min_dt = span;
    for (std::size_t i = 1; i < t.size(); ++i) {
      max_dt = std::max(max_dt, t[i] - t[i - 1]);
      min_dt = std::min(min_dt, t[i] - t[i - 1]);
    }
    const double mean_dt = span / static_cast<double>(t.size() - 1);
    outcome.timing = InspectTiming{span, 1.0 / mean_dt, min_dt, max_dt};
    if (max_dt > 1.5 * mean_dt)
      outcome.warnings.push_back(
          fmt::format("{}: irregular sampling: the largest gap is {:.3g} s, {:.1f} times the mean interval", a.file,
                      max_dt, max_dt / mean_dt));
  }
  outcome.warnings.insert(outcome.warnings.end(), table.warnings.begin(), table.warnings.end());
  return outcome;
}

Envelope to_envelope(const InspectOutcome& o) {
  Envelope env("inspect");
  env.set_options({{"time_column", o.options.time_column}, {"columns", o.options.columns}});
  add_input(env, o.input);
  auto& res = env.results();
  res["rows"] = o.rows;
  res["header"] = o.header;
  nlohmann::json cols = nlohmann::json::array();
  for (const auto& c : o.columns)
    cols.push_back({{"name", c.name}, {"unit", c.unit}, {"min", c.min}, {"max", c.max}, {"mean", c.mean}});
  res["columns"] = cols;
  if (o.timing)
    res["time"] = {{"span_s", o.timing->span_s},
                   {"sample_rate_hz", o.timing->sample_rate_hz},
                   {"min_dt_s", o.timing->min_dt_s},
                   {"max_dt_s", o.timing->max_dt_s}};
  for (const auto& w : o.warnings) env.warn(w);
  return env;
}

void print_text(const InspectOutcome& o, std::ostream& os) {
  os << fmt::format("{}: {} rows, {} columns\n", o.options.file, o.rows, o.header.size());
  for (const auto& c : o.columns)
    os << fmt::format("  {:<16} [{}]  min {:.6g}  max {:.6g}  mean {:.6g}\n", c.name, c.unit, c.min, c.max, c.mean);
  if (o.timing)
    os << fmt::format("  time span {:.6g} s, {:.6g} Hz mean sampling\n", o.timing->span_s, o.timing->sample_rate_hz);
}

}  // namespace tunekit::calibration
