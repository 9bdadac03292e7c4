#pragma once
// The run journal: one directory per run holding an append-only record of the run, flushed to
// the operating system as it is written, so a crash, an unplugged cable or Ctrl-C loses
// nothing already received and a partial run can be analyzed as it is.
//
//   journal.jsonl   one JSON object per line: {"seq", "t_s" (wall seconds since the run began),
//                   "kind": "tx" | "rx" | "event" | "error", "line" or "what", ...}.
//                   Every G-code line sent and every protocol line received is there; sensor
//                   data lines go to the CSV files instead (counted in the "end" event).
//   *.csv           sensor samples, one row per sample, appended and flushed with every batch
//                   received (formats in docs/machine.md).
//   run.json        summary written (atomically) when the run ends, complete or not.

#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace tunekit::machine {

/// An append-only CSV file: header once, rows appended, flushed on flush().
class CsvAppender {
 public:
  CsvAppender(const std::string& path, const std::string& header_line);
  ~CsvAppender();
  CsvAppender(const CsvAppender&) = delete;
  CsvAppender& operator=(const CsvAppender&) = delete;
  void row(std::string_view line);  ///< without the newline
  void flush();
  void sync();  ///< flush and fsync
  std::size_t rows() const { return rows_; }
  const std::string& path() const { return path_; }

 private:
  std::FILE* f_ = nullptr;
  std::string path_;
  std::size_t rows_ = 0;
};

class Journal {
 public:
  /// Creates `dir` (and parents) and opens journal.jsonl for appending. InputError if the
  /// directory cannot be created.
  explicit Journal(std::string dir);
  ~Journal();
  Journal(const Journal&) = delete;
  Journal& operator=(const Journal&) = delete;

  void sent(std::string_view line);
  void received(std::string_view line);
  void event(std::string_view what, nlohmann::json extra = nlohmann::json::object());
  void error(std::string_view what, nlohmann::json extra = nlohmann::json::object());

  /// The CSV stream `file_name` in the run directory, created with `header` on first use.
  CsvAppender& csv(const std::string& file_name, const std::string& header);
  bool has_csv(const std::string& file_name) const { return csvs_.count(file_name) != 0; }

  void flush();  ///< flush journal and every CSV to the operating system
  void sync();   ///< flush and fsync everything
  const std::string& dir() const { return dir_; }
  std::string path(const std::string& file_name) const { return dir_ + "/" + file_name; }

 private:
  void write_record(nlohmann::json rec);
  std::string dir_;
  std::FILE* f_ = nullptr;
  std::size_t seq_ = 0;
  std::chrono::steady_clock::time_point t0_;
  std::map<std::string, std::unique_ptr<CsvAppender>> csvs_;
};

}  // namespace tunekit::machine
