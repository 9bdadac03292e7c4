// tunekit batch: analyze every dataset in a folder in parallel and write one summary. Each
// file is recognized by its columns and analyzed by the command a user would run on it:
//   accel_x/accel_y/accel_z (Klipper raw) or freq,psd_x (Klipper calibration data) -> shaper
//   feed + force (a liquefier step test as tunekit run writes it)                   -> step
//   feed + force with a feed changing faster than the liquefier settles (a chirp)    -> freq
//   shear_rate + viscosity (rheometer data)                                          -> rheo
// Other files are listed as skipped with the reason. --require applies to every dataset whose
// results name the number; one that names nothing in any dataset is an error (exit 2).
#include <algorithm>
#include <atomic>
#include <filesystem>
#include <functional>
#include <fstream>
#include <memory>
#include <sstream>
#include <thread>

#include <fmt/format.h>

#include "tunekit/calibration/analyses/rheo_command.hpp"
#include "tunekit/calibration/analyses/shaper_command.hpp"
#include "tunekit/calibration/commands/batch_command.hpp"
#include "tunekit/calibration/analyses/step_command.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/results/requirements.hpp"
#include "tunekit/calibration/analyses/freq_command.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/json_error_text.hpp"
#include "tunekit/core/file_bytes.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/ident/excitation.hpp"
#include "tunekit/protocols/chirp_plan.hpp"

namespace tunekit::calibration {
namespace {

namespace fs = std::filesystem;

struct Job {
  std::string file;
  std::vector<std::string> args;      // the equivalent command line, for the summary; empty: skipped
  std::function<Envelope()> analyze;  // the command's compute(), as its envelope
  std::string skip_reason;
  int code = 0;
  std::string err;
  nlohmann::json results;
};

// The column names of a CSV file, from its first 64 KiB, with units stripped, lower case.
std::vector<std::string> sniff_columns(const std::string& path) {
  std::string head;
  try {
    head = read_file_head(path, 65536);  // a FIFO or device is not sniffed (the analysis names it)
  } catch (const Error&) {
  }
  std::istringstream in(head);
  std::string line, last_comment;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    if (line[0] == '#') {
      last_comment = line.substr(1);
      continue;
    }
    const bool numeric = line.find_first_not_of("0123456789+-.eE, \t;") == std::string::npos;
    const std::string header = numeric ? last_comment : line;
    std::vector<std::string> cols;
    std::string field;
    std::istringstream hs(header);
    while (std::getline(hs, field, ',')) {
      auto name = formats::split_name_unit(field).first;
      std::transform(name.begin(), name.end(), name.begin(),
                     [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
      cols.push_back(name);
    }
    return cols;
  }
  return {};
}

// A step test holds each feed level for several liquefier time constants; a chirp (or any
// broadband excitation) changes the level within one. Without a measurement of this liquefier,
// Bellini's literature time constant separates the two. A file that cannot be read is taken for
// a step test, whose analysis then reports what is wrong with it.
bool feed_changes_within_tau(const std::string& path) {
  try {
    const auto table = formats::read_csv(path, {{"time", "feed"}, "time"});
    const auto& t = table.column("time").values;
    const auto& u = table.column("feed").values;
    if (t.size() < 2) return false;
    return ident::typical_hold_s(t, ident::input_holds(u)) < protocols::kLiteratureLiquefierTau_s;
  } catch (const Error&) {
    return false;
  }
}

Job plan_job(const std::string& path) {
  Job j;
  j.file = path;
  const auto ext = fs::path(path).extension().string();
  if (ext != ".csv" && ext != ".CSV") {
    j.skip_reason = "not a CSV file";
    return j;
  }
  const auto cols = sniff_columns(path);
  auto has = [&](const char* c) { return std::find(cols.begin(), cols.end(), c) != cols.end(); };
  if (has("accel_x") || has("accel_y") || has("accel_z") || (has("freq") && has("psd_x"))) {
    j.args = {"shaper", path};
    j.analyze = [path] {
      ShaperOptions o;
      o.accel.files = {path};
      return to_envelope(compute_shaper(o));
    };
  } else if (has("feed") && has("force") && has("time") && feed_changes_within_tau(path)) {
    j.args = {"freq", path, "--time", "time", "--input", "feed", "--output", "force"};
    j.analyze = [path] {
      FreqOptions o;
      o.file = path;
      o.time_column = "time";
      o.input_column = "feed";
      o.output_column = "force";
      return to_envelope(compute_freq(o));
    };
  } else if (has("feed") && has("force") && has("time")) {
    j.args = {"step", path, "--time", "time", "--input", "feed", "--output", "force"};
    j.analyze = [path] {
      StepOptions o;
      o.file = path;
      o.time_column = "time";
      o.input_column = "feed";
      o.output_column = "force";
      return to_envelope(compute_step(o));
    };
  } else if (has("shear_rate") && has("viscosity")) {
    j.args = {"rheo", path};
    j.analyze = [path] {
      RheoOptions o;
      o.file = path;
      return to_envelope(compute_rheo(o));
    };
  } else {
    j.skip_reason = "no known columns (accel_x.., freq+psd_x, time+feed+force, shear_rate+viscosity)";
  }
  return j;
}

// Per requirement: whether it named a number in some dataset, and why not in the last one
// where it did not.
struct RequirementReach {
  bool named = false;
  std::string why_not;
};

// Evaluates `requirements` on a dataset analyzed without error: records each outcome in its
// summary entry `e` (not applicable where its results name no such number), prints each unmet
// one and returns the dataset's exit code (1 when one is unmet).
int apply_requirements(const Job& j, const std::vector<Requirement>& requirements, std::vector<RequirementReach>& reach,
                       nlohmann::json& e, CliContext& ctx) {
  if (requirements.empty()) return j.code;
  int code = j.code;
  nlohmann::json reqs = nlohmann::json::array();
  for (std::size_t i = 0; i < requirements.size(); ++i) {
    const auto& r = requirements[i];
    try {
      const auto o = evaluate_requirement(r, j.results);
      reach[i].named = true;
      reqs.push_back({{"expression", r.expression}, {"path", o.resolved_path}, {"value", o.value}, {"met", o.met}});
      if (!o.met) {
        code = static_cast<int>(ExitCode::fit_failed);
        ctx.err << fmt::format("tunekit: {}: requirement not met: {} ({} = {:.6g})\n", j.file, r.expression,
                               o.resolved_path, o.value);
      }
    } catch (const InputError& why) {
      reach[i].why_not = why.message();
      reqs.push_back({{"expression", r.expression}, {"applicable", false}});
    }
  }
  e["requirements"] = reqs;
  e["exit_code"] = code;
  e["status"] = code == 0 ? "ok" : "failed";
  return code;
}

// A requirement that names nothing in any dataset analyzed is a mistake in the command line
// (a typo'd path), as it is for a single command: exit 2, naming it.
void refuse_unnamed_requirements(const std::vector<RequirementReach>& reach, int analyzed) {
  if (analyzed == 0) return;  // nothing to look in: the datasets' own errors say why
  for (const auto& r : reach)
    if (!r.named) throw InputError(fmt::format("{}; it applies to no dataset ({} analyzed)", r.why_not, analyzed));
}

}  // namespace

int run_batch(const BatchArgs& a, CliContext& ctx) {
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(a.dir))
    if (e.is_regular_file()) files.push_back(e.path().string());
  std::sort(files.begin(), files.end());
  if (files.empty()) throw InputError("no files in the folder", a.dir);

  std::vector<Job> jobs;
  for (const auto& f : files) jobs.push_back(plan_job(f));
  std::vector<Requirement> requirements;
  for (const auto& r : a.output.require) requirements.push_back(parse_requirement(r));

  // Worker threads take jobs in order; each runs the command's compute() and reports it as the
  // command with --json would (the envelope on stdout, warnings and errors on stderr).
  std::atomic<std::size_t> next{0};
  auto worker = [&] {
    for (std::size_t i = next++; i < jobs.size(); i = next++) {
      Job& j = jobs[i];
      if (!j.analyze) continue;
      std::ostringstream out, err;
      CliContext job_ctx{out, err};
      try {
        OutputOptions as_json;
        as_json.json = true;
        j.code = emit(j.analyze(), as_json, job_ctx);
      } catch (const Error& e) {
        err << e.formatted() << "\n";
        j.code = static_cast<int>(e.code());
      } catch (const std::bad_alloc&) {
        err << "tunekit: error: out of memory\n";
        j.code = static_cast<int>(ExitCode::bad_input);
      } catch (const std::filesystem::filesystem_error& e) {
        err << "tunekit: error: " << core::plain_filesystem_error(e.what()) << "\n";
        j.code = static_cast<int>(ExitCode::bad_input);
      } catch (const std::exception& e) {
        // A JSON library error that escaped is told in plain words, never in the library's text.
        err << "tunekit: error: internal error: " << core::plain_json_error(e.what()) << "\n";
        j.code = static_cast<int>(ExitCode::fit_failed);
      }
      j.err = err.str();
      if (j.code == 0 || j.code == 1) {
        try {
          j.results = nlohmann::json::parse(out.str()).at("results");
        } catch (const std::exception&) {
          j.results = nullptr;
        }
      }
    }
  };
  const unsigned n = a.jobs > 0 ? a.jobs : std::max(1u, std::thread::hardware_concurrency());
  std::vector<std::thread> pool;
  for (unsigned i = 0; i < std::min<std::size_t>(n, jobs.size()); ++i) pool.emplace_back(worker);
  for (auto& t : pool) t.join();

  Envelope env("batch");
  env.set_options({{"dir", a.dir}, {"require", a.output.require}});
  nlohmann::json list = nlohmann::json::array();
  int worst = 0, ok = 0, failed = 0, bad = 0, skipped = 0, analyzed = 0;
  std::vector<RequirementReach> reach(requirements.size());
  std::string listing;  // one line per file, printed once the requirements are known to name something
  for (const auto& j : jobs) {
    env.add_input(j.file);
    nlohmann::json e{{"file", j.file}};
    if (j.args.empty()) {
      e["status"] = "skipped";
      e["reason"] = j.skip_reason;
      ++skipped;
    } else {
      e["command"] = j.args;
      e["exit_code"] = j.code;
      e["status"] = j.code == 0 ? "ok" : j.code == 1 ? "failed" : "error";
      if (!j.err.empty()) e["messages"] = j.err;
      if (!j.results.is_null()) e["results"] = j.results;
      analyzed += j.code == 0 ? 1 : 0;
      const int code = j.code == 0 ? apply_requirements(j, requirements, reach, e, ctx) : j.code;
      worst = std::max(worst, code);
      (code == 0 ? ok : code == 1 ? failed : bad)++;
    }
    list.push_back(e);
    if (!a.output.json)
      listing += fmt::format("{:<8} {}{}\n", e["status"].get<std::string>(), j.file,
                             j.args.empty() ? " (" + j.skip_reason + ")" : "");
  }
  refuse_unnamed_requirements(reach, analyzed);
  ctx.out << listing;
  env.results()["datasets"] = list;
  env.results()["counts"] = {{"ok", ok}, {"failed", failed}, {"error", bad}, {"skipped", skipped}};
  OutputOptions o = a.output;
  o.require.clear();  // applied per dataset above
  emit(env, o, ctx);
  if (worst != 0)
    ctx.err << fmt::format("tunekit: batch: {} ok, {} failed, {} with errors, {} skipped\n", ok, failed, bad, skipped);
  return worst;
}

}  // namespace tunekit::calibration
