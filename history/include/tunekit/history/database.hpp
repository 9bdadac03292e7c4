#pragma once
// The two databases the calibration history lives in, behind one small interface:
//   - SQLite (the embedded default): a file, e.g. history.sqlite next to the runs; opened in
//     write-ahead-log mode with a busy timeout, so several processes can record into it at once
//     (writers take turns, readers never block).
//   - PostgreSQL (a print farm's server): a libpq connection URL, postgresql://user@host:5432/db.
// Statements use PostgreSQL's numbered parameters $1, $2, ... on both; values travel as
// int64, double, text or NULL. Every failure is an Error with the database named in it:
// unreachable server or unwritable file -> MachineError (exit 3), bad URL or a database that
// is not tunekit's -> InputError (exit 2).

#include <cstdint>
#include <memory>
#include <string>
#include <variant>
#include <vector>

namespace tunekit::history {

/// One column value: NULL, integer, floating point or text.
using Value = std::variant<std::monostate, std::int64_t, double, std::string>;
using Row = std::vector<Value>;

enum class Backend { sqlite, postgresql };

/// True for "postgresql://..." and "postgres://..." (libpq connection URIs).
bool is_postgresql_url(const std::string& db);

class Connection {
 public:
  virtual ~Connection() = default;
  virtual Backend backend() const = 0;
  /// Runs one or more statements without parameters or results (DDL, pragmas).
  virtual void execute(const std::string& sql) = 0;
  /// Runs one statement with parameters $1..$n and returns its rows.
  virtual std::vector<Row> query(const std::string& sql, const std::vector<Value>& params = {}) = 0;
  /// Starts a write transaction. SQLite takes the write lock at once (BEGIN IMMEDIATE), so two
  /// writers never deadlock upgrading read locks; PostgreSQL's BEGIN.
  virtual void begin() = 0;
  virtual void commit() = 0;
  virtual void rollback() noexcept = 0;
  /// The file path, or the URL without its password: for messages.
  virtual const std::string& name() const = 0;
};

/// Opens `db`: a PostgreSQL URL (see is_postgresql_url) or a SQLite file path (created if absent).
std::unique_ptr<Connection> connect(const std::string& db);

/// Rolls the transaction back unless commit() was called.
class Transaction {
 public:
  explicit Transaction(Connection& c) : c_(c) { c_.begin(); }
  ~Transaction() {
    if (!done_) c_.rollback();
  }
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  void commit() {
    c_.commit();
    done_ = true;
  }

 private:
  Connection& c_;
  bool done_ = false;
};

/// Helpers to read a Value.
bool is_null(const Value& v);
std::int64_t as_int(const Value& v);  ///< integers, or text holding one
double as_double(const Value& v);     ///< NaN for NULL
std::string as_text(const Value& v);  ///< "" for NULL

}  // namespace tunekit::history
