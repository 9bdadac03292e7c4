// A safe stop whichever way a run is ended from outside: SIGINT, SIGTERM and SIGHUP sent to a
// real `tunekit run` process mid-sweep against the simulated printer each stop the machine
// (M410, heaters off), keep every sample and write run.json as "interrupted"; a simulated
// printer whose answer never comes does not keep tunekit alive after it has given up.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "test_support.hpp"

extern char** environ;

using tunekit::test::read_json;
using tunekit::test::read_text;
using tunekit::test::scratch_dir;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

/// Starts the tunekit executable with `args`, stdout and stderr to `log`, with the default
/// action for the stop signals (a shell may start background jobs with SIGINT ignored).
pid_t spawn_tunekit(const std::vector<std::string>& args, const std::string& log) {
  std::vector<std::string> argv_s{TUNEKIT_EXE};
  argv_s.insert(argv_s.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  sigset_t defaults, none;
  sigemptyset(&defaults);
  for (int s : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&defaults, s);
  sigemptyset(&none);
  posix_spawnattr_setsigdefault(&attr, &defaults);
  posix_spawnattr_setsigmask(&attr, &none);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, argv[0], &fa, &attr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  posix_spawnattr_destroy(&attr);
  REQUIRE(rc == 0);
  return pid;
}

/// The child's wait status, or nullopt when it is still running after `limit` (it is then
/// killed and reaped, so that no test leaves a process behind).
std::optional<int> wait_for(pid_t pid, std::chrono::seconds limit) {
  const auto until = Clock::now() + limit;
  for (;;) {
    int status = 0;
    if (::waitpid(pid, &status, WNOHANG) == pid) return status;
    if (Clock::now() > until) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      return std::nullopt;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

/// Data rows of a CSV file (lines starting with a digit).
std::size_t data_rows(const std::string& path) {
  std::ifstream f(path);
  std::string line;
  std::size_t n = 0;
  while (std::getline(f, line))
    if (!line.empty() && line[0] >= '0' && line[0] <= '9') ++n;
  return n;
}

/// The accelerometer CSV of a run directory ("" until it exists).
std::string accel_csv(const std::string& run_dir) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(run_dir, ec))
    if (e.path().filename().string().rfind("raw_data_", 0) == 0) return e.path().string();
  return {};
}

}  // namespace

TEST_CASE("SIGINT, SIGTERM and SIGHUP mid-sweep each stop the printer, keep every sample and say interrupted",
          "[machine][signal]") {
  const std::string root = scratch_dir("safe_stop_signals");
  for (const auto& [sig, name] :
       std::vector<std::pair<int, std::string>>{{SIGINT, "SIGINT"}, {SIGTERM, "SIGTERM"}, {SIGHUP, "SIGHUP"}}) {
    INFO(name);
    const std::string dir = root + "/" + name;
    const pid_t pid = spawn_tunekit({"run", "axis-sweep", "--run-dir", dir}, root + "/" + name + ".log");
    // Mid-sweep: the accelerometer's samples are arriving.
    const auto until = Clock::now() + std::chrono::seconds(120);
    std::string csv;
    while (Clock::now() < until && (csv.empty() || data_rows(csv) < 200)) {
      csv = accel_csv(dir);
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    REQUIRE(!csv.empty());
    ::kill(pid, sig);
    const auto status = wait_for(pid, std::chrono::seconds(60));
    INFO(read_text(root + "/" + name + ".log"));
    REQUIRE(status);
    REQUIRE(WIFEXITED(*status));               // not killed by the signal
    CHECK(WEXITSTATUS(*status) == 128 + sig);  // as the shell reports a process the signal ended
    CHECK(read_text(root + "/" + name + ".log").find("interrupted by " + name) != std::string::npos);
    const auto run = read_json(dir + "/run.json");
    CHECK(run["status"] == "interrupted");
    CHECK(run["error"].get<std::string>().find(name) != std::string::npos);
    // The simulated printer heard the stop and the heaters turned off, after the sweep's moves.
    const std::string rx = read_text(dir + "/sim_received.gcode");
    const auto stop = rx.find("\nM410\n");
    REQUIRE(stop != std::string::npos);
    CHECK(rx.find("\nM104 S0\n", stop) != std::string::npos);
    CHECK(rx.find("\nM140 S0\n", stop) != std::string::npos);
    // The sweep did not finish: the stop came in the middle of it.
    const auto stats = read_json(dir + "/sim_stats.json");
    const std::size_t sent = stats["accel_samples_sent"];
    CHECK(sent > 0);
    // Every sample the printer sent is in the CSV, and run.json counts them.
    CHECK(data_rows(csv) == sent);
    CHECK(run["samples"]["accel"] == sent);
  }
}

TEST_CASE("a simulated answer that never comes does not keep tunekit alive after it gives up", "[machine][signal]") {
  // The fifth line is answered after 1e9 ms: tunekit times out, retries, gives up (exit 3),
  // and stopping its simulated printer must end that wait.
  const std::string dir = scratch_dir("late_ok_forever");
  const auto t0 = Clock::now();
  const pid_t pid = spawn_tunekit({"run", "axis-sweep", "--run-dir", dir + "/run", "--sim", "fault=late-ok@5:1e9",
                                   "--timeout", "0.3", "--retries", "1"},
                                  dir + "/log");
  const auto status = wait_for(pid, std::chrono::seconds(60));
  INFO(read_text(dir + "/log"));
  REQUIRE(status);  // it ended by itself
  CHECK(Clock::now() - t0 < std::chrono::seconds(60));
  REQUIRE(WIFEXITED(*status));
  CHECK(WEXITSTATUS(*status) == 3);
  CHECK(read_text(dir + "/log").find("no answer") != std::string::npos);
  CHECK(read_json(dir + "/run/run.json")["status"] == "failed");
}

TEST_CASE("a late-ok delay beyond what the clock counts is refused as a simulator option", "[machine]") {
  const auto r = tunekit::test::run_cli(
      {"run", "axis-sweep", "--run-dir", scratch_dir("late_ok_range") + "/run", "--sim", "fault=late-ok@5:1e300"});
  CHECK(r.code == 2);
  CHECK(r.err.find("out of range") != std::string::npos);
}
