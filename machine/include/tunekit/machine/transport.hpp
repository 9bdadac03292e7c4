#pragma once
// Byte transports to a machine, behind one interface: POSIX file descriptors (tty devices and
// pseudo-terminals through termios, Unix-domain sockets, in-process socket pairs) and real
// serial ports through libserialport (serial_transport.hpp). Every failure (cannot open, write
// error, disconnect) is a MachineError (exit code 3).

#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

namespace tunekit::machine {

class Transport {
 public:
  virtual ~Transport() = default;
  /// Writes all bytes; throws MachineError on failure or disconnect.
  virtual void write(std::string_view bytes) = 0;
  /// Reads what is available, waiting at most `timeout`. Returns an empty string on timeout;
  /// throws MachineError when the other side has gone (EOF, hang-up, I/O error).
  virtual std::string read_some(std::chrono::milliseconds timeout) = 0;
  /// A human-readable name: the device path or socket path.
  virtual std::string describe() const = 0;
  virtual void close() = 0;
};

/// Splits a transport's byte stream into lines (`\n`, `\r\n` or `\r` endings) or into
/// frames ended by any single delimiter byte (0x03 for Klipper's API server).
class LineReader {
 public:
  explicit LineReader(Transport& t, char delimiter = '\n') : t_(t), delim_(delimiter) {}
  /// The next complete line without its ending, or nullopt if none arrived within `timeout`.
  std::optional<std::string> next(std::chrono::milliseconds timeout);
  /// Lines already buffered (no waiting).
  std::optional<std::string> buffered();
  Transport& transport() { return t_; }

 private:
  Transport& t_;
  char delim_;
  std::string buf_;
  std::size_t pos_ = 0;
};

/// A transport over an open file descriptor (owned, closed on destruction).
class FdTransport : public Transport {
 public:
  FdTransport(int fd, std::string name);
  ~FdTransport() override;
  FdTransport(const FdTransport&) = delete;
  FdTransport& operator=(const FdTransport&) = delete;
  void write(std::string_view bytes) override;
  std::string read_some(std::chrono::milliseconds timeout) override;
  std::string describe() const override { return name_; }
  void close() override;
  int fd() const { return fd_; }

 private:
  int fd_;
  std::string name_;
  bool is_socket_ = false;  ///< written with send(MSG_NOSIGNAL): a closed peer is EPIPE, not SIGPIPE
};

/// Opens a tty device or pseudo-terminal slave (e.g. Klipper's /tmp/printer or tunekit-sim's
/// link) in raw mode (no echo, no line editing, 8N1) at `baud` (ignored by PTYs).
std::unique_ptr<Transport> open_tty(const std::string& path, int baud = 250000);

/// Connects to a Unix-domain stream socket (Klipper's API server, e.g. /tmp/klippy_uds).
std::unique_ptr<Transport> connect_unix_socket(const std::string& path);

/// A connected in-process pair (socketpair): what one side writes the other reads.
std::pair<std::unique_ptr<Transport>, std::unique_ptr<Transport>> make_transport_pair();

/// True if `path` (after following symlinks) is a pseudo-terminal slave (/dev/pts/N).
bool is_pseudo_terminal(const std::string& path);

}  // namespace tunekit::machine
