#pragma once
// Helpers shared by `tunekit history`'s subcommands: list, show (history_command.cpp), trend and
// report (history_trend.cpp), import (history_import.cpp). The options and outcomes are in
// tunekit/calibration/commands/history_command.hpp.

#include <cmath>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/calibration/commands/history_command.hpp"
#include "tunekit/calibration/results/history_record.hpp"
#include "tunekit/history/store.hpp"

namespace tunekit::calibration::history_cmd {

/// The database named by --db, $TUNEKIT_HISTORY_DB or the default (history_record.hpp).
inline std::string hist_db_of(const HistoryOptions& o) {
  OutputOptions out;
  out.db = o.db;
  return history_db(out);
}

/// A number, or null when it is not finite (JSON has no NaN).
inline nlohmann::json hist_number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

/// Machines to look at: those given (their ids checked), or every machine in the database.
inline std::vector<std::string> hist_machines(history::Store& store, const std::vector<std::string>& given) {
  if (!given.empty()) {
    for (const auto& m : given) history::check_machine_id(m);
    return given;
  }
  std::vector<std::string> out;
  for (const auto& m : store.machines()) out.push_back(m.machine_id);
  return out;
}

}  // namespace tunekit::calibration::history_cmd
