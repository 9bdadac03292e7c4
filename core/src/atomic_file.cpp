#include "tunekit/core/atomic_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/core/file_bytes.hpp"

namespace tunekit::core {
namespace {

[[noreturn]] void fail(const std::string& what, const std::string& path, int err = errno) {
  throw InputError(fmt::format("{}: {}", what, std::strerror(err)), path);
}

void fsync_directory(const std::filesystem::path& dir) {
  const int fd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

// The permission bits a new file gets from open(2) with mode 0666, as for any other tool
// under the user's umask (0644 under umask 022). Read from /proc/self/status (Linux 4.7 and
// later; proc(5)) because umask(2) can only be read by setting it, which would race with
// threads creating files; where /proc is missing, that read-by-setting is the fallback.
mode_t new_file_mode() {
  constexpr mode_t kCreateMode = 0666;  // what open(2) and fopen(3) request for a new file
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("Umask:", 0) == 0) return kCreateMode & ~static_cast<mode_t>(std::stoul(line.substr(6), nullptr, 8));
  const mode_t mask = ::umask(0);
  ::umask(mask);
  return kCreateMode & ~mask;
}

// The permission bits for a file written at `path`: those of `mode_of` when it exists (a
// replaced file keeps its mode, a backup its original's), else those of a new file under
// the umask. (mkstemp(3) creates its file 0600, which must not become the output's mode.)
mode_t output_mode(const std::string& mode_of) {
  struct stat st {};
  if (::stat(mode_of.c_str(), &st) == 0) return st.st_mode & 07777;
  return new_file_mode();
}

/// Writes `content` to a new durable temporary file beside `path` (with the permission bits
/// output_mode(mode_of) gives) and returns the temporary file's path.
std::string stage_temporary(const std::string& path, std::string_view content, const std::string& mode_of) {
  const std::filesystem::path target(path);
  const std::filesystem::path dir = target.parent_path();
  std::string tmpl =
      (dir.empty() ? std::string(".") : dir.string()) + "/." + target.filename().string() + ".tmp.XXXXXX";
  std::vector<char> name(tmpl.begin(), tmpl.end());
  name.push_back('\0');
  const int fd = ::mkstemp(name.data());
  if (fd < 0) fail("cannot create a temporary file beside the target", path);
  const std::string tmp(name.data());
  auto give_up = [&](const char* what) {
    const int err = errno;
    ::close(fd);
    ::unlink(tmp.c_str());
    fail(what, path, err);
  };
  if (::fchmod(fd, output_mode(mode_of)) != 0) give_up("cannot set the file's permissions");
  const char* p = content.data();
  std::size_t left = content.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      give_up("write failed");
    }
    p += n;
    left -= static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) give_up("fsync failed");
  if (::close(fd) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    fail("close failed", path, err);
  }
  return tmp;
}

}  // namespace

void write_file_atomic(const std::string& path, std::string_view content,
                       const std::function<void(const std::string&)>& before_rename) {
  write_file_atomic_as(path, content, path, before_rename);
}

void write_file_atomic_as(const std::string& path, std::string_view content, const std::string& mode_of,
                          const std::function<void(const std::string&)>& before_rename) {
  const std::string tmp = stage_temporary(path, content, mode_of);
  auto cleanup = [&] { ::unlink(tmp.c_str()); };
  if (before_rename) {
    try {
      before_rename(tmp);
    } catch (...) {
      cleanup();
      throw;
    }
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    cleanup();
    fail("cannot replace the file", path, err);
  }
  fsync_directory(std::filesystem::path(path).parent_path());
}

void FileBatch::add(std::string path, std::string content, std::string mode_of) {
  if (mode_of.empty()) mode_of = path;
  for (auto& f : files_)
    if (f.path == path) {
      f.content = std::move(content);
      f.mode_of = std::move(mode_of);
      return;
    }
  files_.push_back({std::move(path), std::move(content), std::move(mode_of)});
}

void FileBatch::commit(const std::function<void(const std::string&)>& before_rename) {
  // What each target holds now, to put back if a later rename fails.
  std::vector<std::optional<std::string>> previous;
  for (const auto& f : files_) {
    std::error_code ec;
    const auto st = std::filesystem::status(f.path, ec);
    if (std::filesystem::exists(st) && !std::filesystem::is_regular_file(st))
      throw InputError("cannot write: it exists and is not a regular file (nothing was changed)", f.path);
    previous.push_back(std::filesystem::exists(st) ? std::optional<std::string>(read_file_bytes(f.path))
                                                   : std::nullopt);
  }
  std::vector<std::string> temps;
  auto remove_temps = [&](std::size_t from) {
    for (std::size_t i = from; i < temps.size(); ++i) ::unlink(temps[i].c_str());
  };
  for (const auto& f : files_) {
    try {
      temps.push_back(stage_temporary(f.path, f.content, f.mode_of));
    } catch (const Error& e) {
      remove_temps(0);
      throw InputError(fmt::format("{} (nothing was changed)", e.message()), e.location());
    }
  }
  for (std::size_t i = 0; i < files_.size(); ++i) {
    std::optional<std::string> why;
    try {
      if (before_rename) before_rename(files_[i].path);
      if (::rename(temps[i].c_str(), files_[i].path.c_str()) != 0)
        why = fmt::format("cannot replace the file: {}", std::strerror(errno));
    } catch (const std::exception& e) {
      why = e.what();
    }
    if (!why) continue;
    // Roll back: the files already replaced get their previous bytes back.
    remove_temps(i);
    std::string rollback_failed;
    for (std::size_t k = 0; k < i; ++k) {
      try {
        if (previous[k]) write_file_atomic(files_[k].path, *previous[k]);
        else if (::unlink(files_[k].path.c_str()) != 0) throw InputError(std::strerror(errno), files_[k].path);
      } catch (const std::exception&) {
        rollback_failed += (rollback_failed.empty() ? "" : ", ") + files_[k].path;
      }
    }
    if (!rollback_failed.empty())
      throw InputError(fmt::format("{}; restoring the files written before it failed too: {}", *why, rollback_failed),
                       files_[i].path);
    throw InputError(fmt::format("{} (nothing was changed)", *why), files_[i].path);
  }
  for (const auto& f : files_) fsync_directory(std::filesystem::path(f.path).parent_path());
}

}  // namespace tunekit::core
