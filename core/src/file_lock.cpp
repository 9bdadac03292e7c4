#include "tunekit/core/file_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <thread>

#include <fmt/format.h>

#include "tunekit/core/atomic_file.hpp"
#include "tunekit/core/error.hpp"

namespace tunekit::core {
namespace {

/// Whether `fd` is still the file `path` names (a writer may have renamed a new one over it).
bool still_named(int fd, const std::string& path) {
  struct stat a {
  }, b{};
  return ::fstat(fd, &a) == 0 && ::stat(path.c_str(), &b) == 0 && a.st_dev == b.st_dev && a.st_ino == b.st_ino;
}

bool mkstemp_suffix(std::string_view s) {
  if (s.size() != 6) return false;
  for (char c : s)
    if (!std::isalnum(static_cast<unsigned char>(c))) return false;
  return true;
}

}  // namespace

FileLock::FileLock(const std::string& path, std::chrono::milliseconds wait) : path_(path) {
  const auto until = std::chrono::steady_clock::now() + wait;
  for (;;) {
    fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) {
      if (errno == ENOENT) return;  // nothing to replace yet
      throw InputError(fmt::format("cannot open the file to lock it: {}", std::strerror(errno)), path);
    }
    if (::flock(fd_, LOCK_EX | LOCK_NB) == 0) {
      if (still_named(fd_, path)) return;
      ::close(fd_);  // replaced while we waited: lock the file the name names now
      continue;
    }
    const int err = errno;
    ::close(fd_);
    fd_ = -1;
    if (err != EWOULDBLOCK && err != EINTR)
      throw InputError(fmt::format("cannot lock the file: {}", std::strerror(err)), path);
    if (std::chrono::steady_clock::now() >= until)
      throw InputError(fmt::format("another program has been writing this file for {} s (it holds its lock); "
                                   "nothing was changed: run again when it has finished",
                                   wait.count() / 1000.0),
                       path);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

FileLock::~FileLock() {
  if (fd_ >= 0) ::close(fd_);  // closing the descriptor releases the lock
}

std::vector<std::string> FileLock::remove_stale_temporaries() const {
  std::vector<std::string> out;
  if (fd_ < 0) return out;
  // Beside the file the writers replace: the target of a symbolic link.
  std::error_code canon_ec;
  const auto target = std::filesystem::canonical(path_, canon_ec);
  for (const auto& t : stale_temporaries(canon_ec ? path_ : target.string())) {
    std::error_code ec;
    std::filesystem::remove(t, ec);
    out.push_back(ec ? t + " (could not be removed: " + ec.message() + ")" : t);
  }
  return out;
}

std::vector<std::string> stale_temporaries(const std::string& path) {
  const std::filesystem::path target(path);
  const std::filesystem::path dir = target.parent_path().empty() ? "." : target.parent_path();
  const std::string prefix = temporary_name_prefix(path);
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.size() > prefix.size() && name.compare(0, prefix.size(), prefix) == 0 &&
        mkstemp_suffix(std::string_view(name).substr(prefix.size())) && e.is_regular_file(ec))
      out.push_back(
          (target.parent_path().empty() ? std::filesystem::path(name) : target.parent_path() / name).string());
  }
  return out;
}

}  // namespace tunekit::core
