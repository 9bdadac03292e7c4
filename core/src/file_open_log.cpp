#include "tunekit/core/file_open_log.hpp"

#include <algorithm>
#include <atomic>
#include <filesystem>

namespace tunekit::core {
namespace {

std::mutex live_mutex;                   // guards `live`
std::vector<FileOpenLog*> live;          // the logs alive now
std::atomic<std::size_t> live_count{0};  // live.size(), read without the lock

std::string normalized(const std::string& path) {
  std::error_code ec;
  const auto abs = std::filesystem::absolute(path, ec);
  return (ec ? std::filesystem::path(path) : abs).lexically_normal().string();
}

}  // namespace

FileOpenLog::FileOpenLog() {
  const std::lock_guard lock(live_mutex);
  live.push_back(this);
  live_count.store(live.size());
}

FileOpenLog::~FileOpenLog() {
  const std::lock_guard lock(live_mutex);
  live.erase(std::remove(live.begin(), live.end(), this), live.end());
  live_count.store(live.size());
}

std::vector<std::string> FileOpenLog::paths() const {
  const std::lock_guard lock(mutex_);
  return paths_;
}

std::size_t FileOpenLog::opens(const std::string& path) const {
  const std::string want = normalized(path);
  const std::lock_guard lock(mutex_);
  return static_cast<std::size_t>(
      std::count_if(paths_.begin(), paths_.end(), [&](const std::string& p) { return normalized(p) == want; }));
}

void FileOpenLog::record(const std::string& path) {
  if (live_count.load(std::memory_order_relaxed) == 0) return;
  const std::lock_guard lock(live_mutex);
  for (FileOpenLog* log : live) {
    const std::lock_guard own(log->mutex_);
    log->paths_.push_back(path);
  }
}

}  // namespace tunekit::core
