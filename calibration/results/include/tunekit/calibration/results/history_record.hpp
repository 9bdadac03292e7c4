#pragma once
// Recording results into the calibration history (tunekit/history/store.hpp). Every command
// that writes a JSON envelope takes --record --machine-id NAME [--db DB]; emit() then stores
// the envelope with its inputs' digests, the tool version and the UTC time, in one transaction.
// A batch summary is stored as one record per analysed dataset, so that each dataset's values
// join the machine's trend. The same conversion imports archived run directories and batch
// summaries (`tunekit history import`).

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/calibration/results/context.hpp"
#include "tunekit/history/store.hpp"

namespace tunekit::calibration {

/// The database used when neither --db nor TUNEKIT_HISTORY_DB names one: a SQLite file in the
/// working directory, next to the runs/ folder calibrate writes.
inline constexpr const char* kDefaultHistoryDb = "history.sqlite";

/// The database named by --db, TUNEKIT_HISTORY_DB or the default.
std::string history_db(const OutputOptions& o);

/// Before a long run: with --record, fills in the machine id from `profile_machine_id` when
/// --machine-id is absent, checks it, and opens the database (creating or migrating it), so a
/// bad id or an unreachable database fails before the machine moves.
void prepare_record(OutputOptions& o, const std::string& profile_machine_id);

/// The records an envelope becomes: one, or one per dataset of a batch summary. `source` is
/// the run directory or file it came from; `run_utc` when the run happened (empty: now).
std::vector<history::NewRecord> records_from_envelope(const nlohmann::json& envelope, const std::string& machine_id,
                                                      const std::string& source, const std::string& run_utc);

/// Stores `envelope` (as emit() wrote it) for o.machine_id in history_db(o). One line on
/// ctx.out (unless --json) says where it went.
void record_result(const nlohmann::json& envelope, const OutputOptions& o, CliContext& ctx);

}  // namespace tunekit::calibration
