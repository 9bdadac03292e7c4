#include "tunekit/calibration/results/history_record.hpp"

#include <cstdlib>
#include <filesystem>

#include <fmt/format.h>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/history/quantities.hpp"

namespace tunekit::calibration {
namespace {

std::vector<history::InputDigest> record_inputs_of(const nlohmann::json& inputs) {
  std::vector<history::InputDigest> out;
  if (!inputs.is_array()) return out;
  for (const auto& in : inputs) {
    if (!in.is_object()) continue;
    out.push_back({in.value("path", std::string()), in.value("sha256", std::string()),
                   in.contains("bytes") && in["bytes"].is_number_integer() ? in["bytes"].get<std::int64_t>() : -1});
  }
  return out;
}

history::NewRecord record_from(const nlohmann::json& env, const std::string& machine_id, const std::string& source,
                               const std::string& run_utc) {
  history::NewRecord r;
  r.machine_id = machine_id;
  r.command = env.value("command", std::string());
  if (env.contains("tool") && env["tool"].is_object()) r.tool_version = env["tool"].value("version", std::string());
  r.envelope_schema = env.contains("schema_version") && env["schema_version"].is_number_integer()
                          ? env["schema_version"].get<int>()
                          : 0;
  r.source = source;
  r.run_utc = run_utc;
  r.inputs = record_inputs_of(env.contains("inputs") ? env["inputs"] : nlohmann::json());
  r.quantities =
      history::extract_quantities(r.command, env.contains("results") ? env["results"] : nlohmann::json::object());
  r.envelope = env.dump();
  r.envelope_sha256 = sha256_hex(r.envelope);
  return r;
}

}  // namespace

std::string history_db(const OutputOptions& o) {
  if (!o.db.empty()) return o.db;
  const char* env = std::getenv("TUNEKIT_HISTORY_DB");
  return env != nullptr && *env != '\0' ? env : kDefaultHistoryDb;
}

void prepare_record(OutputOptions& o, const std::string& profile_machine_id) {
  if (!o.record) return;
  if (o.machine_id.empty()) o.machine_id = profile_machine_id;
  if (o.machine_id.empty())
    throw InputError(
        "--record needs the machine's id: --machine-id NAME, or id = \"NAME\" under [machine] in the profile");
  history::check_machine_id(o.machine_id);
  history::Store store(history_db(o));  // creates or migrates it now, not after the run
}

std::vector<history::NewRecord> records_from_envelope(const nlohmann::json& env, const std::string& machine_id,
                                                      const std::string& source, const std::string& run_utc) {
  if (!env.is_object() || !env.contains("command") || !env["command"].is_string() || !env.contains("results"))
    throw InputError("not a tunekit result (a JSON object with command and results)", source);
  std::vector<history::NewRecord> out;
  if (env["command"] != "batch") {
    out.push_back(record_from(env, machine_id, source, run_utc));
    return out;
  }
  // A batch summary: each analysed dataset is its own record, with its own input's digest.
  const auto& datasets = env["results"].contains("datasets") ? env["results"]["datasets"] : nlohmann::json::array();
  const auto inputs = env.contains("inputs") ? env["inputs"] : nlohmann::json::array();
  for (const auto& d : datasets) {
    if (!d.contains("results") || !d["results"].is_object() || !d.contains("command") || !d["command"].is_array() ||
        d["command"].empty())
      continue;
    const std::string file = d.value("file", std::string());
    nlohmann::json sub{{"schema_version", env.value("schema_version", 0)},
                       {"tool", env.contains("tool") ? env["tool"] : nlohmann::json::object()},
                       {"command", d["command"][0]},
                       {"options", {{"batch_command", d["command"]}}},
                       {"inputs", nlohmann::json::array()},
                       {"results", d["results"]},
                       {"diagnostics", nlohmann::json::object()},
                       {"warnings", nlohmann::json::array()}};
    for (const auto& in : inputs)
      if (in.is_object() && in.value("path", std::string()) == file) sub["inputs"].push_back(in);
    out.push_back(record_from(sub, machine_id, source.empty() ? file : source + "#" + file, run_utc));
  }
  return out;
}

void record_result(const nlohmann::json& envelope, const OutputOptions& o, CliContext& ctx) {
  if (o.machine_id.empty())
    throw InputError(
        "--record needs the machine's id: --machine-id NAME (or [machine] id in the profile for calibrate)");
  history::check_machine_id(o.machine_id);
  const std::string db = history_db(o);
  history::Store store(db);
  std::string source = o.record_source;
  std::error_code ec;
  if (!source.empty() && std::filesystem::exists(source, ec))
    source = std::filesystem::weakly_canonical(source, ec).string();
  const auto records = records_from_envelope(envelope, o.machine_id, source, "");
  std::vector<std::int64_t> ids;
  for (const auto& r : records)
    if (const auto id = store.record(r)) ids.push_back(*id);
  if (o.json) return;
  if (ids.size() == 1)
    ctx.out << fmt::format("recorded: history record {} of machine '{}' in {}\n", ids[0], o.machine_id,
                           store.connection().name());
  else
    ctx.out << fmt::format("recorded: {} history records of machine '{}' in {}\n", ids.size(), o.machine_id,
                           store.connection().name());
}

}  // namespace tunekit::calibration
