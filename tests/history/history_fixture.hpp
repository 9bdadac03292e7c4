#pragma once
// The databases the history tests run against: a SQLite file in a scratch directory, and a
// PostgreSQL server of the test's own, started from Debian's postgresql package (initdb and
// pg_ctl in a temporary directory, on a free port of 127.0.0.1, stopped when the test process
// ends). PostgreSQL refuses to run as root, so under root (CI) the server runs as the
// unprivileged user `nobody` (runuser), which owns the temporary directory.

#include <string>
#include <sys/types.h>
#include <vector>

namespace tunekit::test {

struct TestDatabase {
  std::string backend;  ///< "sqlite" or "postgresql"
  std::string url;      ///< what --db takes; empty when skipped
  std::string skip_reason;
};

/// A fresh, empty database of `backend` for the calling test. For PostgreSQL the server is
/// started on first use; when its binaries are absent, url is empty and skip_reason says why.
TestDatabase fresh_database(const std::string& backend, const std::string& name);

/// The test PostgreSQL server's log so far ("" when none was started).
std::string postgres_server_log();

/// Starts `argv` (argv[0] a path) with stdout and stderr appended to `log_path`; returns its pid.
pid_t spawn_process(const std::vector<std::string>& argv, const std::string& log_path);
/// Waits for `pid`; returns its exit status (128 + signal when killed).
int wait_process(pid_t pid);

}  // namespace tunekit::test

/// Runs the rest of the test case once per backend (Catch2 GENERATE), with `db` its fresh
/// database; where PostgreSQL's binaries are absent that run says why and ends.
#define TUNEKIT_FOR_EACH_HISTORY_BACKEND(db, name)                                  \
  const std::string backend_ = GENERATE(as<std::string>{}, "sqlite", "postgresql"); \
  const auto db = ::tunekit::test::fresh_database(backend_, name);                  \
  if (db.url.empty()) {                                                             \
    WARN("skipped on " << backend_ << ": " << db.skip_reason);                      \
    return;                                                                         \
  }                                                                                 \
  INFO("backend " << backend_)
