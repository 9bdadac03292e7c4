// tunekit inspect: read a time-series CSV with the same reader every analysis uses, and
// report its columns, units, row count, time span and sampling. The quickest way to check
// that a log is readable before fitting it.
#include <algorithm>
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/envelope.hpp"
#include "tunekit/ident/csv.hpp"

namespace tunekit::cli {
namespace {

struct InspectArgs {
  std::string file;
  std::string time_column;
  std::vector<std::string> columns;
  OutputOptions output;
};

int run_inspect(const InspectArgs& a, CliContext& ctx) {
  ident::CsvOptions opt;
  opt.columns = a.columns;
  opt.time_column = a.time_column;
  const std::string bytes = ident::read_file_bytes(a.file);
  const auto table = ident::parse_csv(bytes, a.file, opt);

  Envelope env("inspect");
  env.set_options({{"time_column", a.time_column}, {"columns", a.columns}});
  env.add_input(a.file, bytes);
  auto& res = env.results();
  res["rows"] = table.rows;
  res["header"] = table.header;
  nlohmann::json cols = nlohmann::json::array();
  for (const auto& c : table.columns) {
    const auto [lo, hi] = std::minmax_element(c.values.begin(), c.values.end());
    double mean = 0;
    for (double v : c.values) mean += v;
    mean /= static_cast<double>(c.values.size());
    cols.push_back({{"name", c.name}, {"unit", c.unit}, {"min", *lo}, {"max", *hi}, {"mean", mean}});
  }
  res["columns"] = cols;
  if (!a.time_column.empty() && table.rows >= 2) {
    const auto& t = table.column(a.time_column).values;
    const double span = t.back() - t.front();
    double max_dt = 0, min_dt = span;
    for (std::size_t i = 1; i < t.size(); ++i) {
      max_dt = std::max(max_dt, t[i] - t[i - 1]);
      min_dt = std::min(min_dt, t[i] - t[i - 1]);
    }
    const double mean_dt = span / static_cast<double>(t.size() - 1);
    res["time"] = {{"span_s", span}, {"sample_rate_hz", 1.0 / mean_dt}, {"min_dt_s", min_dt}, {"max_dt_s", max_dt}};
    if (max_dt > 1.5 * mean_dt)
      env.warn(fmt::format("{}: irregular sampling: the largest gap is {:.3g} s, {:.1f} times the mean interval",
                           a.file, max_dt, max_dt / mean_dt));
  }
  for (const auto& w : table.warnings) env.warn(w);
  if (!a.output.json) {
    ctx.out << fmt::format("{}: {} rows, {} columns\n", a.file, table.rows, table.header.size());
    for (const auto& c : cols)
      ctx.out << fmt::format("  {:<16} [{}]  min {:.6g}  max {:.6g}  mean {:.6g}\n", c["name"].get<std::string>(),
                             c["unit"].get<std::string>(), c["min"].get<double>(), c["max"].get<double>(),
                             c["mean"].get<double>());
    if (res.contains("time"))
      ctx.out << fmt::format("  time span {:.6g} s, {:.6g} Hz mean sampling\n", res["time"]["span_s"].get<double>(),
                             res["time"]["sample_rate_hz"].get<double>());
  }
  return emit(env, a.output, ctx);
}

}  // namespace

void register_inspect(CLI::App& app, CliContext& ctx) {
  auto args = std::make_shared<InspectArgs>();
  auto* sub = app.add_subcommand("inspect", "Check that a time-series CSV is readable and summarize it");
  sub->add_option("file", args->file, "CSV file (comment lines start with '#'; units allowed in names: 'force (N)')")
      ->required();
  sub->add_option("-t,--time", args->time_column, "Name of the time column (s); must strictly increase");
  sub->add_option("-c,--columns", args->columns, "Columns to read (default: all)");
  add_output_options(sub, args->output);
  sub->footer(
      "Examples:\n"
      "  tunekit inspect datasets/liquefier/holtrup_table_b1_ooze.csv\n"
      "  tunekit inspect adxl345-x.csv --time time --json     # a Klipper raw accelerometer file");
  sub->callback([args, &ctx] { set_exit_code(run_inspect(*args, ctx)); });
}

}  // namespace tunekit::cli
