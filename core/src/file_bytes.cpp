#include "tunekit/core/file_bytes.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit {
namespace {

/// What a non-regular file is, for the message refusing it.
const char* file_kind(mode_t m) {
  if (S_ISDIR(m)) return "a directory";
  if (S_ISFIFO(m)) return "a FIFO (named pipe)";
  if (S_ISCHR(m)) return "a character device";
  if (S_ISBLK(m)) return "a block device";
  if (S_ISSOCK(m)) return "a socket";
  return "not a regular file";
}

class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

[[noreturn]] void too_large(const std::string& path, std::uint64_t max_bytes) {
  throw InputError(
      fmt::format("the file is larger than {} bytes, the most tunekit reads from a file of this kind", max_bytes),
      path);
}

/// Reads up to `max_bytes` bytes; with `whole`, more is an error, else the rest is left unread.
std::string read_checked(const std::string& path, std::uint64_t max_bytes, bool whole) {
  // O_NONBLOCK: opening a FIFO must not wait for a writer before it can be refused.
  const Fd fd(::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC));
  if (fd.get() < 0) throw InputError(fmt::format("cannot open: {}", std::strerror(errno)), path);
  struct stat st {};
  if (::fstat(fd.get(), &st) != 0) throw InputError(fmt::format("cannot read: {}", std::strerror(errno)), path);
  if (!S_ISREG(st.st_mode))
    throw InputError(fmt::format("cannot read it: it is {}, not a regular file", file_kind(st.st_mode)), path);
  const auto size = static_cast<std::uint64_t>(st.st_size);
  if (whole && size > max_bytes) too_large(path, max_bytes);
  std::string data;
  data.reserve(static_cast<std::size_t>(std::min(size, max_bytes)));
  char buf[1 << 16];
  for (;;) {
    const std::uint64_t room = max_bytes + (whole ? 1 : 0) - data.size();  // one more byte tells "too large"
    if (room == 0) break;
    const ssize_t n = ::read(fd.get(), buf, static_cast<std::size_t>(std::min<std::uint64_t>(sizeof buf, room)));
    if (n < 0) {
      if (errno == EINTR) continue;
      throw InputError(fmt::format("read error: {}", std::strerror(errno)), path);
    }
    if (n == 0) break;
    data.append(buf, static_cast<std::size_t>(n));
  }
  if (data.size() > max_bytes) too_large(path, max_bytes);
  return data;
}

}  // namespace

std::string read_file_bytes(const std::string& path, std::uint64_t max_bytes) {
  return read_checked(path, max_bytes, true);
}

std::string read_file_head(const std::string& path, std::uint64_t max_bytes) {
  return read_checked(path, max_bytes, false);
}

bool same_file(const std::string& a, const std::string& b) {
  namespace fs = std::filesystem;
  std::error_code ea, eb;
  if (fs::exists(a, ea) && fs::exists(b, eb)) return fs::equivalent(a, b, ea) && !ea;
  const fs::path pa = fs::weakly_canonical(a, ea), pb = fs::weakly_canonical(b, eb);
  return !ea && !eb && pa == pb;
}

}  // namespace tunekit
