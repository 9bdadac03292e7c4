#include "tunekit/history/store.hpp"

#include <cmath>
#include <ctime>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::history {
namespace {

struct Migration {
  int version;
  const char* description;
  const char* sql;  // "@ID@" stands for the backend's auto-numbered primary key column
};

// Each migration runs once, in order, inside the transaction that opens an older database.
// Add new ones at the end; never edit one that has shipped.
const Migration kMigrations[] = {
    {1, "records, their inputs and quantities",
     "CREATE TABLE records ("
     " id @ID@,"
     " machine_id TEXT NOT NULL,"
     " run_utc TEXT NOT NULL,"
     " recorded_utc TEXT NOT NULL,"
     " command TEXT NOT NULL,"
     " tool_version TEXT NOT NULL,"
     " envelope_schema INTEGER NOT NULL,"
     " source TEXT NOT NULL,"
     " envelope_sha256 TEXT NOT NULL,"
     " dedupe_key TEXT UNIQUE,"
     " n_inputs INTEGER NOT NULL,"
     " n_quantities INTEGER NOT NULL,"
     " envelope TEXT NOT NULL);\n"
     "CREATE INDEX records_by_machine ON records (machine_id, run_utc, id);\n"
     "CREATE TABLE record_inputs ("
     " record_id BIGINT NOT NULL REFERENCES records (id) ON DELETE CASCADE,"
     " path TEXT NOT NULL,"
     " sha256 TEXT NOT NULL,"
     " bytes BIGINT);\n"
     "CREATE INDEX record_inputs_by_record ON record_inputs (record_id);\n"
     "CREATE TABLE quantities ("
     " record_id BIGINT NOT NULL REFERENCES records (id) ON DELETE CASCADE,"
     " machine_id TEXT NOT NULL,"
     " run_utc TEXT NOT NULL,"
     " name TEXT NOT NULL,"
     " value DOUBLE PRECISION,"
     " stderr DOUBLE PRECISION,"
     " text_value TEXT,"
     " unit TEXT NOT NULL,"
     " PRIMARY KEY (record_id, name));\n"
     // Covering: a trend reads its series from the index alone, in order.
     "CREATE INDEX quantities_series ON quantities (machine_id, name, run_utc, record_id, value, stderr, text_value, "
     "unit);\n"},
};

std::string with_backend_types(std::string sql, Backend b) {
  const std::string id =
      b == Backend::sqlite ? "INTEGER PRIMARY KEY" : "BIGINT GENERATED ALWAYS AS IDENTITY PRIMARY KEY";
  for (std::size_t p; (p = sql.find("@ID@")) != std::string::npos;) sql.replace(p, 4, id);
  return sql;
}

// Lock key for the migration transaction on PostgreSQL (any constant; "tunekit" in ASCII).
constexpr long long kMigrationLockKey = 0x74756e656b6974;

Value text_or_null(const std::string& s) { return s.empty() ? Value{} : Value{s}; }

RecordSummary summary_from(const Row& r) {
  RecordSummary s;
  s.id = as_int(r[0]);
  s.machine_id = as_text(r[1]);
  s.run_utc = as_text(r[2]);
  s.recorded_utc = as_text(r[3]);
  s.command = as_text(r[4]);
  s.tool_version = as_text(r[5]);
  s.source = as_text(r[6]);
  s.envelope_sha256 = as_text(r[7]);
  s.n_inputs = as_int(r[8]);
  s.n_quantities = as_int(r[9]);
  return s;
}

constexpr const char* kSummaryColumns =
    "id, machine_id, run_utc, recorded_utc, command, tool_version, source, envelope_sha256, n_inputs, n_quantities";

SeriesPoint point_from(const Row& r, std::size_t first) {
  SeriesPoint p;
  p.record_id = as_int(r[first]);
  p.run_utc = as_text(r[first + 1]);
  p.value = as_double(r[first + 2]);
  p.stderr_value = as_double(r[first + 3]);
  p.text = as_text(r[first + 4]);
  p.unit = as_text(r[first + 5]);
  return p;
}

}  // namespace

std::string utc_now() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  std::tm tm{};
  gmtime_r(&ts.tv_sec, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S", &tm);
  return fmt::format("{}.{:03d}Z", buf, ts.tv_nsec / 1000000);
}

void check_machine_id(const std::string& id) {
  if (id.empty()) throw InputError("the machine id is empty (--machine-id NAME, or [machine] id in the profile)");
  if (id.size() > 128) throw InputError("the machine id is longer than 128 characters: " + id.substr(0, 40) + "...");
  for (unsigned char c : id)
    if (c < 0x20 || c == 0x7f) throw InputError("the machine id contains a control character");
  if (id.front() == ' ' || id.back() == ' ')
    throw InputError("the machine id begins or ends with a space: '" + id + "'");
}

Store::Store(const std::string& db) : Store(connect(db)) {}

Store::Store(std::unique_ptr<Connection> connection) : db_(std::move(connection)) { migrate(); }

int Store::schema_version() {
  const auto rows = db_->query("SELECT MAX(version) FROM schema_migrations");
  return rows.empty() || is_null(rows[0][0]) ? 0 : static_cast<int>(as_int(rows[0][0]));
}

void Store::migrate() {
  Transaction tx(*db_);
  // On PostgreSQL, processes opening a new database at once wait here for the first one's
  // migrations instead of racing to create the same tables; SQLite's BEGIN IMMEDIATE already
  // serializes them.
  if (db_->backend() == Backend::postgresql)
    db_->query(fmt::format("SELECT pg_advisory_xact_lock({})", kMigrationLockKey));
  db_->execute(
      "CREATE TABLE IF NOT EXISTS schema_migrations (version INTEGER PRIMARY KEY, description TEXT NOT NULL, "
      "applied_utc TEXT NOT NULL)");
  const int have = schema_version();
  if (have > kHistorySchemaVersion)
    throw InputError(fmt::format("the history database has schema version {}, newer than this tunekit's {}: "
                                 "update tunekit to read it",
                                 have, kHistorySchemaVersion),
                     db_->name());
  if (have == kHistorySchemaVersion) {
    tx.commit();
    return;
  }
  for (const auto& m : kMigrations) {
    if (m.version <= have) continue;
    db_->execute(with_backend_types(m.sql, db_->backend()));
    db_->query("INSERT INTO schema_migrations (version, description, applied_utc) VALUES ($1, $2, $3)",
               {static_cast<std::int64_t>(m.version), std::string(m.description), utc_now()});
  }
  tx.commit();
}

std::optional<std::int64_t> Store::record(const NewRecord& r) {
  check_machine_id(r.machine_id);
  if (r.command.empty()) throw InputError("a history record needs the command that produced it");
  const std::string now = utc_now();
  const std::string run_utc = r.run_utc.empty() ? now : r.run_utc;
  const Value dedupe = r.deduplicate ? Value{r.machine_id + "\n" + r.source + "\n" + r.envelope_sha256} : Value{};

  Transaction tx(*db_);
  const auto ids = db_->query(
      "INSERT INTO records (machine_id, run_utc, recorded_utc, command, tool_version, envelope_schema, source, "
      "envelope_sha256, dedupe_key, n_inputs, n_quantities, envelope) "
      "VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12) ON CONFLICT (dedupe_key) DO NOTHING RETURNING id",
      {r.machine_id, run_utc, now, r.command, r.tool_version, static_cast<std::int64_t>(r.envelope_schema), r.source,
       r.envelope_sha256, dedupe, static_cast<std::int64_t>(r.inputs.size()),
       static_cast<std::int64_t>(r.quantities.size()), r.envelope});
  if (ids.empty()) return std::nullopt;  // already recorded (the transaction rolls back: nothing written)
  const std::int64_t id = as_int(ids[0][0]);
  for (const auto& in : r.inputs)
    db_->query("INSERT INTO record_inputs (record_id, path, sha256, bytes) VALUES ($1, $2, $3, $4)",
               {id, in.path, in.sha256, in.bytes >= 0 ? Value{in.bytes} : Value{}});
  for (const auto& q : r.quantities)
    db_->query(
        "INSERT INTO quantities (record_id, machine_id, run_utc, name, value, stderr, text_value, unit) "
        "VALUES ($1, $2, $3, $4, $5, $6, $7, $8)",
        {id, r.machine_id, run_utc, q.name, q.value, q.stderr_value, text_or_null(q.text), q.unit});
  tx.commit();
  return id;
}

std::vector<MachineSummary> Store::machines() {
  std::vector<MachineSummary> out;
  for (const auto& row : db_->query("SELECT machine_id, COUNT(*), MIN(run_utc), MAX(run_utc) FROM records "
                                    "GROUP BY machine_id ORDER BY machine_id"))
    out.push_back({as_text(row[0]), as_int(row[1]), as_text(row[2]), as_text(row[3])});
  return out;
}

std::vector<RecordSummary> Store::records(const std::string& machine_id) {
  std::vector<RecordSummary> out;
  for (const auto& row :
       db_->query(fmt::format("SELECT {} FROM records WHERE machine_id = $1 ORDER BY run_utc, id", kSummaryColumns),
                  {machine_id}))
    out.push_back(summary_from(row));
  return out;
}

std::optional<StoredRecord> Store::get(std::int64_t id) {
  const auto rows = db_->query(fmt::format("SELECT {}, envelope FROM records WHERE id = $1", kSummaryColumns), {id});
  if (rows.empty()) return std::nullopt;
  StoredRecord rec;
  static_cast<RecordSummary&>(rec) = summary_from(rows[0]);
  rec.envelope = as_text(rows[0][10]);
  for (const auto& r :
       db_->query("SELECT path, sha256, bytes FROM record_inputs WHERE record_id = $1 ORDER BY path", {id}))
    rec.inputs.push_back({as_text(r[0]), as_text(r[1]), is_null(r[2]) ? -1 : as_int(r[2])});
  for (const auto& r : db_->query(
           "SELECT name, value, stderr, text_value, unit FROM quantities WHERE record_id = $1 ORDER BY name", {id}))
    rec.quantities.push_back({as_text(r[0]), as_double(r[1]), as_double(r[2]), as_text(r[3]), as_text(r[4])});
  return rec;
}

std::map<std::string, std::vector<SeriesPoint>> Store::series(const std::string& machine_id) {
  std::map<std::string, std::vector<SeriesPoint>> out;
  for (const auto& r : db_->query("SELECT name, record_id, run_utc, value, stderr, text_value, unit FROM quantities "
                                  "WHERE machine_id = $1 ORDER BY name, run_utc, record_id",
                                  {machine_id}))
    out[as_text(r[0])].push_back(point_from(r, 1));
  return out;
}

std::vector<SeriesPoint> Store::series(const std::string& machine_id, const std::string& quantity) {
  std::vector<SeriesPoint> out;
  for (const auto& r : db_->query("SELECT record_id, run_utc, value, stderr, text_value, unit FROM quantities "
                                  "WHERE machine_id = $1 AND name = $2 ORDER BY run_utc, record_id",
                                  {machine_id, quantity}))
    out.push_back(point_from(r, 0));
  return out;
}

}  // namespace tunekit::history
