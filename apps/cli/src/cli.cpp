#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/option_binding.hpp"
#include "tunekit/calibration/history_record.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/version.hpp"

namespace tunekit::cli {

using namespace calibration;

namespace {
thread_local int g_exit_code = 0;  // per thread: batch runs commands in parallel

// Optimal-string-alignment distance (Levenshtein with adjacent transpositions): "stpe" is one
// edit from "step".
std::size_t cli_edit_distance(const std::string& a, const std::string& b) {
  const std::size_t n = a.size(), m = b.size();
  std::vector<std::vector<std::size_t>> d(n + 1, std::vector<std::size_t>(m + 1));
  for (std::size_t i = 0; i <= n; ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= m; ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= n; ++i)
    for (std::size_t j = 1; j <= m; ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[n][m];
}

// The candidate nearest to `word` when it is close enough to be a typo, else "".
std::string cli_nearest(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_d = std::numeric_limits<std::size_t>::max();
  for (const auto& c : candidates) {
    const std::size_t dist = cli_edit_distance(word, c);
    if (dist < best_d) {
      best_d = dist;
      best = c;
    }
  }
  const std::size_t limit = std::max<std::size_t>(1, std::min<std::size_t>(3, word.size() / 3));
  return best_d <= limit ? best : std::string();
}

bool cli_is_number(const std::string& s) {
  char* end = nullptr;
  std::strtod(s.c_str(), &end);
  return !s.empty() && end == s.c_str() + s.size();
}

// "unknown command 'stpe'; did you mean 'step'?" for a first word that names no command, or
// the same for an option the command does not have; empty when the arguments look fine.
std::string cli_typo_message(CLI::App& app, const std::vector<std::string>& args) {
  std::size_t cmd_at = args.size();
  for (std::size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--help" || args[i] == "-h" || args[i] == "--version") return {};
    if (!args[i].empty() && args[i][0] != '-') {
      cmd_at = i;
      break;
    }
  }
  if (cmd_at == args.size()) return {};
  const std::string& cmd = args[cmd_at];
  CLI::App* sub = nullptr;
  std::vector<std::string> names;
  for (auto* s : app.get_subcommands([](const CLI::App*) { return true; })) {
    names.push_back(s->get_name());
    if (s->get_name() == cmd) sub = s;
  }
  if (!sub) {
    const std::string near = cli_nearest(cmd, names);
    return fmt::format("unknown command '{}'{}; 'tunekit --help' lists the commands", cmd,
                       near.empty() ? std::string() : fmt::format("; did you mean '{}'?", near));
  }
  std::vector<std::string> longs;
  for (const auto* o : sub->get_options())
    for (const auto& l : o->get_lnames()) longs.push_back("--" + l);
  for (const auto* o : app.get_options())
    for (const auto& l : o->get_lnames()) longs.push_back("--" + l);
  for (std::size_t i = cmd_at + 1; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--") break;
    if (a.size() < 3 || a.rfind("--", 0) != 0 || cli_is_number(a)) continue;
    const std::string name = a.substr(0, a.find('='));
    if (std::find(longs.begin(), longs.end(), name) != longs.end()) continue;
    const std::string near = cli_nearest(name, longs);
    return fmt::format("unknown option '{}' for 'tunekit {}'{}; 'tunekit {} --help' lists its options", name, cmd,
                       near.empty() ? std::string() : fmt::format("; did you mean '{}'?", near), cmd);
  }
  return {};
}

}  // namespace

void set_exit_code(int code) { g_exit_code = code; }

static void add_record_options(CLI::App* sub, OutputOptions& o) {
  sub->add_flag("--record", o.record,
                "Also store the result in the calibration history (with --machine-id; see 'tunekit history')");
  sub->add_option("--machine-id", o.machine_id, "Which machine the result belongs to (history records)");
  sub->add_option("--db", o.db,
                  fmt::format("History database: a SQLite file or postgresql://user@host:port/dbname (default: "
                              "$TUNEKIT_HISTORY_DB, else {})",
                              kDefaultHistoryDb));
}

void add_output_options(CLI::App* sub, OutputOptions& o, bool recordable) {
  sub->add_flag("--json", o.json, "Print the results as JSON on stdout");
  // The long name is --json-file: --output names the output column in step and freq.
  sub->add_option("-o,--json-file", o.output_path, "Also write the JSON results to this file");
  sub->add_option("--require", o.require,
                  "CI threshold on a result, e.g. 'tau_s<0.6' or 'x.freq_hz>=35' (repeatable); exit 1 naming each "
                  "unmet one");
  if (recordable) add_record_options(sub, o);
}

CLI::App* add_reserved_command(CLI::App& app, const std::string& name, const std::string& description) {
  auto* sub = app.add_subcommand(name, description + " [not in this build yet]");
  sub->allow_extras();
  sub->callback([name] { throw InputError("'tunekit " + name + "' is not available in this build yet"); });
  return sub;
}

int run_cli(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  CliContext ctx{out, err};
  ctx.interactive = ::isatty(STDERR_FILENO) != 0;
  g_exit_code = 0;
  CLI::App app{
      "tunekit: system identification and calibration for extrusion 3D printers.\n"
      "Fits liquefier dynamics, melt rheology and axis resonances, and exports pressure advance\n"
      "and input shaper settings to Marlin, Klipper and RepRapFirmware.",
      "tunekit"};
  app.set_version_flag("--version", std::string("tunekit ") + core::kVersion);
  app.add_flag("-v,--verbose", ctx.verbosity, "More output on stderr (repeat for more)");
  app.require_subcommand(1);
  app.fallthrough();
  app.footer(
      "Exit codes: 0 ok, 1 fit failed or requirement unmet, 2 usage or bad input, 3 machine failure.\n"
      "Run 'tunekit COMMAND --help' for a command's options and examples.");

  register_step(app, ctx);
  register_freq(app, ctx);
  register_rheo(app, ctx);
  register_nozzle(app, ctx);
  register_resonance(app, ctx);
  register_shaper(app, ctx);
  register_linewidth(app, ctx);
  register_run(app, ctx);
  register_export(app, ctx);
  register_calibrate(app, ctx);
  register_report(app, ctx);
  register_batch(app, ctx);
  register_ports(app, ctx);
  register_inspect(app, ctx);
  register_history(app, ctx);
  register_belts(app, ctx);
  register_delta(app, ctx);
  register_overshoot(app, ctx);

  try {
    std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 parses from the back
    app.parse(reversed);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() != 0) {
      // CLI11 has no suggestions of its own ("A subcommand is required" for `tunekit stpe`).
      const std::string typo = cli_typo_message(app, args);
      if (!typo.empty()) {
        err << "tunekit: error: " << typo << "\n";
        return static_cast<int>(ExitCode::bad_input);
      }
    }
    const int code = app.exit(e, out, err);
    return code == 0 ? 0 : static_cast<int>(ExitCode::bad_input);
  } catch (const Error& e) {
    err << e.formatted() << "\n";
    return static_cast<int>(e.code());
  } catch (const std::bad_alloc&) {
    err << "tunekit: error: out of memory\n";
    return static_cast<int>(ExitCode::bad_input);
  } catch (const std::exception& e) {
    err << "tunekit: error: internal error: " << e.what() << "\n";
    return static_cast<int>(ExitCode::fit_failed);
  }
  return g_exit_code;
}

}  // namespace tunekit::cli
