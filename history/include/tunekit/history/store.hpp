#pragma once
// The calibration history: every recorded result of a machine, with its inputs' digests, the
// tool version and the UTC time, and the quantities a trend is drawn from (tau, theta, K, each
// axis's resonance frequency and damping, the shaper chosen, the advance).
//
// Schema (the same on SQLite and PostgreSQL; versioned, migrations run on open):
//   schema_migrations(version, description, applied_utc)
//   records(id, machine_id, run_utc, recorded_utc, command, tool_version, envelope_schema,
//           source, envelope_sha256, dedupe_key UNIQUE, n_inputs, n_quantities, envelope)
//   record_inputs(record_id -> records, path, sha256, bytes)
//   quantities(record_id -> records, machine_id, run_utc, name, value, stderr, text_value, unit)
// A record and its inputs and quantities are written in one transaction: a reader (or a
// process that was killed halfway) never sees a record without its quantities, and
// n_inputs / n_quantities let anyone check that.

#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "tunekit/history/database.hpp"

namespace tunekit::history {

/// One number (or, for the shaper type, one word) of a result. `stderr_value` is the standard
/// error (NaN when the analysis gives none); units in `unit` ("Hz", "s", "1").
struct Quantity {
  std::string name;  ///< e.g. "tau_s", "x.freq_hz", "x.shaper"
  double value = std::numeric_limits<double>::quiet_NaN();
  double stderr_value = std::numeric_limits<double>::quiet_NaN();
  std::string text;  ///< for word-valued quantities (the shaper type); empty otherwise
  std::string unit;
};

struct InputDigest {
  std::string path;
  std::string sha256;
  std::int64_t bytes = -1;
};

struct NewRecord {
  std::string machine_id;
  std::string command;       ///< the tunekit command that produced the result
  std::string tool_version;  ///< tunekit's version that produced it
  int envelope_schema = 0;   ///< the JSON envelope's schema_version
  std::string run_utc;       ///< when the run happened, "YYYY-MM-DDTHH:MM:SS.mmmZ"; empty: now
  std::string source;        ///< run directory or file it was imported from; empty for a live record
  std::string envelope_sha256;
  bool deduplicate = false;  ///< import: skip it when this machine already has this source with these results
  std::vector<InputDigest> inputs;
  std::vector<Quantity> quantities;
  std::string envelope;  ///< the result's JSON text
};

struct RecordSummary {
  std::int64_t id = 0;
  std::string machine_id, run_utc, recorded_utc, command, tool_version, source, envelope_sha256;
  std::int64_t n_inputs = 0, n_quantities = 0;
};

struct StoredRecord : RecordSummary {
  std::vector<InputDigest> inputs;
  std::vector<Quantity> quantities;
  std::string envelope;
};

struct MachineSummary {
  std::string machine_id;
  std::int64_t runs = 0;
  std::string first_run_utc, last_run_utc;
};

struct SeriesPoint {
  std::int64_t record_id = 0;
  std::string run_utc;
  double value = std::numeric_limits<double>::quiet_NaN();
  double stderr_value = std::numeric_limits<double>::quiet_NaN();
  std::string text;
  std::string unit;
};

/// The schema version this build writes and reads.
inline constexpr int kHistorySchemaVersion = 1;

/// The current UTC time as "YYYY-MM-DDTHH:MM:SS.mmmZ" (sorts as text).
std::string utc_now();

/// Machine ids: 1-128 printable characters, no whitespace at either end. InputError otherwise.
void check_machine_id(const std::string& id);

class Store {
 public:
  /// Opens the database (see connect()) and brings its schema up to kHistorySchemaVersion
  /// (migrations run in one transaction under a lock, so processes opening it at once agree).
  /// A database written by a newer tunekit (a higher version) is refused with InputError.
  explicit Store(const std::string& db);
  explicit Store(std::unique_ptr<Connection> connection);

  /// Writes one record in one transaction; returns its id, or nothing when `deduplicate` found
  /// the same source and results already recorded for the machine.
  std::optional<std::int64_t> record(const NewRecord& r);

  std::vector<MachineSummary> machines();
  /// A machine's records, oldest run first.
  std::vector<RecordSummary> records(const std::string& machine_id);
  std::optional<StoredRecord> get(std::int64_t id);
  /// Every quantity series of a machine, each oldest run first (one query).
  std::map<std::string, std::vector<SeriesPoint>> series(const std::string& machine_id);
  /// One quantity's series of a machine, oldest run first.
  std::vector<SeriesPoint> series(const std::string& machine_id, const std::string& quantity);

  int schema_version();
  Connection& connection() { return *db_; }

 private:
  void migrate();
  std::unique_ptr<Connection> db_;
};

}  // namespace tunekit::history
