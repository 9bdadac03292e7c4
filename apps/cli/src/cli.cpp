#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/option_binding.hpp"
#include "tunekit/calibration/results/history_record.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/json_error_text.hpp"
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

// The long options ("--name") of the program and of each command and subcommand the words of
// `args` from `cmd_at` on name ("history", then "trend"), and that path ("history trend").
std::pair<std::vector<std::string>, std::string> cli_long_options(CLI::App& app, const std::vector<std::string>& args,
                                                                  std::size_t cmd_at) {
  std::vector<std::string> longs;
  const auto add = [&longs](const CLI::App* a) {
    for (const auto* o : a->get_options())
      for (const auto& l : o->get_lnames()) longs.push_back("--" + l);
  };
  add(&app);
  CLI::App* cur = &app;
  std::string path;
  for (std::size_t i = cmd_at; i < args.size() && args[i] != "--"; ++i) {
    if (args[i].empty() || args[i][0] == '-') continue;
    for (auto* s : cur->get_subcommands([](const CLI::App*) { return true; }))
      if (s->get_name() == args[i]) {
        cur = s;
        path += (path.empty() ? "" : " ") + args[i];
        add(s);
        break;
      }
  }
  return {longs, path};
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
  const auto [longs, path] = cli_long_options(app, args, cmd_at);
  for (std::size_t i = cmd_at + 1; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--") break;
    if (a.size() < 3 || a.rfind("--", 0) != 0 || cli_is_number(a)) continue;
    const std::string name = a.substr(0, a.find('='));
    if (std::find(longs.begin(), longs.end(), name) != longs.end()) continue;
    const std::string near = cli_nearest(name, longs);
    return fmt::format("unknown option '{}' for 'tunekit {}'{}; 'tunekit {} --help' lists its options", name, path,
                       near.empty() ? std::string() : fmt::format("; did you mean '{}'?", near), path);
  }
  return {};
}

// The command the arguments name ("step", "history trend") and its CLI11 App, for a
// "run 'tunekit X --help'" hint; the path is "" when they name none.
std::pair<const CLI::App*, std::string> cli_named_command(CLI::App& app, const std::vector<std::string>& args) {
  CLI::App* cur = &app;
  std::string path;
  for (const auto& a : args) {
    if (a.empty() || a[0] == '-') continue;
    for (auto* s : cur->get_subcommands([](const CLI::App*) { return true; }))
      if (s->get_name() == a) {
        cur = s;
        path += (path.empty() ? "" : " ") + a;
        break;
      }
  }
  return {cur, path};
}

// What a value of an option's CLI11 type name is ("INT" -> "a whole number").
std::string cli_value_kind(const CLI::App& app, const std::string& option) {
  const CLI::Option* o = app.get_option_no_throw(option);
  const std::string type = o != nullptr ? o->get_type_name() : std::string();
  if (type == "INT" || type == "UINT") return "a whole number";
  if (type == "FLOAT" || type == "NUMBER") return "a number";
  return "a value this option accepts";
}

// The text after `prefix` in `s`, or nullopt.
std::optional<std::string> cli_after(const std::string& s, const std::string& prefix) {
  if (s.rfind(prefix, 0) != 0) return std::nullopt;
  return s.substr(prefix.size());
}

// The text before `suffix` in `s` when `s` ends with it, or nullopt.
std::optional<std::string> cli_before(const std::string& s, const std::string& suffix) {
  if (s.size() < suffix.size() || s.compare(s.size() - suffix.size(), suffix.size(), suffix) != 0) return std::nullopt;
  return s.substr(0, s.size() - suffix.size());
}

// A positional's name as the help shows it ("file" -> "FILE").
std::string cli_upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

// CLI11's error (CLI11 2.1, CLI/Error.hpp wordings) in plain words, without a hint.
std::string cli_plain_parse_error(const CLI::ParseError& e, const CLI::App& command) {
  const std::string what = e.what();
  if (what == "A subcommand is required") return "no command given";
  if (auto name = cli_before(what, " is required"); name && !name->empty() && name->front() != '-')
    return fmt::format("the {} argument is missing", cli_upper(*name));  // a positional: "file is required"
  if (auto rest = cli_after(what, "Could not convert: ")) {
    // "Could not convert: --jobs = abc"
    const auto eq = rest->find(" = ");
    if (eq != std::string::npos)
      return fmt::format("{}: '{}' is not {}", rest->substr(0, eq), rest->substr(eq + 3),
                         cli_value_kind(command, rest->substr(0, eq)));
  }
  if (auto rest = cli_after(what, "The following argument was not expected: "))
    return "unexpected argument '" + *rest + "'";
  if (auto rest = cli_after(what, "The following arguments were not expected: "))
    return "unexpected arguments '" + *rest + "'";
  if (dynamic_cast<const CLI::ArgumentMismatch*>(&e) != nullptr && what.find(" required ") != std::string::npos &&
      what.find(" missing") != std::string::npos)
    return fmt::format("{} needs a value", what.substr(0, what.find(':')));  // "--time: 1 required TEXT missing"
  if (auto rest = cli_after(what, "Exactly 1 option from ")) return "give exactly one of " + *rest;
  if (auto rest = cli_after(what, "At least 1 option from ")) return "give at least one of " + *rest;
  if (dynamic_cast<const CLI::ExcludesError*>(&e) != nullptr) {
    const auto at = what.find(" excludes ");
    if (at != std::string::npos)
      return fmt::format("{} cannot be used with {}", what.substr(0, at), what.substr(at + 10));
  }
  if (dynamic_cast<const CLI::RequiresError*>(&e) != nullptr) {
    const auto at = what.find(" requires ");
    if (at != std::string::npos) return fmt::format("{} needs {}", what.substr(0, at), what.substr(at + 10));
  }
  return what;  // "--time is required", "--jobs: Value -1 not in range ..."
}

// Every command and what adds it to the command line, in the order the help lists them.
using RegisterCommand = void (*)(CLI::App&, CliContext&);
constexpr std::pair<std::string_view, RegisterCommand> kCommands[] = {
    {"step", register_step},           {"freq", register_freq},
    {"rheo", register_rheo},           {"nozzle", register_nozzle},
    {"resonance", register_resonance}, {"shaper", register_shaper},
    {"linewidth", register_linewidth}, {"run", register_run},
    {"export", register_export},       {"calibrate", register_calibrate},
    {"report", register_report},       {"batch", register_batch},
    {"ports", register_ports},         {"inspect", register_inspect},
    {"history", register_history},     {"belts", register_belts},
    {"delta", register_delta},         {"overshoot", register_overshoot},
    {"profile", register_profile},     {"thermal", register_thermal}};

// The command the arguments run, when their first word names one and no help or version is
// asked for: only that command's options are then built (building all twenty commands' options
// is about a millisecond of every start). Empty otherwise: the help, and the messages for a
// word that names no command, need every command.
std::string_view cli_sole_command(const std::vector<std::string>& args) {
  for (const auto& a : args)
    if (a == "--help" || a == "-h" || a == "--version") return {};
  for (const auto& a : args) {
    if (a.empty() || a[0] == '-') continue;
    for (const auto& c : kCommands)
      if (c.first == a) return c.first;
    return {};
  }
  return {};
}

// "tunekit: error: WHAT; run 'tunekit CMD --help' for its usage": one line, like every other
// error of the tool, instead of CLI11's two lines.
std::string cli_parse_error_line(const CLI::ParseError& e, CLI::App& app, const std::vector<std::string>& args) {
  const auto [command, path] = cli_named_command(app, args);
  const std::string hint =
      path.empty() ? "'tunekit --help' lists the commands" : fmt::format("run 'tunekit {} --help' for its usage", path);
  return fmt::format("tunekit: error: {}; {}", cli_plain_parse_error(e, *command), hint);
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

void add_feed_track_option(CLI::App* sub, std::string& target) {
  sub->add_option(
      "--feed-track", target,
      "With --input: the commanded feed on its own instants (CSV: time (s), feed; calibrate writes "
      "feed_track.csv beside each load-cell record), aligned with the input column's window means; it "
      "drives the whole-record model where it matches them (default: feed_track.csv beside the log when there "
      "is one, else the input column)");
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
      "Exit codes: 0 ok, 1 fit failed or requirement unmet, 2 usage or bad input, 3 machine failure;\n"
      "130, 143, 129: a run stopped by SIGINT, SIGTERM, SIGHUP (machine stopped, heaters off); 141: the\n"
      "reader of stdout went away (SIGPIPE, as for `tunekit ... | head`), after the files were written.\n"
      "Run 'tunekit COMMAND --help' for a command's options and examples.");

  const std::string_view sole = cli_sole_command(args);
  for (const auto& [name, add] : kCommands)
    if (sole.empty() || name == sole) add(app, ctx);

  try {
    std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 parses from the back
    app.parse(reversed);
  } catch (const CLI::ParseError& e) {
    // CLI11 has no suggestions of its own ("A subcommand is required" for `tunekit stpe`); and
    // `tunekit thermal --help` names no command: an error, not the main help with exit 0.
    const std::string typo = cli_typo_message(app, args);
    if (!typo.empty() && (e.get_exit_code() != 0 || typo.rfind("unknown command", 0) == 0)) {
      err << "tunekit: error: " << typo << "\n";
      return static_cast<int>(ExitCode::bad_input);
    }
    if (e.get_exit_code() == 0) return app.exit(e, out, err);  // --help, --version
    err << cli_parse_error_line(e, app, args) << "\n";
    return static_cast<int>(ExitCode::bad_input);
  } catch (const Error& e) {
    err << e.formatted() << "\n";
    return static_cast<int>(e.code());
  } catch (const std::bad_alloc&) {
    err << "tunekit: error: out of memory\n";
    return static_cast<int>(ExitCode::bad_input);
  } catch (const std::filesystem::filesystem_error& e) {
    // A read-only place, a name too long, a missing directory: the condition in plain words.
    err << "tunekit: error: " << core::plain_filesystem_error(e.what()) << "\n";
    return static_cast<int>(ExitCode::bad_input);
  } catch (const std::exception& e) {
    // A JSON library error that escaped is told in plain words, never in the library's text.
    err << "tunekit: error: internal error: " << core::plain_json_error(e.what()) << "\n";
    return static_cast<int>(ExitCode::fit_failed);
  }
  return g_exit_code;
}

}  // namespace tunekit::cli
