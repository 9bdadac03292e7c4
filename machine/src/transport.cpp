#include "tunekit/machine/transport.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::machine {
namespace {

std::string errno_text() { return std::strerror(errno); }

speed_t baud_constant(int baud) {
  switch (baud) {
    case 9600: return B9600;
    case 19200: return B19200;
    case 38400: return B38400;
    case 57600: return B57600;
    case 115200: return B115200;
    case 230400: return B230400;
    case 460800: return B460800;
    case 500000: return B500000;
    case 921600: return B921600;
    case 1000000: return B1000000;
    default: return B115200;  // 250000 is not a POSIX constant; PTYs ignore the rate anyway
  }
}

}  // namespace

std::optional<std::string> LineReader::buffered() {
  while (pos_ < buf_.size()) {
    const auto end = buf_.find_first_of(delim_ == '\n' ? std::string_view("\r\n") : std::string_view(&delim_, 1), pos_);
    if (end == std::string::npos) break;
    std::string line = buf_.substr(pos_, end - pos_);
    pos_ = end + 1;
    if (delim_ == '\n' && line.empty()) continue;  // the '\n' of a "\r\n" pair, or a blank line
    return line;
  }
  if (pos_ > 0) {
    buf_.erase(0, pos_);
    pos_ = 0;
  }
  return std::nullopt;
}

std::optional<std::string> LineReader::next(std::chrono::milliseconds timeout) {
  if (auto l = buffered()) return l;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() < 0) return std::nullopt;
    std::string chunk = t_.read_some(left);
    if (chunk.empty()) {
      if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
      continue;
    }
    buf_ += chunk;
    if (auto l = buffered()) return l;
  }
}

FdTransport::FdTransport(int fd, std::string name) : fd_(fd), name_(std::move(name)) {
  struct stat st {};
  is_socket_ = ::fstat(fd_, &st) == 0 && S_ISSOCK(st.st_mode);
}
FdTransport::~FdTransport() { close(); }

void FdTransport::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

void FdTransport::write(std::string_view bytes) {
  if (fd_ < 0) throw MachineError("the connection is closed", name_);
  std::size_t done = 0;
  while (done < bytes.size()) {
    // A socket whose peer has gone must give EPIPE (a MachineError below), not SIGPIPE, which
    // would end the process before the journal is flushed and the safe state is sent.
    const ssize_t n = is_socket_ ? ::send(fd_, bytes.data() + done, bytes.size() - done, MSG_NOSIGNAL)
                                 : ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      if (errno == EAGAIN || errno == EWOULDBLOCK) {
        pollfd p{fd_, POLLOUT, 0};
        if (::poll(&p, 1, 5000) <= 0) throw MachineError("write timed out (the machine does not read)", name_);
        continue;
      }
      throw MachineError(fmt::format("write failed: {} (disconnected?)", errno_text()), name_);
    }
    done += static_cast<std::size_t>(n);
  }
}

std::string FdTransport::read_some(std::chrono::milliseconds timeout) {
  if (fd_ < 0) throw MachineError("the connection is closed", name_);
  pollfd p{fd_, POLLIN, 0};
  const int r = ::poll(&p, 1, static_cast<int>(std::max<long long>(0, timeout.count())));
  if (r < 0) {
    if (errno == EINTR) return {};
    throw MachineError(fmt::format("poll failed: {}", errno_text()), name_);
  }
  if (r == 0) return {};
  char buf[65536];
  const ssize_t n = ::read(fd_, buf, sizeof buf);
  if (n > 0) return std::string(buf, static_cast<std::size_t>(n));
  if (n < 0 && (errno == EINTR || errno == EAGAIN)) return {};
  if (n == 0) throw MachineError("the machine closed the connection", name_);
  throw MachineError(fmt::format("the connection was lost: {}", errno_text()), name_);
}

std::unique_ptr<Transport> open_tty(const std::string& path, int baud) {
  const int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw MachineError(fmt::format("cannot open: {}", errno_text()), path);
  termios tio{};
  if (::tcgetattr(fd, &tio) != 0) {
    ::close(fd);
    throw MachineError("not a terminal device", path);
  }
  ::cfmakeraw(&tio);
  tio.c_cflag |= CLOCAL | CREAD;
  tio.c_cflag &= ~static_cast<tcflag_t>(CRTSCTS);
  ::cfsetispeed(&tio, baud_constant(baud));
  ::cfsetospeed(&tio, baud_constant(baud));
  tio.c_cc[VMIN] = 1;
  tio.c_cc[VTIME] = 0;
  if (::tcsetattr(fd, TCSANOW, &tio) != 0) {
    ::close(fd);
    throw MachineError(fmt::format("cannot configure the terminal: {}", errno_text()), path);
  }
  return std::make_unique<FdTransport>(fd, path);
}

std::unique_ptr<Transport> connect_unix_socket(const std::string& path) {
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  if (path.size() >= sizeof addr.sun_path) throw MachineError("socket path too long", path);
  std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
  const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw MachineError(fmt::format("socket: {}", errno_text()), path);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    const std::string why = errno_text();
    ::close(fd);
    throw MachineError(fmt::format("cannot connect: {}", why), path);
  }
  return std::make_unique<FdTransport>(fd, path);
}

std::pair<std::unique_ptr<Transport>, std::unique_ptr<Transport>> make_transport_pair() {
  int fds[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0)
    throw MachineError(fmt::format("socketpair: {}", errno_text()));
  return {std::make_unique<FdTransport>(fds[0], "in-process host side"),
          std::make_unique<FdTransport>(fds[1], "in-process machine side")};
}

bool is_pseudo_terminal(const std::string& path) {
  std::error_code ec;
  const auto real = std::filesystem::canonical(path, ec);
  if (ec) return false;
  return real.string().rfind("/dev/pts/", 0) == 0 || real.string() == "/dev/ptmx";
}

}  // namespace tunekit::machine
