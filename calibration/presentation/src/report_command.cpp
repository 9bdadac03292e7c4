#include "tunekit/calibration/presentation/report_command.hpp"

#include <filesystem>

#include <fmt/format.h>

#include "tunekit/calibration/results/results_json.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/json_error_text.hpp"

namespace tunekit::calibration {

ReportOutcome compute_report(const ReportOptions& options) {
  ReportOutcome outcome;
  outcome.options = options;
  const std::string& run_dir = options.run_dir;
  const std::string results_path = run_dir + "/results.json";
  const nlohmann::json env = read_results_json(results_path);
  nlohmann::json pd = nlohmann::json::object();
  const std::string pd_path = run_dir + "/plotdata.json";
  if (std::filesystem::exists(pd_path)) {
    pd = read_json_file(pd_path);
    if (!pd.is_object())
      throw InputError(fmt::format("plot data must be a JSON object, not {}", pd.type_name()), pd_path);
  }
  std::string html;
  try {
    outcome.images = render_report_plots(run_dir, pd);
    html = build_report_html(env, outcome.images);
  } catch (const nlohmann::json::exception& e) {
    // A member of an unexpected type deeper in the results or the plot data.
    throw InputError(
        fmt::format("unexpected content in the results or plot data: {}", core::plain_json_error(e.what())),
        results_path);
  }
  outcome.html_path = run_dir + "/report.html";
  core::write_file_atomic(outcome.html_path, html);
  return outcome;
}

void print_text(const ReportOutcome& outcome, std::ostream& os) { os << outcome.html_path << "\n"; }

std::string write_report(const std::string& run_dir) { return compute_report({run_dir}).html_path; }

}  // namespace tunekit::calibration
