// tunekit history import: archived run directories, result files and batch summaries into the
// history database, each result once (a second import of the same archive adds nothing).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>
#include <regex>
#include <set>
#include <sstream>

#include <fmt/format.h>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/commands/history_command.hpp"
#include "tunekit/calibration/results/history_record.hpp"
#include "tunekit/calibration/results/results_json.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/history/store.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/core/file_bytes.hpp"

#include "history_common.hpp"

namespace tunekit::calibration {
namespace history_cmd {
namespace {

namespace fs = std::filesystem;

// "calibrate-20261123-014501" in a run directory's name is when it ran; otherwise the
// result file's modification time.
std::string hist_run_time(const fs::path& dir, const fs::path& file) {
  static const std::regex stamp(R"((\d{4})(\d{2})(\d{2})-(\d{2})(\d{2})(\d{2}))");
  std::smatch m;
  const std::string name = dir.filename().string();
  if (std::regex_search(name, m, stamp))
    return fmt::format("{}-{}-{}T{}:{}:{}.000Z", m[1].str(), m[2].str(), m[3].str(), m[4].str(), m[5].str(),
                       m[6].str());
  std::error_code ec;
  const auto ft = fs::last_write_time(file, ec);
  if (ec) return "";
  const auto sys = std::chrono::file_clock::to_sys(ft);
  const std::time_t tt = std::chrono::system_clock::to_time_t(sys);
  std::tm tm{};
  gmtime_r(&tt, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S.000Z", &tm);
  return buf;
}

struct ImportItem {
  fs::path file;                 // the JSON result
  fs::path dir;                  // its run directory (or its folder)
  fs::path root;                 // the PATH given on the command line it was found under
  bool found_in_folder = false;  // not named on the command line: skipped (and listed) when it is not a result
};

bool hist_looks_like_result(const fs::path& p) {
  std::string head;
  try {
    head = read_file_bytes(p.string()).substr(0, 4096);
  } catch (const std::exception&) {
    return false;
  }
  // Envelope keys are sorted: "command" comes first, "schema_version" after the (long) results.
  return head.find("\"command\"") != std::string::npos;
}

void hist_collect(const fs::path& root, const fs::path& dir, std::vector<ImportItem>& out) {
  if (fs::exists(dir / "results.json")) {  // a run directory: its analysis/*.json are parts of it
    out.push_back({dir / "results.json", dir, root, dir != root});
    return;
  }
  std::vector<fs::path> entries;
  for (const auto& e : fs::directory_iterator(dir)) entries.push_back(e.path());
  std::sort(entries.begin(), entries.end());
  for (const auto& e : entries) {
    if (fs::is_directory(e)) hist_collect(root, e, out);
    else if (e.extension() == ".json" && hist_looks_like_result(e)) out.push_back({e, dir, root, true});
  }
}

}  // namespace

}  // namespace history_cmd

HistoryImportOutcome compute_history_import(const HistoryOptions& a) {
  using namespace history_cmd;
  HistoryImportOutcome out;
  out.options = a;
  if (!a.machine_id.empty() && a.machine_from_path)
    throw InputError("give either --machine-id or --machine-from-path, not both");
  if (!a.machine_id.empty()) history::check_machine_id(a.machine_id);
  std::vector<ImportItem> items;
  for (const auto& p : a.paths) {
    const fs::path path(p);
    if (!fs::exists(path)) throw InputError("no such file or directory", p);
    if (fs::is_directory(path)) hist_collect(path, path, items);
    else items.push_back({path, path.parent_path(), path.parent_path()});
  }
  if (items.empty())
    throw InputError("no tunekit results found (run directories with results.json, or result JSON files)");
  history::Store store(hist_db_of(a));
  out.db = store.connection().name();
  for (const auto& it : items) {
    std::string machine = a.machine_id;
    if (machine.empty() && a.machine_from_path) {
      // archive/<machine>/...: the first folder under the PATH given.
      const auto rel = fs::relative(it.dir, it.root);
      machine = rel.empty() || rel == "." ? it.root.filename().string() : rel.begin()->string();
    }
    if (machine.empty())
      throw InputError(
          "whose results are these? give --machine-id NAME, or --machine-from-path for archive/<machine>/...",
          it.file.string());
    const std::string source = fs::weakly_canonical(it.file.filename() == "results.json" ? it.dir : it.file).string();
    std::vector<history::NewRecord> records;
    try {
      const nlohmann::json envelope = read_json_file(it.file.string());
      records = records_from_envelope(envelope, machine, source, hist_run_time(it.dir, it.file));
    } catch (const InputError& e) {
      if (!it.found_in_folder) throw;
      // A syntax error keeps its line and column.
      const std::string at = it.file.string() + ":";
      const bool located = e.location().rfind(at, 0) == 0;
      out.entries.push_back(
          {source, "skipped", located ? e.location() + ": " + e.message() : e.message(), "", "", std::nullopt});
      continue;
    }
    for (auto& r : records) {
      r.deduplicate = true;  // importing an archive twice adds nothing
      const auto id = store.record(r);
      out.entries.push_back({r.source, id ? "imported" : "already recorded", "", machine, r.command, id});
      (id ? out.imported : out.already_recorded)++;
    }
  }
  return out;
}

Envelope to_envelope(const HistoryImportOutcome& o) {
  const auto& a = o.options;
  Envelope env("history import");
  env.set_options(
      {{"db", o.db}, {"paths", a.paths}, {"machine_id", a.machine_id}, {"machine_from_path", a.machine_from_path}});
  nlohmann::json list = nlohmann::json::array();
  for (const auto& e : o.entries) {
    if (e.status == "skipped") {
      list.push_back({{"source", e.source}, {"status", e.status}, {"reason", e.reason}});
      continue;
    }
    list.push_back({{"source", e.source},
                    {"machine_id", e.machine_id},
                    {"command", e.command},
                    {"record_id", e.record_id ? nlohmann::json(*e.record_id) : nlohmann::json(nullptr)},
                    {"status", e.status}});
  }
  env.results()["records"] = list;
  env.results()["counts"] = {{"imported", o.imported}, {"already_recorded", o.already_recorded}};
  return env;
}

void print_text(const HistoryImportOutcome& o, std::ostream& os) {
  for (const auto& e : o.entries) {
    if (e.status == "skipped") os << fmt::format("{:<16} {} ({})\n", "skipped", e.source, e.reason);
    else os << fmt::format("{:<16} {} ({}, {})\n", e.status, e.source, e.machine_id, e.command);
  }
  os << fmt::format("{} imported, {} already recorded\n", o.imported, o.already_recorded);
}

}  // namespace tunekit::calibration
