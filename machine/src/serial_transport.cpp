#include "tunekit/machine/serial_transport.hpp"

#include <libserialport.h>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::machine {
namespace {

std::string sp_error_text() {
  char* msg = sp_last_error_message();
  std::string s = msg ? msg : "unknown error";
  sp_free_error_message(msg);
  return s;
}

class SerialTransport : public Transport {
 public:
  SerialTransport(sp_port* port, std::string path) : port_(port), path_(std::move(path)) {}
  ~SerialTransport() override { close(); }
  SerialTransport(const SerialTransport&) = delete;
  SerialTransport& operator=(const SerialTransport&) = delete;

  void write(std::string_view bytes) override {
    if (!port_) throw MachineError("the connection is closed", path_);
    const auto r = sp_blocking_write(port_, bytes.data(), bytes.size(), 5000);
    if (r < 0) throw MachineError(fmt::format("write failed: {}", sp_error_text()), path_);
    if (static_cast<std::size_t>(r) != bytes.size()) throw MachineError("write timed out", path_);
  }

  std::string read_some(std::chrono::milliseconds timeout) override {
    if (!port_) throw MachineError("the connection is closed", path_);
    char buf[4096];
    // Wait for the first byte, then take whatever else is already there.
    auto r = sp_blocking_read_next(port_, buf, 1, static_cast<unsigned>(std::max<long long>(1, timeout.count())));
    if (r < 0) throw MachineError(fmt::format("read failed: {} (unplugged?)", sp_error_text()), path_);
    if (r == 0) return {};
    std::string out(buf, 1);
    r = sp_nonblocking_read(port_, buf, sizeof buf);
    if (r < 0) throw MachineError(fmt::format("read failed: {} (unplugged?)", sp_error_text()), path_);
    out.append(buf, static_cast<std::size_t>(r));
    return out;
  }

  std::string describe() const override { return path_; }
  void close() override {
    if (port_) {
      sp_close(port_);
      sp_free_port(port_);
    }
    port_ = nullptr;
  }

 private:
  sp_port* port_;
  std::string path_;
};

}  // namespace

std::vector<SerialPortInfo> list_serial_ports() {
  std::vector<SerialPortInfo> out;
  sp_port** ports = nullptr;
  if (sp_list_ports(&ports) != SP_OK) return out;
  for (int i = 0; ports[i]; ++i) {
    SerialPortInfo info;
    sp_port* p = ports[i];
    info.path = sp_get_port_name(p);
    if (const char* d = sp_get_port_description(p)) info.description = d;
    switch (sp_get_port_transport(p)) {
      case SP_TRANSPORT_USB: {
        info.transport = "usb";
        int vid = -1, pid = -1;
        if (sp_get_port_usb_vid_pid(p, &vid, &pid) == SP_OK) {
          info.usb_vid = vid;
          info.usb_pid = pid;
        }
        if (const char* sn = sp_get_port_usb_serial(p)) info.serial_number = sn;
        break;
      }
      case SP_TRANSPORT_BLUETOOTH: info.transport = "bluetooth"; break;
      default: info.transport = "native"; break;
    }
    out.push_back(std::move(info));
  }
  sp_free_port_list(ports);
  return out;
}

std::unique_ptr<Transport> open_serial(const std::string& path, int baud) {
  sp_port* port = nullptr;
  if (sp_get_port_by_name(path.c_str(), &port) != SP_OK)
    throw MachineError(fmt::format("no such serial port: {}", sp_error_text()), path);
  if (sp_open(port, SP_MODE_READ_WRITE) != SP_OK) {
    const std::string why = sp_error_text();
    sp_free_port(port);
    throw MachineError(fmt::format("cannot open: {}", why), path);
  }
  sp_set_baudrate(port, baud);
  sp_set_bits(port, 8);
  sp_set_parity(port, SP_PARITY_NONE);
  sp_set_stopbits(port, 1);
  sp_set_flowcontrol(port, SP_FLOWCONTROL_NONE);
  return std::make_unique<SerialTransport>(port, path);
}

std::unique_ptr<Transport> open_transport(const std::string& path, int baud) {
  if (path.rfind("unix:", 0) == 0) return connect_unix_socket(path.substr(5));
  if (is_pseudo_terminal(path)) return open_tty(path, baud);
  try {
    return open_serial(path, baud);
  } catch (const MachineError&) {
    return open_tty(path, baud);  // a tty libserialport does not know (e.g. a symlink to a PTY)
  }
}

}  // namespace tunekit::machine
