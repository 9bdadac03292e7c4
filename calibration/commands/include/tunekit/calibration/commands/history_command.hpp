#pragma once
// tunekit history as functions: what changed on a machine, and since when. Results recorded with
// `--record --machine-id NAME` (or imported from archived run directories and batch summaries)
// are kept per machine in a SQLite file or a PostgreSQL server (tunekit/history/store.hpp); drift
// is a change from the machine's baseline larger than the combined uncertainty of the two runs
// (tunekit/history/drift.hpp; JCGM 100:2008, Guide to the expression of uncertainty in
// measurement). One options struct serves the five subcommands, each with its own compute and
// outcome; the shape of a command is described in docs/cpp-api.md.

#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/results/requirements.hpp"
#include "tunekit/history/drift.hpp"
#include "tunekit/history/store.hpp"

namespace tunekit::calibration {

struct HistoryOptions {
  std::string db;  ///< SQLite file or postgresql:// URL; empty: $TUNEKIT_HISTORY_DB, else history.sqlite
  std::vector<std::string> machines;    ///< machine ids (list, trend, report); empty: every machine
  std::vector<std::string> quantities;  ///< e.g. tau_s, x.freq_hz (trend, report); empty: all or the headline ones
  std::int64_t record_id = 0;           ///< show: the record
  history::DriftOptions drift;          ///< trend, report: baseline runs and coverage factor k
  bool show_runs = false;               ///< trend: every run of every machine (default only with machines named)
  std::vector<std::string> require;     ///< trend: CI thresholds on drift.* (a trailing % is percent) or quantities.*
  std::string html_out = "fleet.html";  ///< report: the HTML file written
  std::vector<std::string> paths;       ///< import: run directories, result files, batch summaries, folders of them
  std::string machine_id;               ///< import: the machine all imported results belong to
  bool machine_from_path = false;       ///< import: the machine id is the first folder under each PATH
};

/// `history list`: the machines, or the records of the machines named.
struct HistoryListOutcome {
  HistoryOptions options;
  std::string db;                                                                    ///< the database's display name
  std::vector<history::MachineSummary> machines;                                     ///< without machines named
  std::vector<std::pair<std::string, std::vector<history::RecordSummary>>> records;  ///< per machine named, in order
};
HistoryListOutcome compute_history_list(const HistoryOptions& options);
Envelope to_envelope(const HistoryListOutcome& outcome);
void print_text(const HistoryListOutcome& outcome, std::ostream& os);

/// `history show ID`: one record with its inputs, quantities and stored result.
struct HistoryShowOutcome {
  HistoryOptions options;
  std::string db;
  history::StoredRecord record;
  nlohmann::json result;  ///< the stored envelope, or its text when it is not JSON
};
/// InputError (exit 2) when there is no such record.
HistoryShowOutcome compute_history_show(const HistoryOptions& options);
Envelope to_envelope(const HistoryShowOutcome& outcome);
void print_text(const HistoryShowOutcome& outcome, std::ostream& os);

/// One machine's quantities against its baseline.
struct MachineTrend {
  std::string machine_id;
  std::size_t runs = 0;                      ///< records that hold any of the quantities
  std::vector<history::DriftSeries> series;  ///< headline quantities first, then by name (or as asked)
};

/// `history trend`: each machine's series, drift and requirement outcomes.
struct HistoryTrendOutcome {
  HistoryOptions options;
  std::string db;
  bool with_runs = false;  ///< every run listed (machines named, or show_runs)
  struct Machine {
    MachineTrend trend;
    nlohmann::json quantities;  ///< per quantity: unit, count, latest, baseline, drift (runs as columns with with_runs)
    nlohmann::json drift;       ///< drift.NAME: the latest run's significant change (%), nested by the name's dots
    std::vector<std::string> drifted;  ///< quantities whose latest run drifted
    /// Per --require: its outcome, or nullopt when it does not apply to this machine (several machines).
    std::vector<std::pair<std::string, std::optional<RequirementOutcome>>> requirements;
  };
  std::vector<Machine> machines;
  int exit_code = 0;  ///< 1 when a requirement is unmet on any machine
};
/// InputError (exit 2) for an empty database, a machine without the quantities asked for, or a
/// requirement that applies to nothing on a single machine.
HistoryTrendOutcome compute_history_trend(const HistoryOptions& options);
Envelope to_envelope(const HistoryTrendOutcome& outcome);
void print_text(const HistoryTrendOutcome& outcome, std::ostream& os);
/// "tunekit: MACHINE: requirement not met: EXPR (PATH = VALUE)", one line per unmet requirement.
void print_unmet_requirements(const HistoryTrendOutcome& outcome, std::ostream& err);

/// `history report`: the fleet HTML report (one row per machine, sparklines, drift flagged).
struct HistoryReportOutcome {
  HistoryOptions options;
  std::string db;
  std::vector<std::string> columns;  ///< the quantities shown
  struct Row {
    std::string machine_id;
    std::size_t runs = 0;
    std::string last_run_utc;
    std::vector<std::string> drifted;
  };
  std::vector<Row> rows;
};
/// Writes options.html_out atomically.
HistoryReportOutcome compute_history_report(const HistoryOptions& options);
Envelope to_envelope(const HistoryReportOutcome& outcome);
void print_text(const HistoryReportOutcome& outcome, std::ostream& os);

/// `history import`: results into the database, each once.
struct HistoryImportOutcome {
  HistoryOptions options;
  std::string db;
  struct Entry {
    std::string source;
    std::string status;      ///< "imported", "already recorded" or "skipped"
    std::string reason;      ///< why skipped
    std::string machine_id;  ///< imported or already recorded: whose
    std::string command;
    std::optional<std::int64_t> record_id;  ///< imported: the new record
  };
  std::vector<Entry> entries;  ///< in the order found
  int imported = 0, already_recorded = 0;
};
/// Stores every result found under options.paths. A file found in a folder that is not a result
/// is skipped (and listed); one named on the command line is an InputError (exit 2).
HistoryImportOutcome compute_history_import(const HistoryOptions& options);
Envelope to_envelope(const HistoryImportOutcome& outcome);
void print_text(const HistoryImportOutcome& outcome, std::ostream& os);

}  // namespace tunekit::calibration
