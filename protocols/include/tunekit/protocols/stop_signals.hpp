#pragma once
// A safe stop on the signals that end a run from outside: SIGINT (Ctrl-C), SIGTERM (kill,
// timeout(1), systemd's stop) and SIGHUP (the terminal or SSH session went away). While a
// StopSignals is alive, none of them ends the process: each sets a flag that the runner checks
// between lines and the link checks while it waits for an answer, so the run stops the machine
// (the firmware's stop sequence and heaters off), flushes its journal and writes run.json with
// "status": "interrupted" before it returns (runner.hpp). SIGHUP ignored when the guard is
// installed (as under nohup(1)) stays ignored. A command that runs experiments keeps a guard for
// its whole length and checks the flag between its stages (throw_if_stopped), so a signal that
// arrives after the last line was answered, or during the analysis, still ends the command with
// exit code 128 + the signal's number (130 SIGINT, 143 SIGTERM, 129 SIGHUP), never 0.

#include <atomic>
#include <string>

namespace tunekit::protocols {

class StopSignals {
 public:
  /// Installs the handlers (nested guards share them: the outermost installs and restores, and
  /// clears the flag when it installs).
  StopSignals();
  ~StopSignals();
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

  /// Set once one of the signals arrived while a guard was alive.
  static const std::atomic<bool>& flag();
  /// The signal's name ("SIGTERM"), or empty when none arrived.
  static std::string received();
  /// The signal's number (SIGTERM), or 0 when none arrived.
  static int received_number();
  /// Throws InterruptedError (exit code 128 + the signal's number) saying `where` the run was
  /// when one of the signals arrived; nothing when none did.
  static void throw_if_stopped(const std::string& where);
  /// Notes that the signal was reported (an InterruptedError is on its way). When the outermost
  /// guard ends with a signal received and not reported (it arrived after the command's last
  /// check), the guard re-raises it: the process ends by that signal, never with exit code 0.
  static void report();
};

}  // namespace tunekit::protocols
