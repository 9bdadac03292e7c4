// tunekit ports: the command line of the command (options bound straight into the library's
// option structs, so --help shows the library's defaults); the work is done by the
// calibration library's compute function.

#include "tunekit/cli/command.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/cli/option_binding.hpp"
#include "tunekit/calibration/commands/ports_command.hpp"
#include "tunekit/machine/serial_transport.hpp"
#include <fmt/format.h>
#include <memory>

namespace tunekit::cli {

using namespace calibration;

namespace {

struct PortsCommand {
  PortsOptions options;
  OutputOptions output;
};

}  // namespace

void register_ports(CLI::App& app, CliContext& ctx) {
  auto cmd = std::make_shared<PortsCommand>();
  auto* sub = app.add_subcommand("ports", "List serial ports");
  add_output_options(sub, cmd->output);
  sub->footer(
      "Pseudo-terminals (Klipper's /tmp/printer, tunekit-sim's link) are not serial ports and are not\n"
      "listed; give them to 'tunekit run --port' directly.\n"
      "Examples:\n"
      "  tunekit ports\n"
      "  tunekit ports --json");
  sub->callback([cmd, &ctx] { set_exit_code(report_outcome(compute_ports(cmd->options), cmd->output, ctx)); });
}

}  // namespace tunekit::cli
