#pragma once
// `tunekit history`'s options, shared by its subcommands: list, show, trend and report
// (cmd_history.cpp) and import (cmd_history_import.cpp).

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "tunekit/cli/context.hpp"

namespace tunekit::cli::history_cmd {

struct HistoryArgs {
  OutputOptions output;
  std::vector<std::string> machines;
  std::vector<std::string> quantities;
  std::int64_t record_id = 0;
  std::size_t baseline_runs = 1;
  double coverage_k = 1.96;
  std::string html_out = "fleet.html";
  std::vector<std::string> paths;
  bool machine_from_path = false;
  bool show_runs = false;
};

/// tunekit history import PATH...: run directories, result files and batch summaries into the
/// history database (cmd_history_import.cpp).
int hist_run_import(const HistoryArgs& a, CliContext& ctx);

}  // namespace tunekit::cli::history_cmd
