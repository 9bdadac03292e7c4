// A stop signal at any instant of a run, the last line's answer and what follows it included,
// ends in the safe state with exit code 128 + the signal's number and run.json saying where the
// run was; at the normal end of a run that heated, the heaters are turned off again (unless
// --keep-heaters). Each case runs the real tunekit executable against the simulated printer.
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

// The whole file in a namespace of its own: the test areas are unity builds, and other files
// have helpers of the same names.
namespace test_stop_any_instant {

/// Starts tunekit with `args` (stdout and stderr to `log`), the stop signals at their defaults.
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

int wait_status(pid_t pid) {
  int status = 0;
  const auto until = Clock::now() + std::chrono::seconds(120);
  while (::waitpid(pid, &status, WNOHANG) != pid) {
    if (Clock::now() > until) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      FAIL("tunekit did not end within 120 s");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return status;
}

/// Whether the process has ended (a zombie not yet reaped): a signal sent now is not received.
bool has_ended(pid_t pid) {
  const std::string stat = read_text("/proc/" + std::to_string(pid) + "/stat");
  const auto close = stat.rfind(')');
  return close == std::string::npos || close + 2 >= stat.size() || stat[close + 2] == 'Z';
}

/// Polls `file` until it contains `text` (true) or `pid` has ended (false).
bool wait_for_text(const std::string& file, const std::string& text, pid_t pid) {
  for (;;) {
    if (read_text(file).find(text) != std::string::npos) return true;
    if (has_ended(pid)) return false;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
}

/// The index of the last line of `gcode` (one command per line, "N12 M104 S0*81" read as
/// "M104 S0") that starts with `prefix`; npos when none does.
std::size_t last_line(const std::string& gcode, const std::string& prefix) {
  std::size_t at = std::string::npos, index = 0;
  for (std::size_t b = 0, e; b < gcode.size(); b = e + 1, ++index) {
    e = gcode.find('\n', b);
    if (e == std::string::npos) e = gcode.size();
    std::string line = gcode.substr(b, e - b);
    if (line.size() > 1 && line[0] == 'N' && line.find(' ') != std::string::npos) {
      line = line.substr(line.find(' ') + 1);
      line = line.substr(0, line.find('*'));
    }
    if (line.compare(0, prefix.size(), prefix) == 0) at = index;
  }
  return at;
}

/// The hot end was set last to 0: the last M104/M109 line the simulator received is "M104 S0".
bool hotend_ends_off(const std::string& received) {
  const auto heat_wait = last_line(received, "M109"), heat = last_line(received, "M104 S2");
  const auto off = last_line(received, "M104 S0");
  if (off == std::string::npos) return false;
  return (heat_wait == std::string::npos || off > heat_wait) && (heat == std::string::npos || off > heat);
}

TEST_CASE("a SIGTERM after the run's last line was answered is not swallowed: exit 143, interrupted, heaters off",
          "[machine][signal]") {
  const std::string root = scratch_dir("stop_after_last_line");
  // The signal arrives once the journal holds the run's "end" record: every line was answered,
  // the run is writing its files. A trial where tunekit had already exited is not conclusive.
  bool conclusive = false;
  for (int trial = 0; trial < 5 && !conclusive; ++trial) {
    const std::string dir = root + "/run" + std::to_string(trial);
    const pid_t pid = spawn_tunekit({"run", "liquefier-step", "--machine", "sim", "--run-dir", dir}, dir + ".log");
    fs::create_directories(dir);
    const bool seen = wait_for_text(dir + "/journal.jsonl", "\"what\":\"end\"", pid);
    if (!seen || has_ended(pid)) {
      wait_status(pid);
      continue;
    }
    ::kill(pid, SIGTERM);
    const int status = wait_status(pid);
    conclusive = true;
    INFO(read_text(dir + ".log"));
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 143);
    CHECK(read_text(dir + ".log").find("interrupted by SIGTERM") != std::string::npos);
    const auto run = read_json(dir + "/run.json");
    CHECK(run["status"] == "interrupted");
    CHECK(run.contains("stopped_at"));
    CHECK(hotend_ends_off(read_text(dir + "/sim_received.gcode")));
  }
  REQUIRE(conclusive);
}

TEST_CASE("a signal at spread instants of a run always ends it non-zero with its journal in the safe state",
          "[machine][signal]") {
  const std::string root = scratch_dir("stop_spread");
  for (const auto& [sig, delay_ms] : std::vector<std::pair<int, int>>{{SIGINT, 0}, {SIGTERM, 60}, {SIGHUP, 150}}) {
    const std::string dir = root + "/" + std::to_string(sig) + "_" + std::to_string(delay_ms);
    const pid_t pid = spawn_tunekit({"run", "liquefier-step", "--machine", "sim", "--run-dir", dir}, dir + ".log");
    // From the journal's creation on (the run has begun; before it, nothing was sent and the
    // signal's default action may end the process).
    while (!fs::exists(dir + "/journal.jsonl") && !has_ended(pid))
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
    const bool received = !has_ended(pid);
    ::kill(pid, sig);
    const int status = wait_status(pid);
    INFO(read_text(dir + ".log"));
    if (!received) continue;  // it had finished before the signal
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 128 + sig);
    if (fs::exists(dir + "/sim_received.gcode")) CHECK(hotend_ends_off(read_text(dir + "/sim_received.gcode")));
  }
}

TEST_CASE("a run that heated ends with its heaters off, --keep-heaters keeps them", "[machine]") {
  const std::string dir = scratch_dir("heaters_restored");
  const auto off = tunekit::test::run_cli({"run", "liquefier-step", "--machine", "sim", "--run-dir", dir + "/off"});
  REQUIRE(off.code == 0);
  CHECK(hotend_ends_off(read_text(dir + "/off/sim_received.gcode")));
  const std::string journal = read_text(dir + "/off/journal.jsonl");
  CHECK(journal.find("\"what\":\"heaters off\"") != std::string::npos);
  REQUIRE(journal.rfind(" M104 S0*") != std::string::npos);
  CHECK(journal.rfind(" M104 S0*") > journal.rfind(" M109 "));

  const auto kept = tunekit::test::run_cli(
      {"run", "liquefier-step", "--machine", "sim", "--run-dir", dir + "/kept", "--keep-heaters"});
  REQUIRE(kept.code == 0);
  CHECK_FALSE(hotend_ends_off(read_text(dir + "/kept/sim_received.gcode")));
  CHECK(read_text(dir + "/kept/journal.jsonl").find("\"what\":\"heaters kept\"") != std::string::npos);
}

TEST_CASE("calibrate stopped by SIGINT after its last experiment, during the analysis, exits 130",
          "[machine][signal]") {
  const std::string root = scratch_dir("calibrate_stop_analysis");
  bool conclusive = false;
  for (int trial = 0; trial < 5 && !conclusive; ++trial) {
    const std::string dir = root + "/run" + std::to_string(trial);
    const pid_t pid = spawn_tunekit({"calibrate", "--machine", "sim", "--firmware", "rrf", "--skip-axes", "--out", dir},
                                    dir + ".log");
    // The last experiment's run.json is written when it has ended; the analysis follows.
    bool seen = false;
    while (!seen && !has_ended(pid)) {
      std::error_code ec;
      for (const auto& e : fs::directory_iterator(dir, ec))
        if (e.path().filename() == "liquefier-chirp" && fs::exists(e.path() / "run.json")) seen = true;
      std::this_thread::sleep_for(std::chrono::microseconds(500));
    }
    if (!seen || has_ended(pid)) {
      wait_status(pid);
      continue;
    }
    ::kill(pid, SIGINT);
    const int status = wait_status(pid);
    conclusive = true;
    INFO(read_text(dir + ".log"));
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 130);
    CHECK(read_text(dir + ".log").find("interrupted by SIGINT") != std::string::npos);
    CHECK(hotend_ends_off(read_text(dir + "/liquefier-chirp/sim_received.gcode")));
  }
  REQUIRE(conclusive);
}

}  // namespace test_stop_any_instant
