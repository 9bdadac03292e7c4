#pragma once
// A calibration run's record, typed: what `tunekit calibrate` found and what every view of the run
// is rendered from (the terminal's table, the HTML report, results.json and through it the
// --require thresholds and the history record). JSON is only its edge: write_record_results()
// writes it into results.json's envelope, read_run_record() reads a run directory's results.json
// and plotdata.json back into the same type, so that `tunekit report RUN_DIR` renders the report
// the run wrote.

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/calibration/results/agreement.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/results/plot_data.hpp"

namespace tunekit::calibration {

/// A value with its 95 % interval (same unit); NaN bounds where there is no interval, a NaN
/// value where the quantity was not obtained.
struct ValueEstimate {
  double value = std::numeric_limits<double>::quiet_NaN();
  double ci95_lo = std::numeric_limits<double>::quiet_NaN(), ci95_hi = std::numeric_limits<double>::quiet_NaN();
  bool has_value() const { return std::isfinite(value); }
  bool has_interval() const { return std::isfinite(ci95_lo) && std::isfinite(ci95_hi); }
};

/// One row of the summary: an identified or designed quantity.
struct SummaryRow {
  std::string label;  ///< what it is, in words
  ValueEstimate estimate;
  std::string unit;  ///< "1" for a dimensionless quantity
  /// Why the row has no interval ("designed", "set by the test ..."); empty for a row that has
  /// (or should have had) one.
  std::string basis;
  /// Where results.json's `results` records the value and its interval (dotted paths, e.g.
  /// "axes.x.modes[0].freq_hz"): written into results.json and shown in the report's cells;
  /// `ci_path` empty for a row with a basis.
  std::string path, ci_path;
};

/// The run's record.
struct CalibrationRecord {
  std::string command = "calibrate";  ///< the tunekit command that made it
  std::string tool_version;           ///< the tunekit version that made it
  std::string machine;                ///< the machine profile's name
  std::vector<SummaryRow> summary;
  std::vector<Agreement> agreements;  ///< quantities measured two ways
  std::vector<std::string> notes;     ///< informational lines
  std::vector<std::string> warnings;
  std::string config_diff;  ///< the configuration change as a unified diff; empty: none
  ReportPlots plots;
  /// The rest of results.json's `results`: each analysis' results as its own JSON holds them,
  /// the chirp plan, the reproduce commands. Written, never read back to render the run.
  nlohmann::json details = nlohmann::json::object();
};

/// The one writer of results.json's results: the record's results and warnings into `env`
/// (whose command, options and inputs the caller has set).
void write_record_results(const CalibrationRecord& record, Envelope& env);

/// The one writer of plotdata.json: the plots' series as JSON (report.hpp lists the members).
nlohmann::json plotdata_json(const ReportPlots& plots);

/// The one reader: RUN_DIR/results.json (and RUN_DIR/plotdata.json when there is one) back into
/// a record. A summary row's value and interval are read from where its path and ci_path point
/// (a row whose value is not a number keeps a NaN value). InputError located at the file for a
/// missing or malformed file.
CalibrationRecord read_run_record(const std::string& run_dir);

/// The record of an envelope (results.json's contents) and plot data already parsed; `where`
/// names them in errors.
CalibrationRecord record_from_json(const nlohmann::json& envelope, const nlohmann::json& plotdata,
                                   const std::string& where);

/// The plots of plotdata.json's contents (report.hpp lists its members); absent members are
/// plots left out. Throws nlohmann::json's exceptions for members of an unexpected type.
ReportPlots plots_from_json(const nlohmann::json& plotdata);

/// The flow-dependent advance plot from `tunekit export`'s results.flow_advance (with its optional
/// rheology member) or plotdata.json's flow_advance.
FlowAdvancePlot flow_advance_plot_from_json(const nlohmann::json& flow_advance);
/// The rheology-predicted tau beside a flow design (export's comparison with tunekit rheo's
/// prediction, as its results hold it).
FlowAdvancePlot::Rheology flow_rheology_from_json(const nlohmann::json& rheology);

}  // namespace tunekit::calibration
