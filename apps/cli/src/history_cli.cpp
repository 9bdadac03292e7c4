// tunekit history: the command line of the command (options bound straight into the library's
// option structs, so --help shows the library's defaults); the work is done by the
// calibration library's compute function.

#include "tunekit/cli/command.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/commands/history_command.hpp"
#include "tunekit/calibration/results/history_record.hpp"
#include "tunekit/cli/option_binding.hpp"
#include "tunekit/calibration/presentation/report.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/history/store.hpp"
#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <memory>

namespace tunekit::cli {

using namespace calibration;

namespace {

struct HistoryCommand {
  HistoryOptions options;
  OutputOptions output;
};

CLI::App* hist_sub(CLI::App* parent, const std::string& name, const std::string& desc, HistoryCommand& a) {
  auto* s = parent->add_subcommand(name, desc);
  add_output_options(s, a.output, false);
  s->add_option("--db", a.options.db,
                fmt::format("SQLite file or postgresql://user@host:port/dbname (default: $TUNEKIT_HISTORY_DB, else {})",
                            kDefaultHistoryDb));
  return s;
}

}  // namespace

void register_history(CLI::App& app, CliContext& ctx) {
  auto* hist = app.add_subcommand("history",
                                  "Calibration history per machine: list, show, trend and drift, fleet report, import");
  hist->require_subcommand(1);
  hist->footer(
      "Record with any calibrate, batch or analysis command: --record --machine-id NAME [--db DB].\n"
      "The database is a SQLite file (default history.sqlite, or $TUNEKIT_HISTORY_DB) or a PostgreSQL server\n"
      "(--db postgresql://user@host:5432/tunekit) shared by a farm; its schema is created or migrated on open.");

  auto list = std::make_shared<HistoryCommand>();
  auto* l = hist_sub(hist, "list", "Machines in the history, or one machine's records (--machine)", *list);
  l->add_option("-m,--machine", list->options.machines, "Machine id (repeatable)");
  l->callback([list, &ctx] { set_exit_code(report_outcome(compute_history_list(list->options), list->output, ctx)); });

  auto show = std::make_shared<HistoryCommand>();
  auto* s = hist_sub(hist, "show", "One record: inputs with their SHA-256, quantities, the stored result", *show);
  s->add_option("id", show->options.record_id, "Record id (from 'history list --machine M')")->required();
  s->callback([show, &ctx] { set_exit_code(report_outcome(compute_history_show(show->options), show->output, ctx)); });

  auto trend = std::make_shared<HistoryCommand>();
  auto* t = hist_sub(hist, "trend", "Each quantity's runs against the machine's baseline; drift flagged", *trend);
  t->add_option("-m,--machine", trend->options.machines, "Machine id (repeatable; default: every machine)");
  t->add_option("-q,--quantity", trend->options.quantities,
                "Quantity (repeatable): tau_s, theta_s, K, x.freq_hz, x.zeta, x.shaper, x.shaper_freq_hz, pa_k_s, ...");
  t->add_option("--baseline", trend->options.drift.baseline_runs, "The machine's first N runs form its baseline")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  t->add_option("--coverage", trend->options.drift.coverage_k,
                "Drift when |change| > K x sqrt(u_run^2 + u_baseline^2) (1.96: 95 % interval of the difference)")
      ->capture_default_str()
      ->check(positive_finite("a coverage factor"));
  t->add_flag("--runs", trend->options.show_runs, "Every run of every machine (default: every run only for --machine)");
  t->footer(
      "A change within the combined uncertainty of the run and the baseline is not drift. drift.NAME is the latest\n"
      "run's change from the baseline in percent when it is drift, 0 otherwise; gate CI on it:\n"
      "  tunekit history trend --machine printer-07 --require 'drift.x.freq_hz>-5%'\n"
      "Uncertainties follow JCGM 100:2008, Guide to the expression of uncertainty in measurement.");
  t->callback([trend, &ctx] {
    // --require is evaluated per machine by compute_history_trend(), not on the envelope.
    trend->options.require = trend->output.require;
    OutputOptions output = trend->output;
    output.require.clear();
    const auto outcome = compute_history_trend(trend->options);
    print_unmet_requirements(outcome, ctx.err);
    set_exit_code(std::max(outcome.exit_code, report_outcome(outcome, output, ctx)));
  });

  auto report = std::make_shared<HistoryCommand>();
  auto* r = hist_sub(hist, "report", "Fleet HTML report: one row per machine, sparklines, drifted quantities flagged",
                     *report);
  r->add_option("--out", report->options.html_out, "HTML file to write")->capture_default_str();
  r->add_option("-m,--machine", report->options.machines, "Machine id (repeatable; default: every machine)");
  r->add_option("-q,--quantity", report->options.quantities,
                "Columns (repeatable; default: the headline quantities present)");
  r->add_option("--baseline", report->options.drift.baseline_runs, "The machine's first N runs form its baseline")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  r->add_option("--coverage", report->options.drift.coverage_k, "Coverage factor of the drift interval")
      ->capture_default_str()
      ->check(positive_finite("a coverage factor"));
  r->callback(
      [report, &ctx] { set_exit_code(report_outcome(compute_history_report(report->options), report->output, ctx)); });

  auto imp = std::make_shared<HistoryCommand>();
  auto* i =
      hist_sub(hist, "import", "Import run directories, result files and batch summaries (folders are searched)", *imp);
  i->add_option("paths", imp->options.paths, "Run directories, result JSON files, batch summaries or folders of them")
      ->required();
  i->add_option("--machine-id", imp->options.machine_id, "The machine all these results belong to");
  i->add_flag("--machine-from-path", imp->options.machine_from_path,
              "Take each result's machine id from the first folder under PATH (archive/<machine>/...)");
  i->footer(
      "Each run directory (a folder with results.json) is one record; a batch summary is one record per dataset.\n"
      "A run's time is taken from its directory name (calibrate-YYYYMMDD-HHMMSS) or the file's time. Importing\n"
      "the same results again adds nothing. Example:\n"
      "  tunekit history import archive/ --machine-from-path --db postgresql://tunekit@farm-db/tunekit");
  i->callback([imp, &ctx] { set_exit_code(report_outcome(compute_history_import(imp->options), imp->output, ctx)); });
}

}  // namespace tunekit::cli
