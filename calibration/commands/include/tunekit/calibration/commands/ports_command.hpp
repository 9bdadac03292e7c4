#pragma once
// tunekit ports as a function: the serial ports libserialport sees (pseudo-terminals such as
// Klipper's /tmp/printer are not serial ports and are not listed). The shape of a command is
// described in docs/cpp-api.md.

#include <ostream>
#include <vector>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/machine/serial_transport.hpp"

namespace tunekit::calibration {

struct PortsOptions {};  ///< nothing to choose

struct PortsOutcome {
  std::vector<machine::SerialPortInfo> ports;  ///< path, description, transport, USB ids, serial number
};

PortsOutcome compute_ports(const PortsOptions& options);

Envelope to_envelope(const PortsOutcome& outcome);
void print_text(const PortsOutcome& outcome, std::ostream& os);

}  // namespace tunekit::calibration
