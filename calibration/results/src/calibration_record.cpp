// The edge of a calibration run's record (calibration_record.hpp): its one writer into
// results.json's envelope and its one reader from a run directory's results.json. The plot
// series' JSON is in plot_data_json.cpp.
#include "tunekit/calibration/results/calibration_record.hpp"

#include <filesystem>

#include <fmt/format.h>

#include "tunekit/calibration/results/json_access.hpp"
#include "tunekit/calibration/results/results_json.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/json_error_text.hpp"

namespace tunekit::calibration {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

nlohmann::json row_json(const SummaryRow& row) {
  nlohmann::json r{{"label", row.label}, {"path", row.path}, {"unit", row.unit}};
  if (!row.ci_path.empty()) r["ci_path"] = row.ci_path;
  else r["basis"] = row.basis;
  return r;
}

// A row of results.summary: its value and interval read from where its paths point.
SummaryRow row_from_json(const nlohmann::json& results, const nlohmann::json& row) {
  SummaryRow r;
  r.path = row.value("path", std::string());
  r.label = row.value("label", r.path);
  r.unit = row.value("unit", std::string());
  if (const auto* v = json_at(results, r.path); v != nullptr && v->is_number()) r.estimate.value = v->get<double>();
  r.ci_path = row.value("ci_path", std::string());
  if (r.ci_path.empty()) {
    r.basis = row.value("basis", std::string("n/a"));
    return r;
  }
  const auto* ci = json_at(results, r.ci_path);
  if (ci != nullptr && ci->is_array() && ci->size() == 2 && (*ci)[0].is_number() && (*ci)[1].is_number()) {
    r.estimate.ci95_lo = (*ci)[0].get<double>();
    r.estimate.ci95_hi = (*ci)[1].get<double>();
  }
  return r;
}

double number_or_nan(const nlohmann::json& j, const char* key) {
  return j.contains(key) && j[key].is_number() ? j[key].get<double>() : kNaN;
}

Estimate estimate_from_json(const nlohmann::json& e) {
  Estimate out{e.value("method", std::string()), number_or_nan(e, "value"), kNaN, kNaN};
  if (e.contains("ci95") && e["ci95"].is_array() && e["ci95"].size() == 2) {
    if (e["ci95"][0].is_number()) out.ci95_lo = e["ci95"][0].get<double>();
    if (e["ci95"][1].is_number()) out.ci95_hi = e["ci95"][1].get<double>();
  }
  return out;
}

Agreement agreement_from_json(const nlohmann::json& j) {
  Agreement a;
  a.id = j.value("id", std::string());
  a.quantity = j.value("quantity", std::string());
  a.unit = j.value("unit", std::string());
  if (j.contains("estimates") && j["estimates"].is_array() && j["estimates"].size() == 2) {
    a.a = estimate_from_json(j["estimates"][0]);
    a.b = estimate_from_json(j["estimates"][1]);
  }
  a.difference = number_or_nan(j, "difference");
  a.combined_half_width = number_or_nan(j, "combined_half_width");
  if (j.contains("margin") && j["margin"].is_object()) {
    a.margin_relative = number_or_nan(j["margin"], "relative");
    a.margin_value = number_or_nan(j["margin"], "value");
    a.margin_basis = j["margin"].value("basis", std::string());
  }
  a.verdict = j.value("verdict", std::string());
  a.agree = j.value("agree", false);
  a.statement = j.value("statement", std::string());
  return a;
}

// The record's typed parts of `results`; the rest stays in `details`.
void typed_results_from_json(const nlohmann::json& results, CalibrationRecord& r) {
  r.machine = results.value("machine", std::string());
  if (results.contains("summary") && results["summary"].is_array())
    for (const auto& row : results["summary"]) r.summary.push_back(row_from_json(results, row));
  if (results.contains("agreement") && results["agreement"].is_array())
    for (const auto& a : results["agreement"]) r.agreements.push_back(agreement_from_json(a));
  if (results.contains("notes") && results["notes"].is_array())
    for (const auto& n : results["notes"])
      if (n.is_string()) r.notes.push_back(n.get<std::string>());
  if (results.contains("config_diff") && results["config_diff"].is_string())
    r.config_diff = results["config_diff"].get<std::string>();
  r.details = results.is_object() ? results : nlohmann::json::object();
  for (const char* key : {"machine", "summary", "agreement", "notes", "config_diff"}) r.details.erase(key);
}

}  // namespace

void write_record_results(const CalibrationRecord& record, Envelope& env) {
  auto& res = env.results();
  res = record.details;
  res["machine"] = record.machine;
  res["summary"] = nlohmann::json::array();
  for (const auto& row : record.summary) res["summary"].push_back(row_json(row));
  res["agreement"] = nlohmann::json::array();
  for (const auto& a : record.agreements) res["agreement"].push_back(to_json(a));
  res["notes"] = record.notes;
  res["config_diff"] = record.config_diff;
  for (const auto& w : record.warnings) env.warn(w);
}

CalibrationRecord record_from_json(const nlohmann::json& env, const nlohmann::json& plotdata,
                                   const std::string& where) {
  CalibrationRecord r;
  try {
    const auto& results = env.contains("results") ? env["results"] : env;
    r.command = env.value("command", std::string("?"));
    r.tool_version.clear();
    if (env.contains("tool")) r.tool_version = env["tool"].value("version", std::string("?"));
    typed_results_from_json(results, r);
    if (env.contains("warnings"))
      for (const auto& w : env["warnings"]) r.warnings.push_back(w.get<std::string>());
    r.plots = plots_from_json(plotdata);
  } catch (const nlohmann::json::exception& e) {
    // A member of an unexpected type deeper in the results or the plot data.
    throw InputError(
        fmt::format("unexpected content in the results or plot data: {}", core::plain_json_error(e.what())), where);
  }
  return r;
}

CalibrationRecord read_run_record(const std::string& run_dir) {
  const std::string results_path = run_dir + "/results.json";
  const nlohmann::json env = read_results_json(results_path);
  nlohmann::json pd = nlohmann::json::object();
  const std::string pd_path = run_dir + "/plotdata.json";
  if (std::filesystem::exists(pd_path)) {
    pd = read_json_file(pd_path);
    if (!pd.is_object())
      throw InputError(fmt::format("plot data must be a JSON object, not {}", pd.type_name()), pd_path);
  }
  return record_from_json(env, pd, results_path);
}

}  // namespace tunekit::calibration
