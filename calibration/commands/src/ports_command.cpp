// tunekit ports: list the serial ports libserialport sees (pseudo-terminals such as Klipper's
// /tmp/printer are not serial ports and are not listed; pass them to --port directly).
#include <memory>

#include <fmt/format.h>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/commands/ports_command.hpp"
#include "tunekit/machine/serial_transport.hpp"

namespace tunekit::calibration {

PortsOutcome compute_ports(const PortsOptions&) { return {machine::list_serial_ports()}; }

Envelope to_envelope(const PortsOutcome& o) {
  Envelope env("ports");
  nlohmann::json list = nlohmann::json::array();
  for (const auto& p : o.ports) {
    nlohmann::json j{{"path", p.path}, {"description", p.description}, {"transport", p.transport}};
    if (p.usb_vid >= 0) {
      j["usb_vid"] = fmt::format("{:04x}", p.usb_vid);
      j["usb_pid"] = fmt::format("{:04x}", p.usb_pid);
    }
    if (!p.serial_number.empty()) j["serial_number"] = p.serial_number;
    list.push_back(j);
  }
  env.results()["ports"] = list;
  return env;
}

void print_text(const PortsOutcome& o, std::ostream& os) {
  if (o.ports.empty()) os << "no serial ports found\n";
  for (const auto& p : o.ports)
    os << fmt::format("{:<20} {:<10} {}{}\n", p.path, p.transport, p.description,
                      p.usb_vid >= 0 ? fmt::format(" [{:04x}:{:04x}]", p.usb_vid, p.usb_pid) : "");
}

}  // namespace tunekit::calibration
