#include <unistd.h>

#include <algorithm>
#include <iostream>

#include "tunekit/cli/commands.hpp"
#include "tunekit/fitting/error.hpp"

#ifndef TUNEKIT_VERSION
#define TUNEKIT_VERSION "0.0.0"
#endif

namespace tunekit::cli {
namespace {
thread_local int g_exit_code = 0;  // per thread: batch runs commands in parallel
}

void set_exit_code(int code) { g_exit_code = code; }

void add_output_options(CLI::App* sub, OutputOptions& o) {
  sub->add_flag("--json", o.json, "Print the results as JSON on stdout");
  // The long name is --json-file: --output names the output column in step and freq.
  sub->add_option("-o,--json-file", o.output_path, "Also write the JSON results to this file");
  sub->add_option("--require", o.require,
                   "CI threshold on a result, e.g. 'tau_s<0.6' or 'x.freq_hz>=35' (repeatable); exit 1 naming each "
                   "unmet one");
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
  CLI::App app{"tunekit: system identification and calibration for extrusion 3D printers.\n"
               "Fits liquefier dynamics, melt rheology and axis resonances, and exports pressure advance\n"
               "and input shaper settings to Marlin, Klipper and RepRapFirmware.",
               "tunekit"};
  app.set_version_flag("--version", "tunekit " TUNEKIT_VERSION);
  app.add_flag("-v,--verbose", ctx.verbosity, "More output on stderr (repeat for more)");
  app.require_subcommand(1);
  app.fallthrough();
  app.footer("Exit codes: 0 ok, 1 fit failed or requirement unmet, 2 usage or bad input, 3 machine failure.\n"
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
  register_overshoot(app, ctx);

  try {
    std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 parses from the back
    app.parse(reversed);
  } catch (const CLI::ParseError& e) {
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
