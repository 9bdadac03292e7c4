// SQLite backend (Debian's libsqlite3). Write-ahead logging lets readers work while one writer
// commits; busy_timeout makes concurrent writers wait for their turn instead of failing.
// journal_mode stays WAL (a rollback journal, DELETE, would make every reader wait for each
// writer on a farm's shared file); instead a connection that recorded something checkpoints
// the log into the file when it closes, so history.sqlite alone holds every record.
// synchronous=NORMAL (SQLite's recommendation for WAL, https://sqlite.org/pragma.html#pragma_synchronous):
// a committed record survives a killed process and the file is never corrupted; only a power
// cut or OS crash may roll back the last commits (re-import their run directories). FULL would
// add an fsync to every record: 2.5 ms of work became 50 ms on a busy disk.
// libsqlite3 is opened when a history is first used (core/shared_library.hpp), not at every
// command's start: it is bound at load time in full (about 1,600 symbol lookups).
#include <sqlite3.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>

#include <fmt/format.h>

#include "connections.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/shared_library.hpp"

namespace tunekit::history {
namespace {

// The SQLite functions used here, resolved when the first database is opened.
struct SqliteApi {
  decltype(&::sqlite3_bind_double) bind_double;
  decltype(&::sqlite3_bind_int64) bind_int64;
  decltype(&::sqlite3_bind_null) bind_null;
  decltype(&::sqlite3_bind_parameter_index) bind_parameter_index;
  decltype(&::sqlite3_bind_text) bind_text;
  decltype(&::sqlite3_busy_timeout) busy_timeout;
  decltype(&::sqlite3_clear_bindings) clear_bindings;
  decltype(&::sqlite3_close) close;
  decltype(&::sqlite3_close_v2) close_v2;
  decltype(&::sqlite3_column_bytes) column_bytes;
  decltype(&::sqlite3_column_count) column_count;
  decltype(&::sqlite3_column_double) column_double;
  decltype(&::sqlite3_column_int64) column_int64;
  decltype(&::sqlite3_column_text) column_text;
  decltype(&::sqlite3_column_type) column_type;
  decltype(&::sqlite3_db_config) db_config;
  decltype(&::sqlite3_errmsg) errmsg;
  decltype(&::sqlite3_errstr) errstr;
  decltype(&::sqlite3_exec) exec;
  decltype(&::sqlite3_finalize) finalize;
  decltype(&::sqlite3_free) free;
  decltype(&::sqlite3_open_v2) open_v2;
  decltype(&::sqlite3_prepare_v2) prepare_v2;
  decltype(&::sqlite3_reset) reset;
  decltype(&::sqlite3_sleep) sleep;
  decltype(&::sqlite3_step) step;
  decltype(&::sqlite3_wal_checkpoint_v2) wal_checkpoint_v2;
};

const SqliteApi& sq() {
  static const SqliteApi api = [] {
    static core::SharedLibrary lib(TUNEKIT_SQLITE3_SONAME, "calibration histories", "libsqlite3-0");
    SqliteApi a;
    a.bind_double = lib.function<decltype(&::sqlite3_bind_double)>("sqlite3_bind_double");
    a.bind_int64 = lib.function<decltype(&::sqlite3_bind_int64)>("sqlite3_bind_int64");
    a.bind_null = lib.function<decltype(&::sqlite3_bind_null)>("sqlite3_bind_null");
    a.bind_parameter_index = lib.function<decltype(&::sqlite3_bind_parameter_index)>("sqlite3_bind_parameter_index");
    a.bind_text = lib.function<decltype(&::sqlite3_bind_text)>("sqlite3_bind_text");
    a.busy_timeout = lib.function<decltype(&::sqlite3_busy_timeout)>("sqlite3_busy_timeout");
    a.clear_bindings = lib.function<decltype(&::sqlite3_clear_bindings)>("sqlite3_clear_bindings");
    a.close = lib.function<decltype(&::sqlite3_close)>("sqlite3_close");
    a.close_v2 = lib.function<decltype(&::sqlite3_close_v2)>("sqlite3_close_v2");
    a.column_bytes = lib.function<decltype(&::sqlite3_column_bytes)>("sqlite3_column_bytes");
    a.column_count = lib.function<decltype(&::sqlite3_column_count)>("sqlite3_column_count");
    a.column_double = lib.function<decltype(&::sqlite3_column_double)>("sqlite3_column_double");
    a.column_int64 = lib.function<decltype(&::sqlite3_column_int64)>("sqlite3_column_int64");
    a.column_text = lib.function<decltype(&::sqlite3_column_text)>("sqlite3_column_text");
    a.column_type = lib.function<decltype(&::sqlite3_column_type)>("sqlite3_column_type");
    a.db_config = lib.function<decltype(&::sqlite3_db_config)>("sqlite3_db_config");
    a.errmsg = lib.function<decltype(&::sqlite3_errmsg)>("sqlite3_errmsg");
    a.errstr = lib.function<decltype(&::sqlite3_errstr)>("sqlite3_errstr");
    a.exec = lib.function<decltype(&::sqlite3_exec)>("sqlite3_exec");
    a.finalize = lib.function<decltype(&::sqlite3_finalize)>("sqlite3_finalize");
    a.free = lib.function<decltype(&::sqlite3_free)>("sqlite3_free");
    a.open_v2 = lib.function<decltype(&::sqlite3_open_v2)>("sqlite3_open_v2");
    a.prepare_v2 = lib.function<decltype(&::sqlite3_prepare_v2)>("sqlite3_prepare_v2");
    a.reset = lib.function<decltype(&::sqlite3_reset)>("sqlite3_reset");
    a.sleep = lib.function<decltype(&::sqlite3_sleep)>("sqlite3_sleep");
    a.step = lib.function<decltype(&::sqlite3_step)>("sqlite3_step");
    a.wal_checkpoint_v2 = lib.function<decltype(&::sqlite3_wal_checkpoint_v2)>("sqlite3_wal_checkpoint_v2");
    return a;
  }();
  return api;
}

constexpr int kSqliteBusyTimeoutMs = 60000;
// The SQLite header's application id of a tunekit history ("TKHS"; sqlite.org/fileformat.html).
constexpr std::int64_t kHistoryApplicationId = 0x544B4853;  // many printers recording into one file take turns

class SqliteConnection final : public Connection {
 public:
  explicit SqliteConnection(std::string path) : path_(std::move(path)) {
    const int rc =
        sq().open_v2(path_.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX, nullptr);
    if (rc != SQLITE_OK) {
      const std::string msg = db_ != nullptr ? sq().errmsg(db_) : sq().errstr(rc);
      sq().close(db_);
      db_ = nullptr;
      throw MachineError("cannot open the history database: " + msg, path_);
    }
    try {
      configure();
    } catch (...) {
      close_connection();  // the checks' statements are cached: finalized first, or the file stays open
      throw;
    }
  }
  ~SqliteConnection() override {
    if (committed_) checkpoint_into_file();
    close_connection();
  }

 private:
  /// Finalizes the cached statements and closes the database. sqlite3_close_v2 closes it once
  /// the last statement is finalized even if one were left (sqlite3_close would leave the
  /// connection, and its file descriptor, open with SQLITE_BUSY).
  void close_connection() {
    for (auto& [sql, stmt] : cache_) sq().finalize(stmt);
    cache_.clear();
    sq().close_v2(db_);
    db_ = nullptr;
  }

  void configure() {
    sq().busy_timeout(db_, kSqliteBusyTimeoutMs);
    require_tunekit_database();  // before anything changes the file (journal_mode=WAL does)
    // SQLite's own checkpoint when the last connection closes is off: every read-only
    // command (list, trend) would pay its fsyncs. A connection that committed records
    // checkpoints on close instead (checkpoint_into_file), and the log is also checkpointed
    // when it grows past SQLite's 1000 pages.
    sq().db_config(db_, SQLITE_DBCONFIG_NO_CKPT_ON_CLOSE, 1, nullptr);
    // Switching a new file to WAL needs it to itself for a moment; processes opening the same
    // new file at once may find it busy, without the busy handler being asked: wait and retry.
    for (int waited_ms = 0;; waited_ms += 10) {
      const int rc = sq().exec(db_, "PRAGMA journal_mode=WAL", nullptr, nullptr, nullptr);
      if (rc == SQLITE_OK) break;
      if ((rc & 0xff) != SQLITE_BUSY || waited_ms >= kSqliteBusyTimeoutMs) fail(rc, sq().errmsg(db_));
      sq().sleep(10);
    }
    // Reads through a memory map and a 64 MiB page cache: a fleet's trend reads a million rows.
    execute("PRAGMA synchronous=NORMAL; PRAGMA foreign_keys=ON; PRAGMA mmap_size=1073741824; PRAGMA cache_size=-65536");
  }

 public:
  Backend backend() const override { return Backend::sqlite; }
  const std::string& name() const override { return path_; }

  void execute(const std::string& sql) override {
    char* msg = nullptr;
    const int rc = sq().exec(db_, sql.c_str(), nullptr, nullptr, &msg);
    if (rc != SQLITE_OK) {
      const std::string text = msg != nullptr ? msg : sq().errstr(rc);
      sq().free(msg);
      fail(rc, text);
    }
  }

  std::vector<Row> query(const std::string& sql, const std::vector<Value>& params) override {
    sqlite3_stmt* stmt = prepare(sql);
    sq().reset(stmt);
    sq().clear_bindings(stmt);
    for (std::size_t i = 0; i < params.size(); ++i) {
      const std::string pname = "$" + std::to_string(i + 1);
      const int idx = sq().bind_parameter_index(stmt, pname.c_str());
      if (idx == 0) continue;  // a parameter the statement does not use
      const Value& v = params[i];
      int rc = SQLITE_OK;
      if (std::holds_alternative<std::monostate>(v)) rc = sq().bind_null(stmt, idx);
      else if (const auto* n = std::get_if<std::int64_t>(&v)) rc = sq().bind_int64(stmt, idx, *n);
      else if (const auto* d = std::get_if<double>(&v))
        rc = std::isfinite(*d) ? sq().bind_double(stmt, idx, *d) : sq().bind_null(stmt, idx);
      else {
        const auto& s = std::get<std::string>(v);
        rc = sq().bind_text(stmt, idx, s.data(), static_cast<int>(s.size()), SQLITE_TRANSIENT);
      }
      if (rc != SQLITE_OK) fail(rc, sq().errmsg(db_));
    }
    std::vector<Row> rows;
    for (;;) {
      const int rc = sq().step(stmt);
      if (rc == SQLITE_DONE) break;
      if (rc != SQLITE_ROW) {
        const std::string msg = sq().errmsg(db_);
        sq().reset(stmt);
        fail(rc, msg);
      }
      const int n = sq().column_count(stmt);
      Row row;
      row.reserve(static_cast<std::size_t>(n));
      for (int c = 0; c < n; ++c) {
        switch (sq().column_type(stmt, c)) {
          case SQLITE_NULL: row.emplace_back(std::monostate{}); break;
          case SQLITE_INTEGER: row.emplace_back(static_cast<std::int64_t>(sq().column_int64(stmt, c))); break;
          case SQLITE_FLOAT: row.emplace_back(sq().column_double(stmt, c)); break;
          default: {
            const auto* p = reinterpret_cast<const char*>(sq().column_text(stmt, c));
            row.emplace_back(std::string(p, static_cast<std::size_t>(sq().column_bytes(stmt, c))));
          }
        }
      }
      rows.push_back(std::move(row));
    }
    sq().reset(stmt);
    return rows;
  }

  void begin() override { execute("BEGIN IMMEDIATE"); }
  void commit() override {
    execute("COMMIT");
    committed_ = true;
  }
  void rollback() noexcept override { sq().exec(db_, "ROLLBACK", nullptr, nullptr, nullptr); }

 private:
  sqlite3_stmt* prepare(const std::string& sql) {
    const auto it = cache_.find(sql);
    if (it != cache_.end()) return it->second;
    sqlite3_stmt* stmt = nullptr;
    const int rc = sq().prepare_v2(db_, sql.c_str(), static_cast<int>(sql.size()), &stmt, nullptr);
    if (rc != SQLITE_OK) fail(rc, sq().errmsg(db_));
    cache_.emplace(sql, stmt);
    return stmt;
  }

  // A connection that recorded something copies the log into the database file and empties
  // it when it closes (SQLite, "PRAGMA wal_checkpoint(TRUNCATE)", sqlite.org/pragma.html):
  // history.sqlite alone then holds every record, so copying that one file to another
  // machine or a backup loses none. Readers do not checkpoint (a trend stays a pure read).
  // A reader still inside the log may hold the checkpoint back: after kCheckpointWaitMs it
  // copies what it can (as PASSIVE does) and the records stay safe in the log for the next
  // writer's close to copy.
  void checkpoint_into_file() noexcept {
    constexpr int kCheckpointWaitMs = 2000;  // a close waits at most this for readers to move on
    sq().busy_timeout(db_, kCheckpointWaitMs);
    sq().wal_checkpoint_v2(db_, nullptr, SQLITE_CHECKPOINT_TRUNCATE, nullptr, nullptr);
  }

  // Only tunekit's own databases are opened: the SQLite header's application id is tunekit's, or
  // (a database made before the id was set) its tables are tunekit's, or it has no table yet (a
  // new file, which gets the id). Another program's database is refused before it is changed.
  void require_tunekit_database() {
    const auto id_rows = query("PRAGMA application_id", {});
    const std::int64_t id = id_rows.empty() ? 0 : std::get<std::int64_t>(id_rows[0][0]);
    if (id == kHistoryApplicationId) return;
    std::vector<std::string> tables;
    for (const auto& row : query("SELECT name FROM sqlite_master WHERE type = 'table' ORDER BY name", {}))
      tables.push_back(std::get<std::string>(row[0]));
    const auto has = [&](const char* t) { return std::find(tables.begin(), tables.end(), t) != tables.end(); };
    if (id == 0 && (tables.empty() || (has("schema_migrations") && has("records")))) {
      // Marked as tunekit's (on a file it may not write, e.g. a read-only copy, it stays unmarked).
      sq().exec(db_, fmt::format("PRAGMA application_id = {}", kHistoryApplicationId).c_str(), nullptr, nullptr,
                nullptr);
      return;
    }
    std::string names;
    for (std::size_t i = 0; i < tables.size() && i < 3; ++i) names += (i ? ", " : "") + tables[i];
    throw InputError(
        fmt::format("not a tunekit history database but another program's SQLite file ({}); nothing was changed: "
                    "give --db a new file or a tunekit history",
                    id != 0 ? fmt::format("application id {:#x}", id)
                            : fmt::format("tables {}{}", names, tables.size() > 3 ? ", ..." : "")),
        path_);
  }

  [[noreturn]] void fail(int rc, const std::string& msg) const {
    const int primary = rc & 0xff;
    // A file that is not a database, or one that is not tunekit's, is bad input; everything
    // else (locked past the timeout, disk full, I/O) is a failure of the storage.
    if (primary == SQLITE_NOTADB || primary == SQLITE_ERROR || primary == SQLITE_CONSTRAINT ||
        primary == SQLITE_MISMATCH)
      throw InputError("history database: " + msg, path_);
    throw MachineError("history database: " + msg, path_);
  }

  std::string path_;
  sqlite3* db_ = nullptr;
  bool committed_ = false;  // a write transaction committed: checkpoint on close
  std::map<std::string, sqlite3_stmt*> cache_;
};

}  // namespace

std::unique_ptr<Connection> connect_sqlite(const std::string& path) {
  // SQLite reads ":memory:" and "file:" URIs (mode=memory, vfs=...) as other places than a
  // file: a record stored there would be lost when the command ends.
  if (path == ":memory:" || path.rfind("file:", 0) == 0)
    throw InputError(
        "the history database must be a file path; SQLite's ':memory:' and 'file:' URIs are refused (a record "
        "there would be lost when tunekit ends; for a file of that name write ./" +
            path + ")",
        path);
  return std::make_unique<SqliteConnection>(path);
}

}  // namespace tunekit::history
