#pragma once
// The G-code line protocol of Marlin-like firmware over a byte transport: one line in flight,
// each sent as "N<n> <command>*<checksum>" and acknowledged by "ok".
//
//  - "Resend: N" (or "rs N"): the line is sent again after the "ok" that follows the request
//    (Marlin prints Error:, Resend:, then ok).
//  - "Error:checksum mismatch" / "Error:Line Number is not Last Line Number+1": informational,
//    a Resend follows. Any other "Error:" line, or a "!!" line (Klipper), is a firmware error:
//    MachineError (exit code 3).
//  - "busy:" / "echo:busy:" lines, temperature reports and any other line keep the link alive:
//    the timeout counts silence, not total time.
//  - no line at all for `timeout`: the same numbered line is sent again (a dropped line);
//    after `max_retries` such retries, MachineError.
// Every line sent and every non-data line received is written to the journal. With a SendGuard,
// a line it refuses is never written.

#include <atomic>
#include <chrono>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tunekit/machine/journal.hpp"
#include "tunekit/machine/transport.hpp"

namespace tunekit::machine {

/// The last check of each line before a link writes it to a machine (the protocols' send guard
/// implements it: non-finite numbers, travel, feed rates and temperatures against the profile).
class LineGuard {
 public:
  virtual ~LineGuard() = default;
  /// Why `line` must not be sent, or nullopt when it may be (its effect is then recorded).
  virtual std::optional<std::string> refuse(std::string_view line) = 0;
};

struct LinkOptions {
  std::chrono::milliseconds timeout{10000};  ///< silence allowed while waiting for "ok"
  int max_retries = 3;                       ///< re-sends of a line nobody answered
  bool line_numbers = true;                  ///< N<n> ... *<checksum> framing
};

struct LinkStats {
  long lines_sent = 0;
  long resends = 0;  ///< answered "Resend:"
  long retries = 0;  ///< re-sent after a timeout
  long busy = 0;     ///< "busy:" lines seen
  long data_lines = 0;
};

class GcodeLink {
 public:
  GcodeLink(Transport& t, Journal* journal, LinkOptions options = {});

  /// Called for every received line that is not part of the protocol (echo:, reports, sensor
  /// data). Return true if the line was sensor data (it is then not written to the journal).
  std::function<bool(std::string_view)> on_line;
  /// Called after each batch of received bytes is processed (the run flushes its CSVs here).
  std::function<void()> on_batch;
  /// Checked while waiting; when set, the wait ends with MachineError("interrupted").
  const std::atomic<bool>* abort_flag = nullptr;
  /// When set, every command passes this last check before it is written: a refused line
  /// (non-finite number, position outside the travel, ...) is never sent and ends the run with
  /// MachineError (exit code 3; the runner then sends the safe-state commands).
  LineGuard* guard = nullptr;

  /// Sends one command and waits for its "ok". Returns the informational lines received
  /// meanwhile (e.g. the M115 report). Throws MachineError as described above.
  std::vector<std::string> send(const std::string& command);
  /// Sends `commands` in order keeping up to `window` of them unanswered, for a firmware that
  /// reads ahead and answers every line with one "ok" in order, never asking for a line again:
  /// Klipper's G-code pseudo-terminal queues what it reads and stops reading at 20 pending
  /// commands (klippy/gcode.py, GCodeIO). Each line passes the guard before it is written. A line
  /// is never sent twice here: a silence of the link's timeout, an error or a resend request
  /// ends the run with MachineError. A window of 1 is send() line by line.
  void send_pipelined(const std::vector<std::string>& commands, std::size_t window);
  /// Resets the firmware's line counter (M110 N0) and ours.
  void reset_line_numbers();
  /// Best effort, for aborts: sends commands without line numbers, waits at most `wait` in
  /// total for their answers, never throws.
  void send_best_effort(const std::vector<std::string>& commands, std::chrono::milliseconds wait);

  const LinkStats& stats() const { return stats_; }
  Transport& transport() { return t_; }

 private:
  void write_numbered(long n);
  void write_checked(const std::string& command);
  void check_abort() const;
  Transport& t_;
  Journal* journal_;
  LinkOptions opt_;
  LineReader reader_;
  long line_no_ = 0;
  std::map<long, std::string> history_;
  LinkStats stats_;
};

}  // namespace tunekit::machine
