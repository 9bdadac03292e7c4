// PostgreSQL backend through libpq (Debian's libpq-dev). Parameters are sent as text and
// typed by the server; results are read back by their column type (integers, floating point,
// everything else as text). libpq (and the twenty libraries it needs: Kerberos, LDAP, GnuTLS,
// ...) is opened when a PostgreSQL history is first used, not at every command's start.
#include <libpq-fe.h>

#include <charconv>
#include <cmath>
#include <cstdlib>

#include "connections.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/shared_library.hpp"

namespace tunekit::history {
namespace {

// The libpq functions used here, resolved when the first connection is made.
struct PqApi {
  decltype(&::PQclear) PQclear;
  decltype(&::PQconnectdb) PQconnectdb;
  decltype(&::PQerrorMessage) PQerrorMessage;
  decltype(&::PQexec) PQexec;
  decltype(&::PQexecParams) PQexecParams;
  decltype(&::PQfinish) PQfinish;
  decltype(&::PQftype) PQftype;
  decltype(&::PQgetisnull) PQgetisnull;
  decltype(&::PQgetlength) PQgetlength;
  decltype(&::PQgetvalue) PQgetvalue;
  decltype(&::PQnfields) PQnfields;
  decltype(&::PQntuples) PQntuples;
  decltype(&::PQresultErrorField) PQresultErrorField;
  decltype(&::PQresultErrorMessage) PQresultErrorMessage;
  decltype(&::PQresultStatus) PQresultStatus;
  decltype(&::PQsetNoticeProcessor) PQsetNoticeProcessor;
  decltype(&::PQstatus) PQstatus;
};

const PqApi& pq() {
  static const PqApi api = [] {
    static core::SharedLibrary lib(TUNEKIT_LIBPQ_SONAME, "PostgreSQL history databases", "libpq5");
    PqApi a;
    a.PQclear = lib.function<decltype(&::PQclear)>("PQclear");
    a.PQconnectdb = lib.function<decltype(&::PQconnectdb)>("PQconnectdb");
    a.PQerrorMessage = lib.function<decltype(&::PQerrorMessage)>("PQerrorMessage");
    a.PQexec = lib.function<decltype(&::PQexec)>("PQexec");
    a.PQexecParams = lib.function<decltype(&::PQexecParams)>("PQexecParams");
    a.PQfinish = lib.function<decltype(&::PQfinish)>("PQfinish");
    a.PQftype = lib.function<decltype(&::PQftype)>("PQftype");
    a.PQgetisnull = lib.function<decltype(&::PQgetisnull)>("PQgetisnull");
    a.PQgetlength = lib.function<decltype(&::PQgetlength)>("PQgetlength");
    a.PQgetvalue = lib.function<decltype(&::PQgetvalue)>("PQgetvalue");
    a.PQnfields = lib.function<decltype(&::PQnfields)>("PQnfields");
    a.PQntuples = lib.function<decltype(&::PQntuples)>("PQntuples");
    a.PQresultErrorField = lib.function<decltype(&::PQresultErrorField)>("PQresultErrorField");
    a.PQresultErrorMessage = lib.function<decltype(&::PQresultErrorMessage)>("PQresultErrorMessage");
    a.PQresultStatus = lib.function<decltype(&::PQresultStatus)>("PQresultStatus");
    a.PQsetNoticeProcessor = lib.function<decltype(&::PQsetNoticeProcessor)>("PQsetNoticeProcessor");
    a.PQstatus = lib.function<decltype(&::PQstatus)>("PQstatus");
    return a;
  }();
  return api;
}

// Column type OIDs (PostgreSQL's src/include/catalog/pg_type.dat).
constexpr Oid kPgBool = 16, kPgInt8 = 20, kPgInt2 = 21, kPgInt4 = 23, kPgFloat4 = 700, kPgFloat8 = 701,
              kPgNumeric = 1700;

std::string pg_one_line(std::string s) {
  for (auto& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

// The URL as shown in messages: the password (user:password@) is left out.
std::string pg_display_name(const std::string& url) {
  const auto scheme = url.find("://");
  const auto at = url.find('@', scheme == std::string::npos ? 0 : scheme + 3);
  if (scheme == std::string::npos || at == std::string::npos) return url;
  const auto colon = url.find(':', scheme + 3);
  if (colon == std::string::npos || colon > at) return url;
  return url.substr(0, colon) + url.substr(at);
}

std::string pg_text(double d) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, d);
  return std::string(buf, r.ptr);
}

void pg_quiet_notice(void*, const char*) {}

class PostgresConnection final : public Connection {
 public:
  explicit PostgresConnection(const std::string& url) : name_(pg_display_name(url)) {
    conn_ = pq().PQconnectdb(url.c_str());
    if (conn_ == nullptr) throw MachineError("cannot connect to the history database: out of memory", name_);
    if (pq().PQstatus(conn_) != CONNECTION_OK) {
      const std::string msg = pg_one_line(pq().PQerrorMessage(conn_));
      pq().PQfinish(conn_);
      conn_ = nullptr;
      throw MachineError("cannot connect to the history database: " + msg, name_);
    }
    pq().PQsetNoticeProcessor(conn_, pg_quiet_notice, nullptr);  // "already exists, skipping" and the like
  }
  ~PostgresConnection() override { pq().PQfinish(conn_); }

  Backend backend() const override { return Backend::postgresql; }
  const std::string& name() const override { return name_; }

  void execute(const std::string& sql) override {
    PGresult* r = pq().PQexec(conn_, sql.c_str());
    check(r);
    pq().PQclear(r);
  }

  std::vector<Row> query(const std::string& sql, const std::vector<Value>& params) override {
    std::vector<std::string> text(params.size());
    std::vector<const char*> values(params.size(), nullptr);
    for (std::size_t i = 0; i < params.size(); ++i) {
      const Value& v = params[i];
      if (const auto* n = std::get_if<std::int64_t>(&v)) text[i] = std::to_string(*n);
      else if (const auto* d = std::get_if<double>(&v)) {
        if (!std::isfinite(*d)) continue;  // stored as NULL
        text[i] = pg_text(*d);
      } else if (const auto* s = std::get_if<std::string>(&v)) text[i] = *s;
      else continue;
      values[i] = text[i].c_str();
    }
    PGresult* r = pq().PQexecParams(conn_, sql.c_str(), static_cast<int>(params.size()), nullptr, values.data(),
                                    nullptr, nullptr, 0);
    check(r);
    std::vector<Row> rows;
    const int nr = pq().PQntuples(r), nc = pq().PQnfields(r);
    rows.reserve(static_cast<std::size_t>(nr));
    for (int i = 0; i < nr; ++i) {
      Row row;
      row.reserve(static_cast<std::size_t>(nc));
      for (int c = 0; c < nc; ++c) {
        if (pq().PQgetisnull(r, i, c)) {
          row.emplace_back(std::monostate{});
          continue;
        }
        const char* s = pq().PQgetvalue(r, i, c);
        switch (pq().PQftype(r, c)) {
          case kPgInt2:
          case kPgInt4:
          case kPgInt8: row.emplace_back(static_cast<std::int64_t>(std::strtoll(s, nullptr, 10))); break;
          case kPgFloat4:
          case kPgFloat8:
          case kPgNumeric: row.emplace_back(std::strtod(s, nullptr)); break;
          case kPgBool: row.emplace_back(static_cast<std::int64_t>(s[0] == 't' ? 1 : 0)); break;
          default: row.emplace_back(std::string(s, static_cast<std::size_t>(pq().PQgetlength(r, i, c))));
        }
      }
      rows.push_back(std::move(row));
    }
    pq().PQclear(r);
    return rows;
  }

  void begin() override { execute("BEGIN"); }
  void commit() override { execute("COMMIT"); }
  void rollback() noexcept override {
    PGresult* r = pq().PQexec(conn_, "ROLLBACK");
    pq().PQclear(r);
  }

 private:
  void check(PGresult* r) {
    const auto st = r != nullptr ? pq().PQresultStatus(r) : PGRES_FATAL_ERROR;
    if (st == PGRES_COMMAND_OK || st == PGRES_TUPLES_OK) return;
    const char* state_c = r != nullptr ? pq().PQresultErrorField(r, PG_DIAG_SQLSTATE) : nullptr;
    const std::string state = state_c != nullptr ? state_c : "";
    const std::string msg = pg_one_line(r != nullptr ? pq().PQresultErrorMessage(r) : pq().PQerrorMessage(conn_));
    pq().PQclear(r);
    // SQLSTATE classes (PostgreSQL manual, Appendix A): 42 syntax or undefined object, 22 data,
    // 23 integrity: the database is not what tunekit expects (bad input); the rest (08
    // connection, 53 resources, 57 operator intervention, 40 rollback, ...) is a failure of
    // the server or the link to it.
    const std::string cls = state.substr(0, 2);
    if (pq().PQstatus(conn_) == CONNECTION_OK && (cls == "42" || cls == "22" || cls == "23"))
      throw InputError("history database: " + msg, name_);
    throw MachineError("history database: " + msg, name_);
  }

  std::string name_;
  PGconn* conn_ = nullptr;
};

}  // namespace

std::unique_ptr<Connection> connect_postgresql(const std::string& url) {
  return std::make_unique<PostgresConnection>(url);
}

}  // namespace tunekit::history
