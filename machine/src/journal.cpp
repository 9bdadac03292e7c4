#include "tunekit/machine/journal.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::machine {
namespace {

/// Opens `path` for appending without following a symbolic link (a link planted in the run
/// directory must not send the run's data elsewhere).
std::FILE* open_append(const std::string& path) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC | O_NOFOLLOW, 0666);
  if (fd < 0) {
    const int err = errno;
    throw InputError(err == ELOOP ? std::string("cannot create: it is a symbolic link, which is not followed")
                                  : fmt::format("cannot create: {}", std::strerror(err)),
                     path);
  }
  std::FILE* f = ::fdopen(fd, "a");
  if (!f) {
    ::close(fd);
    throw InputError(fmt::format("cannot create: {}", std::strerror(errno)), path);
  }
  return f;
}

}  // namespace

CsvAppender::CsvAppender(const std::string& path, const std::string& header_line) : path_(path) {
  f_ = open_append(path);
  std::fputs(header_line.c_str(), f_);
  std::fputc('\n', f_);
  std::fflush(f_);
}

CsvAppender::~CsvAppender() {
  if (f_) {
    std::fflush(f_);
    std::fclose(f_);
  }
}

void CsvAppender::row(std::string_view line) {
  std::fwrite(line.data(), 1, line.size(), f_);
  std::fputc('\n', f_);
  ++rows_;
}

void CsvAppender::flush() { std::fflush(f_); }
void CsvAppender::sync() {
  std::fflush(f_);
  ::fsync(::fileno(f_));
}

Journal::Journal(std::string dir) : dir_(std::move(dir)), t0_(std::chrono::steady_clock::now()) {
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (ec) throw InputError(fmt::format("cannot create the run directory: {}", ec.message()), dir_);
  f_ = open_append(path("journal.jsonl"));
}

Journal::~Journal() {
  if (f_) {
    std::fflush(f_);
    std::fclose(f_);
  }
}

void Journal::write_record(nlohmann::json rec) {
  rec["seq"] = seq_++;
  rec["t_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  const std::string s = rec.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  std::fwrite(s.data(), 1, s.size(), f_);
  std::fputc('\n', f_);
  std::fflush(f_);
}

void Journal::sent(std::string_view line) { write_record({{"kind", "tx"}, {"line", std::string(line)}}); }
void Journal::received(std::string_view line) { write_record({{"kind", "rx"}, {"line", std::string(line)}}); }

void Journal::event(std::string_view what, nlohmann::json extra) {
  extra["kind"] = "event";
  extra["what"] = std::string(what);
  write_record(std::move(extra));
}

void Journal::error(std::string_view what, nlohmann::json extra) {
  extra["kind"] = "error";
  extra["what"] = std::string(what);
  write_record(std::move(extra));
}

CsvAppender& Journal::csv(const std::string& file_name, const std::string& header) {
  auto& slot = csvs_[file_name];
  if (!slot) slot = std::make_unique<CsvAppender>(path(file_name), header);
  return *slot;
}

void Journal::flush() {
  std::fflush(f_);
  for (auto& [name, c] : csvs_) c->flush();
}

void Journal::sync() {
  std::fflush(f_);
  ::fsync(::fileno(f_));
  for (auto& [name, c] : csvs_) c->sync();
}

}  // namespace tunekit::machine
