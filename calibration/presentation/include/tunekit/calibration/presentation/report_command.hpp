#pragma once
// tunekit report as a function: (re)build the self-contained HTML calibration report of a run
// directory from its results.json and plotdata.json (what the report holds: report.hpp). The
// shape of a command is described in docs/cpp-api.md; `report` writes no JSON envelope,
// so it has no to_envelope().

#include <ostream>
#include <string>
#include <vector>

#include "tunekit/calibration/presentation/report.hpp"

namespace tunekit::calibration {

struct ReportOptions {
  std::string run_dir;  ///< a run directory holding results.json (and plotdata.json, optional)
};

struct ReportOutcome {
  ReportOptions options;
  std::string html_path;            ///< RUN_DIR/report.html, written atomically
  std::vector<ReportImage> images;  ///< the plots rendered into RUN_DIR/plots/*.svg and the photos embedded
};

/// Reads RUN_DIR/results.json and plotdata.json, renders the plots and writes report.html.
/// InputError (exit 2, located at the file) for a missing or malformed results file.
ReportOutcome compute_report(const ReportOptions& options);

/// Renders `record` as RUN_DIR's report: the plots into RUN_DIR/plots/*.svg, report.html written
/// atomically (what compute_report does with the record read from RUN_DIR).
ReportOutcome render_report(const std::string& run_dir, const CalibrationRecord& record);

/// The report's path, one line.
void print_text(const ReportOutcome& outcome, std::ostream& os);

}  // namespace tunekit::calibration
