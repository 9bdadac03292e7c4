#include "tunekit/protocols/atomic_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include <fmt/format.h>

#include "tunekit/fitting/error.hpp"

namespace tunekit::protocols {
namespace {

[[noreturn]] void fail(const std::string& what, const std::string& path) {
  throw InputError(fmt::format("{}: {}", what, std::strerror(errno)), path);
}

void fsync_directory(const std::filesystem::path& dir) {
  const int fd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

}  // namespace

void write_file_atomic(const std::string& path, std::string_view content,
                       const std::function<void(const std::string&)>& before_rename) {
  const std::filesystem::path target(path);
  const std::filesystem::path dir = target.parent_path();
  std::string tmpl = (dir.empty() ? std::string(".") : dir.string()) + "/." + target.filename().string() + ".tmp.XXXXXX";
  std::vector<char> name(tmpl.begin(), tmpl.end());
  name.push_back('\0');
  const int fd = ::mkstemp(name.data());
  if (fd < 0) fail("cannot create a temporary file beside the target", path);
  const std::string tmp(name.data());
  auto cleanup = [&] { ::unlink(tmp.c_str()); };

  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) ::fchmod(fd, st.st_mode & 07777);

  const char* p = content.data();
  std::size_t left = content.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      ::close(fd);
      cleanup();
      fail("write failed", tmp);
    }
    p += n;
    left -= static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) {
    ::close(fd);
    cleanup();
    fail("fsync failed", tmp);
  }
  ::close(fd);
  if (before_rename) {
    try {
      before_rename(tmp);
    } catch (...) {
      cleanup();
      throw;
    }
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    cleanup();
    fail("cannot replace the file", path);
  }
  fsync_directory(dir);
}

}  // namespace tunekit::protocols
