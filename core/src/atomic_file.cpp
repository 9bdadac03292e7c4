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

// The file a path names after following its symbolic links (each relative link read from
// its own directory): a write goes to the link's target and the link stays. Stops at a
// missing file (a dangling link is written through, creating its target) and after
// kMaxLinkHops hops, as the kernel does (MAXSYMLINKS, 40: ELOOP beyond).
std::string resolve_links(const std::string& path) {
  constexpr int kMaxLinkHops = 40;
  std::filesystem::path p(path);
  for (int hop = 0; hop < kMaxLinkHops; ++hop) {
    struct stat st {};
    if (::lstat(p.c_str(), &st) != 0 || !S_ISLNK(st.st_mode)) return p.string();
    std::error_code ec;
    const std::filesystem::path to = std::filesystem::read_symlink(p, ec);
    if (ec) fail("cannot read the symbolic link", p.string(), ec.value());
    p = to.is_absolute() ? to : p.parent_path() / to;
  }
  fail("cannot follow the symbolic link", path, ELOOP);
}

// `path` after its links, when they may be followed: a link whose target lies in another
// directory than `path`'s is refused unless `links` is Links::follow.
std::string resolve_allowed_links(const std::string& path, Links links) {
  const std::string target = resolve_links(path);
  if (links == Links::follow || target == path) return target;
  std::error_code e1, e2;
  const auto here = std::filesystem::weakly_canonical(std::filesystem::absolute(path, e1).parent_path(), e1);
  const auto there = std::filesystem::weakly_canonical(std::filesystem::absolute(target, e2).parent_path(), e2);
  if (e1 || e2 || here != there)
    throw InputError(fmt::format("is a symbolic link to {}, outside its directory: it is not followed (nothing was "
                                 "written); remove the link or write elsewhere",
                                 target),
                     path);
  return target;
}

// Refuses to replace a file with several hard links: the rename would give only this name
// the new content and leave the others with the old, and writing in place instead could
// leave a half-written file after a crash. Neither is acceptable for a configuration file.
void refuse_hard_links(const std::string& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode) && st.st_nlink > 1)
    throw InputError(fmt::format("cannot replace it: the file has {} hard links, and replacing it would leave the "
                                 "other names with the old content (writing it in place is not crash-safe); "
                                 "nothing was changed: break the link first (e.g. cp FILE FILE.new && mv FILE.new "
                                 "FILE) or edit it by hand",
                                 st.st_nlink),
                     path);
}

// Gives the temporary file `fd` the owner and group of `mode_of` when that exists (a file
// edited as root, e.g. Klipper's printer.cfg, stays its owner's). Root can always do so; an
// unprivileged user can give only a group of its own (chown(2)), and the new file is then
// the writer's, as after any editor that saves by renaming.
void keep_owner(int fd, const std::string& mode_of) {
  struct stat want {
  }, have{};
  if (::stat(mode_of.c_str(), &want) != 0 || ::fstat(fd, &have) != 0) return;
  if (want.st_uid == have.st_uid && want.st_gid == have.st_gid) return;
  if (::fchown(fd, want.st_uid, want.st_gid) != 0 && ::fchown(fd, static_cast<uid_t>(-1), want.st_gid) != 0) {
    // Neither: the new file is the writer's.
  }
}

/// Writes `content` to a new durable temporary file beside `path` (with the permission bits
/// output_mode(mode_of) gives, and the owner and group of `mode_of` when it exists) and
/// returns the temporary file's path.
std::string stage_temporary(const std::string& path, std::string_view content, const std::string& mode_of) {
  const std::filesystem::path target(path);
  const std::filesystem::path dir = target.parent_path();
  std::string tmpl = (dir.empty() ? std::string(".") : dir.string()) + "/" + temporary_name_prefix(path) + "XXXXXX";
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
  keep_owner(fd, mode_of);
  // After fchown, which clears the set-user-ID and set-group-ID bits.
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

std::string shorten_file_name(std::string_view name, std::size_t max_bytes) {
  if (name.size() <= max_bytes) return std::string(name);
  std::size_t n = max_bytes;
  while (n > 0 && (static_cast<unsigned char>(name[n]) & 0xC0) == 0x80) --n;  // not inside a character
  return std::string(name.substr(0, n));
}

std::string temporary_name_prefix(const std::string& path) {
  constexpr std::size_t kAround = 1 + 5 + 6;  // ".", ".tmp.", mkstemp's six characters
  return "." + shorten_file_name(std::filesystem::path(path).filename().string(), kMaxFileNameBytes - kAround) +
         ".tmp.";
}

void require_link_within_directory(const std::string& path) { resolve_allowed_links(path, Links::within_directory); }

namespace {

void write_atomic(const std::string& link_path, std::string_view content, const std::string& mode_of,
                  const std::function<void(const std::string&)>& before_rename, Links links) {
  const std::string path = resolve_allowed_links(link_path, links);
  refuse_hard_links(path);
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

}  // namespace

void write_file_atomic(const std::string& path, std::string_view content,
                       const std::function<void(const std::string&)>& before_rename, Links links) {
  write_atomic(path, content, path, before_rename, links);
}

void write_file_atomic_as(const std::string& path, std::string_view content, const std::string& mode_of,
                          const std::function<void(const std::string&)>& before_rename) {
  write_atomic(path, content, mode_of, before_rename, Links::within_directory);
}

void FileBatch::add(std::string path, std::string content, std::string mode_of, Links links) {
  if (mode_of.empty()) mode_of = path;
  for (auto& f : files_)
    if (f.path == path) {
      f.content = std::move(content);
      f.mode_of = std::move(mode_of);
      f.links = links;
      return;
    }
  files_.push_back({std::move(path), std::move(content), std::move(mode_of), links});
}

void FileBatch::commit(const std::function<void(const std::string&)>& before_rename) {
  // What each target holds now, to put back if a later rename fails.
  std::vector<std::optional<std::string>> previous;
  for (auto& f : files_) {
    f.path = resolve_allowed_links(f.path, f.links);  // a symbolic link's target is written, the link stays
    refuse_hard_links(f.path);
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
        if (previous[k]) write_file_atomic(files_[k].path, *previous[k], {}, Links::follow);
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
