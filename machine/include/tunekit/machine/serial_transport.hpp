#pragma once
// Real serial devices (USB CDC, FTDI, CH340...) through libserialport. libserialport refuses
// pseudo-terminals by design; use open_tty() (transport.hpp) for those.

#include <memory>
#include <string>
#include <vector>

#include "tunekit/machine/transport.hpp"

namespace tunekit::machine {

struct SerialPortInfo {
  std::string path;         ///< e.g. /dev/ttyACM0
  std::string description;  ///< product string when known
  std::string transport;    ///< usb, native, bluetooth
  int usb_vid = -1;
  int usb_pid = -1;
  std::string serial_number;
};

/// Lists the serial ports libserialport can see (empty when there are none).
std::vector<SerialPortInfo> list_serial_ports();

/// Opens a serial port at `baud` 8N1 without flow control; MachineError if it cannot.
std::unique_ptr<Transport> open_serial(const std::string& path, int baud);

/// Opens `path` with the right transport: "unix:PATH" is a Unix socket, a pseudo-terminal
/// goes through termios, anything else through libserialport (falling back to termios).
std::unique_ptr<Transport> open_transport(const std::string& path, int baud);

}  // namespace tunekit::machine
