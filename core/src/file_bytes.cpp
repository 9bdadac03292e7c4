#include "tunekit/core/file_bytes.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/core/file_open_log.hpp"
#include "tunekit/core/input_read_scope.hpp"

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
  Fd(Fd&& o) noexcept : fd_(o.fd_) { o.fd_ = -1; }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  Fd& operator=(Fd&&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

[[noreturn]] void too_large(const std::string& path, std::uint64_t max_bytes) {
  throw InputError(
      fmt::format("the file is larger than {} bytes, the most tunekit reads from a file of this kind", max_bytes),
      path);
}

/// Opens an input file for reading, the one place the file layer opens a file: recorded in the
/// live FileOpenLogs, checked to be a regular file (`st` its status).
Fd open_input(const std::string& path, struct stat& st) {
  core::FileOpenLog::record(path);
  // O_NONBLOCK: opening a FIFO must not wait for a writer before it can be refused.
  Fd fd(::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC));
  if (fd.get() < 0) throw InputError(fmt::format("cannot open: {}", std::strerror(errno)), path);
  if (::fstat(fd.get(), &st) != 0) throw InputError(fmt::format("cannot read: {}", std::strerror(errno)), path);
  if (!S_ISREG(st.st_mode))
    throw InputError(fmt::format("cannot read it: it is {}, not a regular file", file_kind(st.st_mode)), path);
  return fd;
}

/// Reads up to `max_bytes` bytes of the open file; with `whole`, more is an error, else the rest is left unread.
std::string read_open(const Fd& fd, const struct stat& st, const std::string& path, std::uint64_t max_bytes,
                      bool whole) {
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

std::string read_checked(const std::string& path, std::uint64_t max_bytes, bool whole) {
  struct stat st {};
  const Fd fd = open_input(path, st);
  return read_open(fd, st, path, max_bytes, whole);
}

}  // namespace

std::string read_file_bytes(const std::string& path, std::uint64_t max_bytes) {
  if (auto kept = core::InputReadScope::cached(path)) {
    if (kept->size() > max_bytes) too_large(path, max_bytes);
    return std::move(*kept);
  }
  std::string bytes = read_checked(path, max_bytes, true);
  core::InputReadScope::keep(path, bytes);
  return bytes;
}

std::string read_file_head(const std::string& path, std::uint64_t max_bytes) {
  if (auto kept = core::InputReadScope::cached(path)) return kept->substr(0, max_bytes);
  if (core::InputReadScope::active()) {
    // In a scope the whole file is read once and kept: what reads it next gets the same bytes.
    std::string bytes = read_checked(path, kMaxInputFileBytes, true);
    core::InputReadScope::keep(path, bytes);
    return bytes.substr(0, max_bytes);
  }
  return read_checked(path, max_bytes, false);
}

MappedFileBytes::MappedFileBytes(const std::string& path) {
  // In an InputReadScope that holds the file's bytes: those, the file not opened again.
  if (auto kept = core::InputReadScope::cached(path)) {
    copy_ = std::move(*kept);
    return;
  }
  struct stat st {};
  const Fd fd = open_input(path, st);
  if (st.st_size > 0 && static_cast<std::uint64_t>(st.st_size) <= kMaxInputFileBytes) {
    // Not MAP_POPULATE: the kernel maps a file's cached pages sixteen at a time as they are
    // first read, and for a large CSV that happens on both parsing threads at once; mapping all
    // of them up front is one more serial millisecond for a 20 MB file.
    void* p = ::mmap(nullptr, static_cast<std::size_t>(st.st_size), PROT_READ, MAP_PRIVATE, fd.get(), 0);
    if (p != MAP_FAILED) {
      map_ = static_cast<const char*>(p);
      size_ = static_cast<std::size_t>(st.st_size);
      return;
    }
  }
  copy_ = read_open(fd, st, path, kMaxInputFileBytes, true);  // empty, too large, or not mappable
}

MappedFileBytes::~MappedFileBytes() {
  if (map_ != nullptr) ::munmap(const_cast<char*>(map_), size_);
}

bool same_file(const std::string& a, const std::string& b) {
  namespace fs = std::filesystem;
  std::error_code ea, eb;
  if (fs::exists(a, ea) && fs::exists(b, eb)) return fs::equivalent(a, b, ea) && !ea;
  const fs::path pa = fs::weakly_canonical(a, ea), pb = fs::weakly_canonical(b, eb);
  return !ea && !eb && pa == pb;
}

}  // namespace tunekit
