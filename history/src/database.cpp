#include "tunekit/history/database.hpp"

#include <cmath>
#include <cstdlib>

#include <fmt/format.h>

#include "connections.hpp"
#include "tunekit/core/error.hpp"

namespace tunekit::history {

bool is_postgresql_url(const std::string& db) {
  return db.rfind("postgresql://", 0) == 0 || db.rfind("postgres://", 0) == 0;
}

std::unique_ptr<Connection> connect(const std::string& db) {
  if (db.empty()) throw InputError("no history database given (--db FILE or --db postgresql://...)");
  if (is_postgresql_url(db)) return connect_postgresql(db);
  if (db.find("://") != std::string::npos)
    throw InputError("unknown database URL scheme; use a SQLite file path or postgresql://user@host:port/dbname", db);
  return connect_sqlite(db);
}

bool is_null(const Value& v) { return std::holds_alternative<std::monostate>(v); }

std::int64_t as_int(const Value& v) {
  if (const auto* n = std::get_if<std::int64_t>(&v)) return *n;
  if (const auto* d = std::get_if<double>(&v)) {
    // A whole number stored as a real (another writer, a damaged file): one outside the 64-bit
    // range, or NaN, is not a count or an id this history wrote.
    if (!(std::abs(*d) < 9.2e18))
      throw InputError(fmt::format("the history database holds {} where it keeps a whole number", *d));
    return static_cast<std::int64_t>(*d);
  }
  if (const auto* s = std::get_if<std::string>(&v)) return std::strtoll(s->c_str(), nullptr, 10);
  return 0;
}

double as_double(const Value& v) {
  if (const auto* d = std::get_if<double>(&v)) return *d;
  if (const auto* n = std::get_if<std::int64_t>(&v)) return static_cast<double>(*n);
  if (const auto* s = std::get_if<std::string>(&v)) return std::strtod(s->c_str(), nullptr);
  return std::nan("");
}

std::string as_text(const Value& v) {
  if (const auto* s = std::get_if<std::string>(&v)) return *s;
  if (const auto* n = std::get_if<std::int64_t>(&v)) return std::to_string(*n);
  if (const auto* d = std::get_if<double>(&v)) return std::to_string(*d);
  return {};
}

}  // namespace tunekit::history
